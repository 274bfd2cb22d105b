//! Evaluation: every [`Method`] on the same simulated scans, scored against ground truth.
//!
//! [`quick_report`] is the lead's tuning loop; [`cli`] (`pfe eval`, `cargo xtask eval`)
//! reproduces the paper's comparison and writes `docs/EVALUATION.md` and plots.

use crate::method::Method;
use crate::score::{quantile, score_sim, Score};
use crate::sim::{Scenario, SceneKind, SimScan};
use std::fmt::Write as _;
use std::time::{Duration, Instant};

/// Seed of the scan `index` of a run seeded with `seed` (a splitmix-style spread, so runs
/// with nearby seeds do not share scans).
pub fn scan_seed(seed: u64, index: usize) -> u64 {
    let mut z = seed
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add((index as u64).wrapping_mul(0xBF58_476D_1CE4_E5B9));
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The `n` scenarios of a run.
pub fn scenarios(kind: SceneKind, n: usize, sigma_r: f32, seed: u64) -> Vec<Scenario> {
    (0..n)
        .map(|i| Scenario::new(kind, scan_seed(seed, i)).with_sigma(sigma_r))
        .collect()
}

/// One method's result over a set of scans.
#[derive(Clone, Debug)]
pub struct MethodResult {
    /// Method name.
    pub name: String,
    /// Summed score.
    pub score: Score,
    /// Mean wall time of `extract` per scan.
    pub time_per_scan: Duration,
}

/// Runs every method on every scan (each scan simulated once) and scores them.
pub fn run_methods(methods: &mut [&mut dyn Method], scans: &[SimScan]) -> Vec<MethodResult> {
    methods
        .iter_mut()
        .map(|m| {
            let mut score = Score::default();
            let mut time = Duration::ZERO;
            for sim in scans {
                let t0 = Instant::now();
                let ex = m.extract(&sim.geometry, &sim.ranges_mm);
                time += t0.elapsed();
                score.add(&score_sim(&ex, sim));
            }
            MethodResult {
                name: m.name().to_string(),
                score,
                time_per_scan: time / u32::try_from(scans.len().max(1)).unwrap_or(u32::MAX),
            }
        })
        .collect()
}

fn fmt_q(values: &[f64], q: f64, scale: f64, digits: usize) -> String {
    let v = quantile(values, q);
    if v.is_finite() {
        format!("{:.*}", digits, v * scale)
    } else {
        "-".to_string()
    }
}

/// A plain-text table of `results` (one row per method).
pub fn text_table(results: &[MethodResult]) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{:<14} {:>8} {:>9} {:>9} {:>7} {:>7} {:>7} {:>8} {:>8} {:>8} {:>8}",
        "method",
        "us/scan",
        "FalseMark",
        "FalseIden",
        "missed",
        "spur.",
        "matched",
        "rho mm",
        "alpha mr",
        "ctr mm",
        "R mm"
    );
    for r in results {
        let s = &r.score;
        let rho: Vec<f64> = s.line_errors.iter().map(|e| e.rho).collect();
        let alpha: Vec<f64> = s.line_errors.iter().map(|e| e.alpha).collect();
        let ctr: Vec<f64> = s.circle_errors.iter().map(|e| e.center).collect();
        let rad: Vec<f64> = s.circle_errors.iter().map(|e| e.radius).collect();
        let _ = writeln!(
            out,
            "{:<14} {:>8.1} {:>9.4} {:>9.4} {:>7.3} {:>7.3} {:>7} {:>8} {:>8} {:>8} {:>8}",
            r.name,
            r.time_per_scan.as_secs_f64() * 1e6,
            s.false_mark_ratio(),
            s.false_iden_ratio(),
            s.missed_ratio(),
            s.spurious_ratio(),
            s.matched,
            fmt_q(&rho, 0.5, 1.0, 2),
            fmt_q(&alpha, 0.5, 1e3, 2),
            fmt_q(&ctr, 0.5, 1.0, 1),
            fmt_q(&rad, 0.5, 1.0, 1),
        );
    }
    out
}

/// Median CRB of the matched features of `s` (ρ mm, α mrad, centre mm, R mm).
pub fn crb_medians(s: &Score) -> [f64; 4] {
    let c = |v: Vec<f64>| quantile(&v, 0.5);
    [
        c(s.line_errors.iter().map(|e| e.crb_rho).collect()),
        c(s.line_errors.iter().map(|e| e.crb_alpha * 1e3).collect()),
        c(s.circle_errors.iter().map(|e| e.crb_center).collect()),
        c(s.circle_errors.iter().map(|e| e.crb_radius).collect()),
    ]
}

/// Simulates `n_scans` scans of `kind` with range noise `sigma_r` (mm) from `seed`, runs every
/// method on them and returns a table: mean time per scan, FalseMarkRatio, FalseIdenRatio,
/// missed and spurious (fractions of truth features), matched count, and median errors of the
/// correctly typed matched lines (|Δρ| mm, |Δα| mrad) and circles (centre mm, |ΔR| mm), plus
/// the median Cramér–Rao bound of the first method's matched features.
///
/// ```
/// use host_tests::eval::quick_report;
/// use host_tests::method::{Method, Pfe};
/// use host_tests::sim::SceneKind;
/// let mut pfe = Pfe::paper();
/// let report = quick_report(&mut [&mut pfe as &mut dyn Method], SceneKind::Office, 2, 5.0, 1);
/// assert!(report.contains("pfe-paper"));
/// ```
pub fn quick_report(
    methods: &mut [&mut dyn Method],
    kind: SceneKind,
    n_scans: usize,
    sigma_r: f32,
    seed: u64,
) -> String {
    let scans: Vec<SimScan> = scenarios(kind, n_scans, sigma_r, seed)
        .iter()
        .map(Scenario::simulate)
        .collect();
    let truth: usize = scans.iter().map(|s| s.truth.len()).sum();
    let lines: usize = scans
        .iter()
        .flat_map(|s| s.truth.iter())
        .filter(|f| f.kind.is_line())
        .count();
    let results = run_methods(methods, &scans);
    let mut out = format!(
        "scenes: {} x {}, sigma_r = {} mm, seed = {}; truth features: {} ({:.1}/scan; {} lines, {} circles)\n",
        n_scans,
        kind.name(),
        sigma_r,
        seed,
        truth,
        truth as f64 / n_scans.max(1) as f64,
        lines,
        truth - lines
    );
    out.push_str(&text_table(&results));
    if let Some(r) = results.first() {
        let [a, b, c, d] = crb_medians(&r.score);
        let _ = writeln!(
            out,
            "{:<14} {:>76} {:>8.2} {:>8.2} {:>8.1} {:>8.1}",
            "CRB (median)", "", a, b, c, d
        );
    }
    out
}

/// Entry point of `pfe eval`; parses its own arguments.
pub fn cli(args: &[String]) -> anyhow::Result<()> {
    anyhow::bail!("not implemented yet (args: {args:?})")
}
