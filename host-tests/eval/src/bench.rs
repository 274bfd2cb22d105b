//! `pfe bench`: host speed of every method on the same scans, in one run, single thread.
//!
//! Data sets: simulated scans ([`crate::scene`] mixed scenes, SICK LMS200 geometry, σ_r = 5 mm)
//! and, when a directory of them is given (`pfe bench --carmen DIR`), real CARMEN logs read by
//! [`pfe_formats::carmen::Reader`] (its documented angle convention: n odd → −90° +
//! i·180°/(n−1); n even → −90° + i·180°/n; readings at or beyond the scanner's maximum —
//! 50 m, or 81.83 m for 80 m-mode logs — are no return). Every method is told the data's
//! range noise, as a user would configure it and as the `pfe` CLI does: 5 mm for the simulated
//! scans, [`Format::sigma_r`] (10 mm: cm-quantised LMS data) for the CARMEN logs.
//!
//! For each data set and method, one warm-up pass, then `--reps` rounds in which every method
//! makes one timed pass over all scans, interleaved (`std::time::Instant`, one thread); each
//! pass gives ns per beam (every beam counts, valid or not) and scans per second; the table
//! reports the median pass. The ratio column is `time(method) / time(pfe-default)`: how many
//! times faster pfe-default is. The last row ([`FITS_ONLY`]) is the floor under every method:
//! fitting pfe-default's features again, with no segmentation at all.
//!
//! Run by the `pfe` CLI (pfe-cli):
//!
//! ```text
//! pfe bench --json
//! ```

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use pfe_core::{Feature, Point, ScanGeometry, Stage, StageObserver};
use serde::Serialize;

use crate::methods::baselines::{beam_points, refit, DEFAULT_SIGMA_R};
use crate::methods::{Extraction, Method, Pfe, ScanContext};
use crate::methods_for;
use crate::scene::{Scenario, SceneKind};
use pfe_formats::Format;

/// Host budgets (issue: "PFE default ≥ 3× faster than split-and-merge and ≥ 10× faster than
/// ACF per scan, in the same run, on the same scans"): (method, least `× pfe-default`).
pub const BUDGETS: [(&str, f64); 2] = [("split-merge", 3.0), ("acf", 10.0)];

/// One line per data set and budget: `met` or `NOT met`, with the measured ratio and, for
/// scale, the most any segmentation could reach (the method's time over [`FITS_ONLY`]'s).
/// The second value is true when every budget holds.
pub fn budget_lines(report: &BenchReport) -> (Vec<String>, bool) {
    let mut lines = Vec::new();
    let mut all = true;
    for d in &report.datasets {
        let row = |name: &str| d.methods.iter().find(|m| m.method == name);
        let fits = row(FITS_ONLY).map(|f| f.ns_per_point);
        if d.dataset == INTERLEAVED {
            let one = format!("{REFERENCE} --sweeps 1");
            if let (Some(two), Some(one)) = (row(REFERENCE), row(&one)) {
                let ratio = two.ns_per_point / one.ns_per_point;
                let met = ratio <= INTERLEAVED_BUDGET;
                all &= met;
                lines.push(format!(
                    "budget ({INTERLEAVED}): {REFERENCE} with 2 sweeps declared ≤ {INTERLEAVED_BUDGET}× the time with 1: {} ({ratio:.2}×)",
                    if met { "met" } else { "NOT met" },
                ));
            }
            continue;
        }
        for (method, least) in BUDGETS {
            // Without a pfe-default row the ratio is NaN: nothing to judge.
            let Some(m) = row(method).filter(|m| m.slowdown_vs_pfe_default.is_finite()) else {
                continue;
            };
            let ratio = m.slowdown_vs_pfe_default;
            let met = ratio >= least;
            all &= met;
            let ceiling = fits.map_or(String::new(), |f| {
                format!("; no segmentation at all: {:.1}×", m.ns_per_point / f)
            });
            lines.push(format!(
                "budget ({}): {REFERENCE} ≥ {least}× faster than {method}: {} ({ratio:.2}×{ceiling})",
                d.dataset,
                if met { "met" } else { "NOT met" },
            ));
        }
    }
    (lines, all)
}

/// One scan to extract.
#[derive(Clone, Debug)]
pub struct BenchScan {
    /// Beam geometry.
    pub geometry: ScanGeometry,
    /// Ranges, mm (NaN = no return).
    pub ranges_mm: Vec<f32>,
    /// Interleaved sweeps the scan is declared to be made of (0 or 1: one), as `pfe extract
    /// --sweeps` declares them.
    pub sweeps: usize,
}

impl BenchScan {
    /// What the methods are told about the scan: its declared sweeps.
    pub fn context(&self) -> ScanContext {
        ScanContext {
            sweeps: self.sweeps,
            ..ScanContext::default()
        }
    }
}

/// pfe-default told a number of interleaved sweeps whatever the scan declares, as `pfe extract
/// --sweeps N` does: the interleaved data set times the same scans with 2 and with 1.
pub struct Declared {
    name: String,
    sweeps: usize,
    inner: Pfe,
}

impl Declared {
    /// pfe-default with σ_r `sigma_r`, told `sweeps` sweeps; named `pfe-default` for 2 (what
    /// `--sweeps auto` declares for 0.5° LMS scans), `pfe-default --sweeps N` otherwise.
    pub fn new(sigma_r: f32, sweeps: usize) -> Self {
        let name = match sweeps {
            2 => REFERENCE.to_string(),
            n => format!("{REFERENCE} --sweeps {n}"),
        };
        let config = pfe_core::Config::default().with_sigma_r(sigma_r);
        Self {
            inner: Pfe::new(&name, config),
            name,
            sweeps,
        }
    }
}

impl Method for Declared {
    fn name(&self) -> &str {
        &self.name
    }

    fn extract(&mut self, geometry: &ScanGeometry, ranges_mm: &[f32]) -> Extraction {
        self.extract_in(geometry, ranges_mm, &ScanContext::default())
    }

    fn extract_in(
        &mut self,
        geometry: &ScanGeometry,
        ranges_mm: &[f32],
        context: &ScanContext,
    ) -> Extraction {
        let context = ScanContext {
            sweeps: self.sweeps,
            ..*context
        };
        self.inner.extract_in(geometry, ranges_mm, &context)
    }
}

/// The interleaved data set's budget: `--sweeps 2` at most this many times `--sweeps 1`'s time
/// on the same scans.
pub const INTERLEAVED_BUDGET: f64 = 1.25;

/// Name of the interleaved data set.
pub const INTERLEAVED: &str = "interleaved";

/// Timing of one method on one data set.
#[derive(Clone, Debug, Serialize)]
pub struct MethodTiming {
    /// Method name.
    pub method: String,
    /// Median ns per beam.
    pub ns_per_point: f64,
    /// Fastest and slowest pass, ns per beam.
    pub ns_per_point_min: f64,
    /// See `ns_per_point_min`.
    pub ns_per_point_max: f64,
    /// Median scans per second.
    pub scans_per_s: f64,
    /// Mean features per scan.
    pub features_per_scan: f64,
    /// time(this method) / time(pfe-default) (median passes); > 1 means pfe-default is faster.
    pub slowdown_vs_pfe_default: f64,
}

/// Timings on one data set.
#[derive(Clone, Debug, Serialize)]
pub struct DatasetTiming {
    /// Data set name.
    pub dataset: String,
    /// Scans in one pass.
    pub scans: usize,
    /// Beams in one pass.
    pub points: usize,
    /// One entry per method.
    pub methods: Vec<MethodTiming>,
    /// pfe-default by stage ([`stage_times`]), when it is timed.
    pub stages: Vec<StageTiming>,
}

/// Median ns a beam of one stage of pfe-default ([`pfe_core::Stage`]).
#[derive(Clone, Debug, Serialize)]
pub struct StageTiming {
    /// Stage name ([`pfe_core::Stage::name`]).
    pub stage: String,
    /// Median ns per beam over the passes.
    pub ns_per_point: f64,
}

/// Sums the time between one stage's end and the next into per-stage totals.
struct StageClock {
    last: Instant,
    total: [std::time::Duration; Stage::ALL.len()],
}

impl StageObserver for StageClock {
    fn ended(&mut self, stage: Stage) {
        let now = Instant::now();
        if let Some(t) = self.total.get_mut(stage.index()) {
            *t += now - self.last;
        }
        self.last = now;
    }
}

/// pfe-default (σ_r `sigma_r`) by stage on `scans` (with their declared sweeps), through
/// [`pfe_core::Extractor::extract_observed`]: `reps` passes, the median ns a beam of each
/// stage. The clock is read 8 times a scan (about 0.5 ns a beam on the host), so the stages
/// add up to a little more than the method's own row.
pub fn stage_times(scans: &[BenchScan], sigma_r: f32, reps: usize) -> Vec<StageTiming> {
    let config = pfe_core::Config::default().with_sigma_r(sigma_r);
    let mut ex = Box::new(pfe_core::Extractor::<
        { crate::methods::MAX_BEAMS },
        { crate::methods::MAX_FEATURES },
    >::new());
    let points: usize = scans.iter().map(|s| s.ranges_mm.len()).sum();
    let mut passes: Vec<Vec<f64>> = vec![Vec::new(); Stage::ALL.len()];
    for pass in 0..=reps.max(1) {
        let mut clock = StageClock {
            last: Instant::now(),
            total: Default::default(),
        };
        for s in scans {
            let sweeps = u8::try_from(s.sweeps).unwrap_or(u8::MAX);
            let scan = pfe_core::Scan::from_mm(s.geometry, &s.ranges_mm).with_sweeps(sweeps);
            clock.last = Instant::now();
            let _ = std::hint::black_box(ex.extract_observed(&scan, &config, &mut clock));
        }
        // The first pass warms up.
        if pass > 0 {
            for (times, t) in passes.iter_mut().zip(clock.total) {
                times.push(t.as_secs_f64() * 1e9 / points.max(1) as f64);
            }
        }
    }
    Stage::ALL
        .iter()
        .zip(passes.iter_mut())
        .map(|(stage, times)| {
            times.sort_by(f64::total_cmp);
            StageTiming {
                stage: stage.name().to_string(),
                ns_per_point: times.get(times.len() / 2).copied().unwrap_or(f64::NAN),
            }
        })
        .collect()
}

/// The whole report (`--json`).
#[derive(Clone, Debug, Serialize)]
pub struct BenchReport {
    /// "release" or "debug" (debug numbers are meaningless).
    pub profile: String,
    /// Timed passes per data set and method.
    pub reps: usize,
    /// Threads used.
    pub threads: usize,
    /// Per data set.
    pub datasets: Vec<DatasetTiming>,
}

/// The method every other is compared with (the ratio column, the budgets).
pub const REFERENCE: &str = "pfe-default";

/// Name of the row that times the fits alone ([`crate::methods::baselines::refit`] of pfe-default's
/// features): what any method that outputs those features pays, whatever its segmentation.
pub const FITS_ONLY: &str = "fits-only";

/// Times `methods` on `scans`: one warm-up pass each, then `reps` rounds; in each round every
/// method makes one timed pass (interleaved, so that load changes on a shared machine hit all
/// methods alike). Median pass per method. When pfe-default is among them, a last row
/// ([`FITS_ONLY`]) times fitting its features again, without any segmentation, in the same
/// rounds.
pub fn time_methods(
    name: &str,
    scans: &[BenchScan],
    methods: &mut [Box<dyn Method>],
    reps: usize,
) -> DatasetTiming {
    let points: usize = scans.iter().map(|s| s.ranges_mm.len()).sum();
    let reps = reps.max(1);
    let mut fit_inputs: Vec<(Vec<Point>, Vec<Feature>)> = Vec::new();
    let mut features: Vec<(String, usize)> = Vec::new();
    for m in methods.iter_mut() {
        let mut count = 0;
        for s in scans {
            let out = m.extract_in(&s.geometry, &s.ranges_mm, &s.context());
            count += out.features.len();
            if m.name() == REFERENCE {
                fit_inputs.push((beam_points(&s.geometry, &s.ranges_mm), out.features));
            }
        }
        features.push((m.name().to_string(), count));
    }
    if !fit_inputs.is_empty() {
        let count = fit_inputs.iter().map(|(_, f)| f.len()).sum();
        features.push((FITS_ONLY.to_string(), count));
    }
    let mut passes: Vec<Vec<f64>> = vec![Vec::with_capacity(reps); features.len()];
    for _ in 0..reps {
        for (m, times) in methods.iter_mut().zip(passes.iter_mut()) {
            let t = Instant::now();
            for s in scans {
                let context = s.context();
                std::hint::black_box(m.extract_in(
                    &s.geometry,
                    std::hint::black_box(&s.ranges_mm),
                    &context,
                ));
            }
            times.push(t.elapsed().as_secs_f64());
        }
        // The fits-only row, when there is one, follows the methods'.
        if let Some(times) = passes.get_mut(methods.len()) {
            let t = Instant::now();
            for (pts, found) in &fit_inputs {
                // σ_r only scales the covariances.
                std::hint::black_box(refit(pts, std::hint::black_box(found), DEFAULT_SIGMA_R));
            }
            times.push(t.elapsed().as_secs_f64());
        }
    }
    let per_point = |secs: f64| secs * 1e9 / points.max(1) as f64;
    let mut rows: Vec<MethodTiming> = features
        .into_iter()
        .zip(passes.iter_mut())
        .map(|((method, features), times)| {
            times.sort_by(f64::total_cmp);
            let med = times.get(times.len() / 2).copied().unwrap_or(f64::NAN);
            MethodTiming {
                method,
                ns_per_point: per_point(med),
                ns_per_point_min: per_point(times.first().copied().unwrap_or(f64::NAN)),
                ns_per_point_max: per_point(times.last().copied().unwrap_or(f64::NAN)),
                scans_per_s: scans.len() as f64 / med,
                features_per_scan: features as f64 / scans.len().max(1) as f64,
                slowdown_vs_pfe_default: f64::NAN,
            }
        })
        .collect();
    let reference = rows
        .iter()
        .find(|r| r.method == REFERENCE)
        .map(|r| r.ns_per_point);
    for r in &mut rows {
        r.slowdown_vs_pfe_default = reference.map_or(f64::NAN, |p| r.ns_per_point / p);
    }
    DatasetTiming {
        dataset: name.to_string(),
        scans: scans.len(),
        points,
        methods: rows,
        stages: Vec::new(),
    }
}

/// `n` simulated LMS200 scans (361 beams, 8 m, σ_r = 5 mm): [`crate::scene`]'s mixed scenes
/// (office, clutter, pillars, corridor) with seeds `seed, seed + 1, …`.
pub fn simulated_scans(n: usize, seed: u64) -> Vec<BenchScan> {
    (0..n as u64)
        .map(|k| {
            let s = Scenario::new(SceneKind::Mixed, seed.wrapping_add(k)).simulate();
            BenchScan {
                geometry: s.geometry,
                ranges_mm: s.ranges_mm,
                sweeps: 0,
            }
        })
        .collect()
}

/// `n` simulated LMS200 scans at 0.5° (two interleaved sweeps) taken while moving without
/// odometry (the evaluation's interleaved condition: [`crate::MOVING_V`],
/// [`crate::MOVING_OMEGA`]), mixed scenes with seeds `seed, seed + 1, …`; declared 2 sweeps.
pub fn interleaved_scans(n: usize, seed: u64) -> Vec<BenchScan> {
    (0..n as u64)
        .map(|k| {
            let s = Scenario::new(SceneKind::Mixed, seed.wrapping_add(k))
                .with_motion(crate::MOVING_V, crate::MOVING_OMEGA)
                .simulate();
            BenchScan {
                geometry: s.geometry,
                ranges_mm: s.ranges_mm,
                sweeps: s.sweeps,
            }
        })
        .collect()
}

/// Scans of every CARMEN log in `dir` (`*.log`, `*.clf`, gzipped or not, sorted by name), at
/// most `per_log` from each (0 = all).
pub fn carmen_scans(dir: &Path, per_log: usize) -> anyhow::Result<Vec<BenchScan>> {
    let mut logs: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("reading {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .is_some_and(|n| pfe_formats::carmen::is_log_name(&n.to_string_lossy()))
        })
        .collect();
    logs.sort();
    let mut out = Vec::new();
    for log in logs {
        let input =
            pfe_formats::open(&log, |r| r).with_context(|| format!("opening {}", log.display()))?;
        let reader = pfe_formats::carmen::Reader::new(input);
        let limit = if per_log == 0 { usize::MAX } else { per_log };
        for rec in reader.take(limit) {
            let rec = rec.map_err(|e| anyhow::anyhow!("{}: {e}", log.display()))?;
            out.push(BenchScan {
                geometry: rec.geometry,
                ranges_mm: rec.ranges_mm,
                sweeps: 0,
            });
        }
    }
    Ok(out)
}

/// What `pfe bench` times.
#[derive(Clone, Debug)]
pub struct BenchOptions {
    /// Number of simulated scans.
    pub sim_scans: usize,
    /// Seed of the simulated scans.
    pub seed: u64,
    /// Directory of CARMEN logs (*.log, *.clf, gzipped or not), or none: simulated scans
    /// only. A directory with no scan in it is an error ([`NoScans`]).
    pub carmen: Option<PathBuf>,
    /// At most this many scans from each CARMEN log (0 = all).
    pub per_log: usize,
    /// Timed passes per data set and method; the median is reported.
    pub reps: usize,
    /// Time only the methods of this name (and pfe-default's fits, when it is one), on the
    /// data sets named in `datasets`.
    pub only: Option<String>,
    /// Data sets to time (empty: simulated, interleaved, and carmen when `carmen` is given).
    pub datasets: Vec<String>,
}

/// The CARMEN directory given to [`run`] holds no scan (no log, or only empty ones).
#[derive(Debug)]
pub struct NoScans(pub PathBuf);

impl std::fmt::Display for NoScans {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "no scan found in {} (no *.log or *.clf CARMEN log with a scan in it)",
            self.0.display()
        )
    }
}

impl std::error::Error for NoScans {}

/// Runs the benchmark and returns the report.
pub fn run(args: &BenchOptions) -> anyhow::Result<BenchReport> {
    // The logs are read first: a directory without scans fails before any timing.
    let real = match &args.carmen {
        Some(dir) => {
            let real = carmen_scans(dir, args.per_log)?;
            if real.is_empty() {
                return Err(NoScans(dir.clone()).into());
            }
            Some(real)
        }
        None => None,
    };
    let wanted = |name: &str| args.datasets.is_empty() || args.datasets.iter().any(|d| d == name);
    let only = |mut methods: Vec<Box<dyn Method>>| {
        if let Some(only) = &args.only {
            methods.retain(|m| m.name() == only);
        }
        methods
    };
    let mut datasets = Vec::new();
    if wanted("simulated") {
        let sim = simulated_scans(args.sim_scans.max(1), args.seed);
        let mut methods = only(methods_for(DEFAULT_SIGMA_R));
        let mut d = time_methods("simulated", &sim, &mut methods, args.reps);
        if staged(&d) {
            d.stages = stage_times(&sim, DEFAULT_SIGMA_R, args.reps);
        }
        datasets.push(d);
    }
    if wanted(INTERLEAVED) {
        let scans = interleaved_scans(args.sim_scans.max(1), args.seed);
        let mut methods: Vec<Box<dyn Method>> = vec![
            Box::new(Declared::new(DEFAULT_SIGMA_R, 2)),
            Box::new(Declared::new(DEFAULT_SIGMA_R, 1)),
        ];
        if let Some(name) = &args.only {
            methods.retain(|m| m.name() == name);
        }
        let mut d = time_methods(INTERLEAVED, &scans, &mut methods, args.reps);
        if staged(&d) {
            d.stages = stage_times(&scans, DEFAULT_SIGMA_R, args.reps);
        }
        datasets.push(d);
    }
    if let Some(real) = real.filter(|_| wanted("carmen")) {
        let mut methods = only(methods_for(Format::Carmen.sigma_r()));
        let mut d = time_methods("carmen", &real, &mut methods, args.reps);
        if staged(&d) {
            d.stages = stage_times(&real, Format::Carmen.sigma_r(), args.reps);
        }
        datasets.push(d);
    }
    Ok(BenchReport {
        profile: if cfg!(debug_assertions) {
            "debug"
        } else {
            "release"
        }
        .to_string(),
        reps: args.reps.max(1),
        threads: 1,
        datasets,
    })
}

/// Whether a data set's timings include pfe-default's (then its stages are timed too).
fn staged(d: &DatasetTiming) -> bool {
    d.methods.iter().any(|m| m.method == REFERENCE)
}

/// The stages as one line: `load 1.2 · scatter 3.4 · … (sum 20.1)` ns a beam.
pub fn stage_line(stages: &[StageTiming]) -> String {
    let sum: f64 = stages.iter().map(|s| s.ns_per_point).sum();
    let parts: Vec<String> = stages
        .iter()
        .map(|s| format!("{} {:.1}", s.stage, s.ns_per_point))
        .collect();
    format!("{} (sum {sum:.1})", parts.join(" · "))
}

/// The report as a text table.
pub fn table(report: &BenchReport) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "profile {}, {} thread, median of {} passes",
        report.profile, report.threads, report.reps
    );
    for d in &report.datasets {
        let _ = writeln!(s, "\n{}: {} scans, {} beams", d.dataset, d.scans, d.points);
        let _ = writeln!(
            s,
            "{:<12} {:>10} {:>10} {:>10} {:>12} {:>10} {:>14}",
            "method", "ns/beam", "min", "max", "scans/s", "feat/scan", "× pfe-default"
        );
        for m in &d.methods {
            let _ = writeln!(
                s,
                "{:<12} {:>10.1} {:>10.1} {:>10.1} {:>12.0} {:>10.2} {:>14.2}",
                m.method,
                m.ns_per_point,
                m.ns_per_point_min,
                m.ns_per_point_max,
                m.scans_per_s,
                m.features_per_scan,
                m.slowdown_vs_pfe_default
            );
        }
        if !d.stages.is_empty() {
            let _ = writeln!(
                s,
                "{REFERENCE} by stage, ns/beam: {}",
                stage_line(&d.stages)
            );
        }
    }
    if report.profile == "debug" {
        s.push_str("\nwarning: debug build; run `cargo run --release --bin pfe -- bench` for real numbers\n");
    }
    s
}

/// Beam counts of the scaling sweep.
pub const SCALING_BEAMS: [usize; 8] = [91, 181, 271, 361, 451, 541, 631, 721];

/// Mean µs per scan of every method at each of [`SCALING_BEAMS`]: `n` simulated mixed scans at
/// 0.25° (721 beams), each cut to its first `beams` beams (a narrower field of view), timed as
/// [`time_methods`] does.
pub fn scaling(n: usize, seed: u64, reps: usize) -> Vec<(usize, Vec<(String, f64)>)> {
    let full: Vec<BenchScan> = (0..n as u64)
        .map(|k| {
            let mut sc = Scenario::new(SceneKind::Mixed, seed.wrapping_add(k));
            sc.resolution = crate::scene::Resolution::Quarter;
            let s = sc.simulate();
            BenchScan {
                geometry: s.geometry,
                ranges_mm: s.ranges_mm,
                sweeps: 0,
            }
        })
        .collect();
    let mut methods = methods_for(DEFAULT_SIGMA_R);
    SCALING_BEAMS
        .iter()
        .map(|&beams| {
            let cut: Vec<BenchScan> = full
                .iter()
                .map(|s| BenchScan {
                    geometry: s.geometry,
                    ranges_mm: s.ranges_mm.iter().take(beams).copied().collect(),
                    sweeps: 0,
                })
                .collect();
            let d = time_methods("scaling", &cut, &mut methods, reps);
            let per_scan = d
                .methods
                .iter()
                .map(|m| (m.method.clone(), m.ns_per_point * beams as f64 / 1e3))
                .collect();
            (beams, per_scan)
        })
        .collect()
}

/// Writes the `host` section of `md` (the report and the scaling sweep) and
/// `perf-scaling.svg` next to it; neither replaces a file no `pfe` command wrote unless `force`.
pub fn write_markdown(
    md: &Path,
    report: &BenchReport,
    budgets: &[String],
    sweep: &[(usize, Vec<(String, f64)>)],
    force: bool,
) -> anyhow::Result<()> {
    use std::fmt::Write as _;
    let mut body = format!(
        "Reproduce: `cargo run --release -p pfe-cli -- bench --carmen ../shared/data/carmen --md docs/PERFORMANCE.md`\n\n\
         Host CPU: {}, one thread, release build, `std::time::Instant`; median of {} interleaved \
         passes per method (the machine is shared: compare methods within one run). \
         **× pfe-default** = time(method) / time(pfe-default): above 1, pfe-default is faster. \
         Every method is told the data's range noise (5 mm simulated, 10 mm for the \
         cm-quantised CARMEN logs), as `pfe extract` is. **{FITS_ONLY}**: pfe-default's \
         features fitted again with the fits every method here shares (pfe-core's line and \
         circle fits and their covariances), without any segmentation: a floor under every \
         method's time, so time(method) / time({FITS_ONLY}) is the most any segmentation \
         could be faster than that method.\n",
        pfe_formats::docs::cpu_model(),
        report.reps
    );
    for d in &report.datasets {
        let _ = write!(
            body,
            "\n### {} ({} scans, {} beams)\n\n| method | ns/beam | scans/s | features/scan | × pfe-default |\n|---|---:|---:|---:|---:|\n",
            d.dataset, d.scans, d.points
        );
        for m in &d.methods {
            let _ = writeln!(
                body,
                "| {} | {:.1} | {:.0} | {:.2} | {:.2} |",
                m.method,
                m.ns_per_point,
                m.scans_per_s,
                m.features_per_scan,
                m.slowdown_vs_pfe_default
            );
        }
        if !d.stages.is_empty() {
            let _ = write!(
                body,
                "\n{REFERENCE} by stage ([`Extractor::extract_observed`](../pfe-core/src/extractor.rs), ns/beam): {}\n",
                stage_line(&d.stages)
            );
        }
    }
    let _ = write!(body, "\n### Budgets\n\n");
    for b in budgets {
        let _ = writeln!(body, "- {b}");
    }
    let names: Vec<String> = sweep
        .first()
        .map(|(_, v)| v.iter().map(|(n, _)| n.clone()).collect())
        .unwrap_or_default();
    let _ = write!(
        body,
        "\n### Time per scan against the number of beams\n\n\
         Simulated mixed scans at 0.25° cut to their first n beams (µs per scan):\n\n| beams | {} |\n|---:|{}\n",
        names.join(" | "),
        "---:|".repeat(names.len())
    );
    for (beams, row) in sweep {
        let cells: Vec<String> = row.iter().map(|(_, t)| format!("{t:.1}")).collect();
        let _ = writeln!(body, "| {beams} | {} |", cells.join(" | "));
    }
    body.push_str("\n![time per scan vs beams](perf-scaling.svg)\n");
    let xs: Vec<f64> = sweep.iter().map(|(b, _)| *b as f64).collect();
    let curves: Vec<(String, Vec<f64>)> = names
        .iter()
        .enumerate()
        .map(|(i, n)| {
            let ys = sweep
                .iter()
                .map(|(_, row)| row.get(i).map_or(f64::NAN, |(_, t)| *t))
                .collect();
            (n.clone(), ys)
        })
        .collect();
    let svg = crate::svg::line_chart(
        "Time per scan (µs, host) against beams per scan",
        "beams per scan",
        &xs,
        &curves,
    );
    let plot = pfe_formats::outfile::beside(md, "perf-scaling.svg");
    pfe_formats::outfile::check(std::iter::once(md).chain(plot.as_deref()), force)?;
    if let Some(plot) = &plot {
        pfe_formats::outfile::write(plot, &svg, force)?;
    }
    pfe_formats::docs::write_section(md, "host", "`pfe bench`", &body, force)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A row of a data set where pfe-default takes 10 ns a beam.
    fn row(method: &str, ns_per_point: f64) -> MethodTiming {
        MethodTiming {
            method: method.to_string(),
            ns_per_point,
            ns_per_point_min: ns_per_point,
            ns_per_point_max: ns_per_point,
            scans_per_s: 1.0,
            features_per_scan: 1.0,
            slowdown_vs_pfe_default: ns_per_point / 10.0,
        }
    }

    fn report(split_merge: f64, acf: f64) -> BenchReport {
        BenchReport {
            profile: "release".into(),
            reps: 1,
            threads: 1,
            datasets: vec![DatasetTiming {
                dataset: "d".into(),
                scans: 1,
                points: 1,
                methods: vec![
                    row("pfe-default", 10.0),
                    row("split-merge", split_merge),
                    row("acf", acf),
                    row(FITS_ONLY, 4.0),
                ],
                stages: Vec::new(),
            }],
        }
    }

    /// Each budget is judged on its own ratio, at its bound included.
    #[test]
    fn budgets_are_judged_on_the_ratios() {
        let (lines, met) = budget_lines(&report(30.0, 100.0));
        assert!(met, "{lines:?}");
        assert!(lines.iter().all(|l| l.contains(": met")), "{lines:?}");
        let (lines, met) = budget_lines(&report(29.0, 100.0));
        assert!(!met);
        assert!(
            lines.first().is_some_and(|l| l.contains("NOT met (2.90×")),
            "{lines:?}"
        );
        let (lines, met) = budget_lines(&report(40.0, 99.0));
        assert!(!met);
        assert!(
            lines
                .get(1)
                .is_some_and(|l| l.contains("NOT met (9.90×; no segmentation at all: 24.8×)")),
            "{lines:?}"
        );
    }
}
