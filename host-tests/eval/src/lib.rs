//! Evaluation: every [`Method`] on the same simulated scans, scored against ground truth.
//!
//! [`quick_report`] is the lead's tuning loop; [`evaluate`] reproduces the paper's comparison, which
//! `pfe eval` (pfe-cli) writes to `docs/EVALUATION.md` with its plots.

#![forbid(unsafe_code)]

pub mod bench;
pub mod methods;
pub mod plicp;
pub mod posebench;
pub mod realdata;
pub mod report;
pub mod scene;
pub mod score;
pub mod svg;

use crate::methods::baselines::{Acf, SplitMerge};
use crate::methods::{Method, Pfe};
use crate::scene::{Scenario, SceneKind, SimScan};
use crate::score::{quantile, score_sim, Score};
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

/// Runs every method on every scan (each scan simulated once) and scores them; the time is
/// one pass (see [`run_methods_timed`] for a steadier figure).
pub fn run_methods(methods: &mut [&mut dyn Method], scans: &[SimScan]) -> Vec<MethodResult> {
    run_methods_timed(methods, scans, 1)
}

/// Like [`run_methods`], scoring the first pass and timing `passes` passes over all scans
/// (`Instant` around each `extract`): the time per scan is that of the fastest pass, which
/// discounts other load on the machine.
pub fn run_methods_timed(
    methods: &mut [&mut dyn Method],
    scans: &[SimScan],
    passes: usize,
) -> Vec<MethodResult> {
    let n = u32::try_from(scans.len().max(1)).unwrap_or(u32::MAX);
    methods
        .iter_mut()
        .map(|m| {
            let mut score = Score::default();
            let mut best = Duration::MAX;
            for pass in 0..passes.max(1) {
                let mut time = Duration::ZERO;
                for sim in scans {
                    let t0 = Instant::now();
                    let ex = m.extract_in(&sim.geometry, &sim.ranges_mm, &sim.context());
                    time += t0.elapsed();
                    if pass == 0 {
                        score.add(&score_sim(&ex, sim));
                    }
                }
                best = best.min(time);
            }
            MethodResult {
                name: m.name().to_string(),
                score,
                time_per_scan: best / n,
            }
        })
        .collect()
}

/// The four methods of the comparison: PFE `paper`, PFE `default`, ACF, split-and-merge
/// (each in its own default configuration, made for σ_r = 5 mm).
pub fn default_methods() -> Vec<Box<dyn Method>> {
    methods_for(5.0)
}

/// The four methods told the scanner's range noise `sigma_r` (what a user configures for
/// their scanner). The paper's thresholds do not depend on it (only its covariances do).
pub fn methods_for(sigma_r: f32) -> Vec<Box<dyn Method>> {
    vec![
        Box::new(Pfe::new(
            "pfe-paper",
            pfe_core::Config::paper().with_sigma_r(sigma_r),
        )),
        Box::new(Pfe::new(
            "pfe-default",
            pfe_core::Config::default().with_sigma_r(sigma_r),
        )),
        Box::new(Acf::new().with_sigma_r(sigma_r)),
        Box::new(SplitMerge::new().with_sigma_r(sigma_r)),
    ]
}

/// What the evaluation runs.
#[derive(Clone, Debug, PartialEq)]
pub struct EvalOptions {
    /// Scene kind (default mixed).
    pub kind: SceneKind,
    /// Scans per noise level (default 100).
    pub scans: usize,
    /// Seed (default 1).
    pub seed: u64,
    /// σ_r of the main comparison, mm (default 5).
    pub sigma: f32,
    /// σ_r of the sweep, mm (default 1, 2, 5, 10).
    pub sweep: Vec<f32>,
    /// Timed passes over the scans (default 5; the fastest counts).
    pub passes: usize,
    /// Where EVALUATION.md and the plots go (`None`: print only).
    pub out: Option<std::path::PathBuf>,
    /// The command line to name in the report's header.
    pub command: String,
    /// Replace the report's files in `out` even when no `pfe` command wrote them.
    pub force: bool,
}

impl Default for EvalOptions {
    fn default() -> Self {
        Self {
            kind: SceneKind::Mixed,
            scans: 100,
            seed: 1,
            sigma: 5.0,
            sweep: vec![1.0, 2.0, 5.0, 10.0],
            passes: 5,
            out: Some(std::path::PathBuf::from("docs")),
            command: "cargo xtask eval".to_string(),
            force: false,
        }
    }
}

/// Results at one noise level.
#[derive(Clone, Debug)]
pub struct Level {
    /// σ_r, mm.
    pub sigma: f32,
    /// Truth features (all scans).
    pub truth_features: usize,
    /// Of which circles.
    pub truth_circles: usize,
    /// Cramér–Rao bounds of every truth feature (`true` for lines).
    pub truth_crb: Vec<(bool, crate::scene::Crb)>,
    /// One per method, in order.
    pub results: Vec<MethodResult>,
}

/// Everything the report shows.
#[derive(Clone, Debug)]
pub struct Evaluation {
    /// The options used.
    pub options: EvalOptions,
    /// The main comparison (σ = `options.sigma`).
    pub main: Level,
    /// Per scene kind at the main σ (half as many scans each).
    pub by_kind: Vec<(SceneKind, Level)>,
    /// The noise sweep.
    pub sweep: Vec<Level>,
    /// Robustness conditions at the main σ ([`conditions`]).
    pub robustness: Vec<(String, Level)>,
}

/// Simulates and scores one level.
pub fn run_level(
    methods: &mut [Box<dyn Method>],
    kind: SceneKind,
    scans: usize,
    sigma: f32,
    seed: u64,
    passes: usize,
) -> Level {
    run_scenarios(methods, &scenarios(kind, scans, sigma, seed), passes)
}

/// Simulates `scenarios` and scores every method on them (`sigma` of the level: the first
/// scenario's).
pub fn run_scenarios(
    methods: &mut [Box<dyn Method>],
    scenarios: &[Scenario],
    passes: usize,
) -> Level {
    let sims: Vec<SimScan> = scenarios.iter().map(Scenario::simulate).collect();
    let truth_features = sims.iter().map(|s| s.truth.len()).sum();
    let truth_crb: Vec<(bool, crate::scene::Crb)> = sims
        .iter()
        .flat_map(|s| s.truth.iter())
        .map(|f| (f.kind.is_line(), f.crb))
        .collect();
    let truth_circles = truth_crb.iter().filter(|(l, _)| !l).count();
    let mut refs: Vec<&mut dyn Method> = methods
        .iter_mut()
        .map(|m| &mut **m as &mut dyn Method)
        .collect();
    Level {
        sigma: scenarios.first().map_or(0.0, |s| s.sigma_r),
        truth_features,
        truth_circles,
        truth_crb,
        results: run_methods_timed(&mut refs, &sims, passes),
    }
}

/// A named change to the scenarios (a robustness condition).
pub type Condition = (&'static str, fn(&mut Scenario));

/// Forward speed of the moving conditions, mm/s: 8 mm in one 13.33 ms mirror turn.
pub const MOVING_V: f32 = 600.0;
/// Turn rate of the moving conditions, rad/s: 6 mrad in one mirror turn.
pub const MOVING_OMEGA: f32 = 0.45;

/// The robustness conditions at the main σ: (name, change to the scenario). Each runs on the
/// main comparison's scenes (the long-corridor condition on long corridors with the same seeds).
pub fn conditions() -> Vec<Condition> {
    vec![
        ("systematic bias ±15 mm (uncorrected)", |s| s.bias = true),
        ("mixed pixels at depth jumps", |s| s.mixed_pixels = true),
        ("0.25° resolution (721 beams)", |s| {
            s.resolution = crate::scene::Resolution::Quarter
        }),
        ("1° resolution (181 beams)", |s| {
            s.resolution = crate::scene::Resolution::One
        }),
        (
            "interleaved 0.5°, 8 mm / 6 mrad between sweeps, no odometry",
            |s| *s = s.with_motion(MOVING_V, MOVING_OMEGA),
        ),
        (
            "interleaved 0.5°, 8 mm / 6 mrad between sweeps, odometry given",
            |s| {
                *s = s.with_motion(MOVING_V, MOVING_OMEGA);
                s.odometry_given = true;
            },
        ),
        // What interleaving costs beyond the motion: the same motion with no turn (the sweeps
        // stay evenly spaced in bearing), and with every beam in one mirror turn (no LMS2xx
        // does this; de-skewed, the beams stay evenly spaced).
        (
            "interleaved 0.5°, 8 mm / no turn between sweeps, odometry given",
            |s| {
                *s = s.with_motion(MOVING_V, 0.0);
                s.odometry_given = true;
            },
        ),
        (
            "control: 8 mm / 6 mrad a mirror turn, one sweep, odometry given",
            |s| {
                *s = s.with_motion(MOVING_V, MOVING_OMEGA);
                s.one_sweep = true;
                s.odometry_given = true;
            },
        ),
        ("interleaved 0.25° (4 sweeps), moving, no odometry", |s| {
            *s = s.with_motion(MOVING_V, MOVING_OMEGA);
            s.resolution = crate::scene::Resolution::Quarter;
        }),
        ("cm mode, long corridors to 80 m", |s| {
            s.kind = SceneKind::LongCorridor;
            s.range_mode = crate::scene::RangeMode::Cm;
        }),
        ("incidence-dependent noise", |s| s.incidence_noise = true),
    ]
}

/// Runs the whole evaluation with `methods`.
pub fn evaluate(methods: &mut [Box<dyn Method>], options: &EvalOptions) -> Evaluation {
    let main = run_level(
        methods,
        options.kind,
        options.scans,
        options.sigma,
        options.seed,
        options.passes,
    );
    let by_kind = SceneKind::CONCRETE
        .iter()
        .map(|&k| {
            let n = (options.scans / 2).max(1);
            (k, run_level(methods, k, n, options.sigma, options.seed, 1))
        })
        .collect();
    let sweep = options
        .sweep
        .iter()
        .map(|&s| {
            // Each level with methods told that level's noise, when running the standard set.
            let mut tuned = methods_for(s);
            let same = tuned.len() == methods.len()
                && tuned
                    .iter()
                    .zip(methods.iter())
                    .all(|(a, b)| a.name() == b.name());
            if same {
                run_level(&mut tuned, options.kind, options.scans, s, options.seed, 1)
            } else {
                run_level(methods, options.kind, options.scans, s, options.seed, 1)
            }
        })
        .collect();
    let robustness = conditions()
        .into_iter()
        .map(|(name, change)| {
            let mut sc = scenarios(options.kind, options.scans, options.sigma, options.seed);
            sc.iter_mut().for_each(change);
            (name.to_string(), run_scenarios(methods, &sc, 1))
        })
        .collect();
    Evaluation {
        options: options.clone(),
        main,
        by_kind,
        sweep,
        robustness,
    }
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
/// method on them and returns a table: mean time per scan (fastest of 3 passes), FalseMarkRatio, FalseIdenRatio,
/// missed and spurious (fractions of truth features), matched count, and median errors of the
/// correctly typed matched lines (|Δρ| mm, |Δα| mrad) and circles (centre mm, |ΔR| mm), plus
/// the median Cramér–Rao bound of the first method's matched features.
///
/// ```
/// use pfe_eval::quick_report;
/// use pfe_eval::methods::{Method, Pfe};
/// use pfe_eval::scene::SceneKind;
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
    let results = run_methods_timed(methods, &scans, 3);
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
