//! Real-data benchmark without ground truth: every method on consecutive scans of recorded
//! logs whose poses are known (the shared CARMEN logs' corrected poses, taken as the laser's).
//!
//! Per log and method, over all scans and all pairs of consecutive scans k, k+1:
//! - beams in features and bare beams of smooth runs, % of valid beams ([`coverage`]);
//! - lines of k moved into k+1's frame and matched there ([`compare`]): the point-weighted
//!   fraction that re-appears, the median |Δρ| and |Δα|, the median NIS of (α, ρ) with both
//!   lines' full covariance carried across the frame change ([`frame`]), raw and after a
//!   per-pair pose refit ([`refit`]);
//! - circles that re-appear and their centre NIS;
//! - pfe `default`'s lines against each other method's on the beams both hold in lines
//!   ([`shared`]).
//!
//! A pair is compared when both scans have a pose. Scan times are not used: in the shared
//! logs consecutive scans are about 1 m apart (0.1 m in freiburg-079; the corrected logs keep a
//! scan per step of the robot) and several logs' timestamps are 0 or garbage. `pfe realdata` (pfe-cli) prints the table and
//! writes `docs/REALDATA.md` ([`report`]).

pub mod compare;
pub mod coverage;
pub mod frame;
pub mod refit;
pub mod report;
pub mod shared;
pub mod statics;
mod svg;
#[cfg(test)]
mod tests;
pub mod visible;

use std::path::Path;

use anyhow::Context;
use serde::Serialize;

use crate::methods::baselines::{Acf, SplitMerge};
use crate::methods::{Method, Pfe, ScanContext};
use crate::score::quantile;
use pfe_formats::{InputError, Record};

pub use compare::{PairTally, Seen};
pub use coverage::Coverage;
pub use frame::{CircleObs, FrameChange, LineObs, Pose};

/// The four methods, told the data's range noise `sigma_r` (mm): pfe `default` and `paper`,
/// split-and-merge and ACF. pfe `default` is also told the LMS200's systematic range error
/// (CARMEN logs: [`Format::sigma_sys`](pfe_formats::Format::sigma_sys)).
pub fn methods(sigma_r: f32) -> Vec<Box<dyn Method>> {
    let sigma_sys = pfe_formats::Format::Carmen.sigma_sys();
    vec![
        Box::new(Pfe::new(
            "pfe-default",
            pfe_core::Config::default()
                .with_sigma_r(sigma_r)
                .with_sigma_sys(sigma_sys),
        )),
        Box::new(Pfe::new(
            "pfe-paper",
            pfe_core::Config::paper().with_sigma_r(sigma_r),
        )),
        Box::new(SplitMerge::new().with_sigma_r(sigma_r)),
        Box::new(Acf::new().with_sigma_r(sigma_r)),
    ]
}

/// Everything one method gave on one log.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tally {
    /// Scans read.
    pub scans: usize,
    /// Pairs of consecutive scans not compared (a pose missing).
    pub pairs_skipped: usize,
    /// Beam counts.
    pub coverage: Coverage,
    /// Pair results.
    pub pairs: PairTally,
    /// Small objects found.
    pub objects: usize,
    /// Small objects that stay where they are ([`statics`]).
    pub statics: statics::Statics,
}

/// One method's figures on one log.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// Method name.
    pub method: String,
    /// Scans.
    pub scans: usize,
    /// Pairs compared.
    pub pairs: usize,
    /// Valid beams in a feature, %.
    pub in_features_pct: f64,
    /// Bare beams of smooth runs, % of valid beams.
    pub bare_pct: f64,
    /// Of those, the beams of bare stretches at a smooth run's end, % of valid beams.
    pub bare_at_ends_pct: f64,
    /// Point-weighted fraction of lines of ≥ 10 points that re-appear, %.
    pub lines_reappear_pct: f64,
    /// Matched lines.
    pub lines_matched: usize,
    /// Median |Δρ|, mm.
    pub d_rho_mm: f64,
    /// Median |Δα|, mrad.
    pub d_alpha_mrad: f64,
    /// Median line NIS.
    pub nis: f64,
    /// Median line NIS after the pose refit.
    pub nis_refit: f64,
    /// What that median would be with consistent covariances (the same lines and refits).
    pub nis_refit_consistent: f64,
    /// Pairs with a pose refit.
    pub refits: usize,
    /// Circles of scan k.
    pub circles: usize,
    /// Circles that re-appear, %.
    pub circles_reappear_pct: f64,
    /// Matched circles.
    pub circles_matched: usize,
    /// Median centre NIS of matched circles.
    pub circle_nis: f64,
    /// Median centre NIS of matched circles after the pose refit of their pair's lines.
    pub circle_nis_refit: f64,
    /// Small objects per scan.
    pub objects_per_scan: f64,
    /// Small objects of scan k that re-appear in k+1, %.
    pub objects_reappear_pct: f64,
    /// Matched small objects.
    pub objects_matched: usize,
    /// Median centre NIS of matched small objects.
    pub object_nis: f64,
    /// Median centre NIS of matched small objects after the pose refit of their pair's lines.
    pub object_nis_refit: f64,
    /// Unambiguous matches of static small objects ([`statics`]).
    pub static_objects_matched: usize,
    /// Their median centre NIS.
    pub static_object_nis: f64,
    /// Their median centre NIS with the reference poses' own scatter added.
    pub static_object_nis_reference: f64,
    /// Their median centre NIS after the pose refit of their pair's lines.
    pub static_object_nis_refit: f64,
}

impl Tally {
    /// The figures, named `method`.
    pub fn summary(&self, method: &str) -> Summary {
        let pct = |a: usize, b: usize| {
            if b == 0 {
                f64::NAN
            } else {
                100.0 * a as f64 / b as f64
            }
        };
        let p = &self.pairs;
        let statics = self.statics.nis();
        Summary {
            method: method.to_string(),
            scans: self.scans,
            pairs: p.pairs,
            in_features_pct: pct(self.coverage.in_features, self.coverage.valid),
            bare_pct: pct(self.coverage.bare, self.coverage.valid),
            bare_at_ends_pct: pct(self.coverage.bare_at_ends, self.coverage.valid),
            lines_reappear_pct: pct(p.line_points_matched, p.line_points),
            lines_matched: p.d_rho.len(),
            d_rho_mm: quantile(&p.d_rho, 0.5),
            d_alpha_mrad: 1000.0 * quantile(&p.d_alpha, 0.5),
            nis: quantile(&p.nis, 0.5),
            nis_refit: quantile(&p.nis_refit, 0.5),
            nis_refit_consistent: quantile(&p.nis_refit_consistent, 0.5),
            refits: p.refits,
            circles: p.circles,
            circles_reappear_pct: pct(p.circles_matched, p.circles),
            circles_matched: p.circles_matched,
            circle_nis: quantile(&p.circle_nis, 0.5),
            circle_nis_refit: quantile(&p.circle_nis_refit, 0.5),
            objects_per_scan: if self.scans == 0 {
                f64::NAN
            } else {
                self.objects as f64 / self.scans as f64
            },
            objects_reappear_pct: pct(p.objects_matched, p.objects),
            objects_matched: p.objects_matched,
            object_nis: quantile(&p.object_nis, 0.5),
            object_nis_refit: quantile(&p.object_nis_refit, 0.5),
            static_objects_matched: statics.len(),
            static_object_nis: quantile(&statics, 0.5),
            static_object_nis_reference: quantile(&self.statics.nis_reference(), 0.5),
            static_object_nis_refit: quantile(&self.statics.nis_refit(), 0.5),
        }
    }
}

/// One log's figures, one [`Summary`] per method.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LogReport {
    /// Log name (file name without `.gz`, `.log` or `.clf`, and `-corrected`).
    pub log: String,
    /// Beams per scan (of the first scan).
    pub beams: usize,
    /// Per method.
    pub methods: Vec<Summary>,
    /// The first method (pfe `default` in [`methods`]) against each other method, beam by
    /// beam ([`shared`]).
    pub shared: Vec<shared::Shared>,
}

/// What the benchmark tells every method about a scan besides its ranges.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Told {
    /// Interleaved sweeps each scan is declared as (`None`: the record's own, else a SICK
    /// LMS2xx's for its resolution, [`context_of`]).
    pub sweeps: Option<u8>,
    /// Odometry of each scan from its neighbours' poses and times ([`motion_between`]); none
    /// by default (the logs' own odometry fields are zero).
    pub odometry_from_poses: bool,
}

/// Most time between the two neighbours of a scan whose poses give its odometry, s: the
/// mean motion over longer has little to do with the motion during the scan.
pub const ODOMETRY_SPAN_S: f64 = 1.0;

/// The motion during `record` from the poses and times of the scans before and after it
/// (`before`, `after`: pose [x m, y m, θ rad] and time s): the forward speed along the
/// record's heading and the turn rate, as a SICK LMS2xx of the record's resolution takes its
/// beams ([`pfe_core::BeamTiming::lms2xx`]). `None` without the poses or times, or when the
/// neighbours are more than [`ODOMETRY_SPAN_S`] apart.
///
/// ```
/// use pfe_eval::realdata::motion_between;
/// use pfe_formats::Record;
/// let mut r = Record {
///     id: 1,
///     geometry: pfe_core::ScanGeometry::lms200(180.0, 0.5),
///     ranges_mm: vec![1000.0; 361],
///     time: Some(10.25),
///     pose: Some([1.0, 2.0, 3.1]),
///     sweeps: None,
/// };
/// // 0.5 m/s towards +x, backwards for a heading of 3.1 rad, and a turn of 0.2 rad/s
/// // across θ = ±π.
/// let before = ([0.9, 2.0, 3.05], 10.0);
/// let after = ([1.15, 2.0, 3.15 - std::f64::consts::TAU], 10.5);
/// let m = motion_between(Some(before), Some(after), &r).unwrap();
/// let v = 0.25 * 3.1f64.cos() / 0.5 * 1000.0;
/// assert!(v < -499.0 && (m.v - v as f32).abs() < 1e-3 && (m.omega - 0.2).abs() < 1e-5);
/// assert_eq!(m.timing, pfe_core::BeamTiming::lms2xx(0.5));
/// assert!(motion_between(Some(before), Some(([1.15, 2.0, 3.15], 11.5)), &r).is_none());
/// r.time = None;
/// assert!(motion_between(Some(before), Some(after), &r).is_none());
/// ```
pub fn motion_between(
    before: Option<([f64; 3], f64)>,
    after: Option<([f64; 3], f64)>,
    record: &Record,
) -> Option<pfe_core::Motion> {
    let ((a, ta), (b, tb)) = (before?, after?);
    let (t, th) = (record.time?, record.pose?[2]);
    let dt = tb - ta;
    if !(dt > 0.0 && dt <= ODOMETRY_SPAN_S && ta <= t && t <= tb) {
        return None;
    }
    let along = (b[0] - a[0]) * th.cos() + (b[1] - a[1]) * th.sin();
    let turn = (b[2] - a[2] + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
        - std::f64::consts::PI;
    let step = record.geometry.angle_step.abs().to_degrees();
    let m = pfe_core::Motion {
        v: (1000.0 * along / dt) as f32,
        omega: (turn / dt) as f32,
        timing: pfe_core::BeamTiming::lms2xx(step),
    };
    m.is_valid().then_some(m)
}

/// Runs `methods` over `records` (at most `max_scans`, 0 = all), telling them what `told`
/// says. The first method is the reference the others are compared with beam by beam
/// ([`LogReport::shared`]).
pub fn run_records(
    log: &str,
    records: impl Iterator<Item = Result<Record, InputError>>,
    methods: &mut [Box<dyn Method>],
    max_scans: usize,
    told: Told,
) -> anyhow::Result<LogReport> {
    let limit = if max_scans == 0 {
        usize::MAX
    } else {
        max_scans
    };
    let mut tallies = vec![Tally::default(); methods.len()];
    let mut previous: Vec<Option<Seen>> = vec![None; methods.len()];
    let mut shared: Vec<shared::Shared> = methods
        .iter()
        .skip(1)
        .map(|m| shared::Shared::new(m.name()))
        .collect();
    let mut first = true;
    let mut beams = 0;
    // Beams of the previous scan (scan k of the next pair).
    let mut prev_beams = 0;
    let mut records = records.take(limit).peekable();
    // The scan before's pose and time, for the odometry.
    let mut before: Option<([f64; 3], f64)> = None;
    while let Some(record) = records.next() {
        let record = record.map_err(|e| anyhow::Error::new(e).context(log.to_string()))?;
        if beams == 0 {
            beams = record.ranges_mm.len();
        }
        let pose = pose_of(&record);
        let mut context = context_of(&record, told.sweeps);
        if told.odometry_from_poses && record.sweeps.is_none() {
            let after = records
                .peek()
                .and_then(|r| r.as_ref().ok())
                .and_then(|r| r.pose.zip(r.time));
            context.odometry = motion_between(before, after, &record);
        }
        before = record.pose.zip(record.time);
        let mut classed = Vec::with_capacity(methods.len());
        for ((method, tally), prev) in methods.iter_mut().zip(&mut tallies).zip(&mut previous) {
            let ex = method.extract_in(&record.geometry, &record.ranges_mm, &context);
            tally.scans += 1;
            tally.objects += ex
                .features
                .iter()
                .filter(|f| matches!(f, pfe_core::Feature::Object(_)))
                .count();
            tally.coverage.add(&Coverage::of(
                &record.geometry,
                &record.ranges_mm,
                &ex.features,
            ));
            let seen = pose.map(|p| Seen::new(p, &ex.features));
            match seen.as_ref() {
                Some(s) => tally.statics.scan(s),
                None => tally.statics.gap(),
            }
            match (prev.as_ref(), seen.as_ref()) {
                (Some(a), Some(b)) => {
                    tally.pairs.add(a, b);
                    classed.push(shared::beam_lines(a, b, prev_beams));
                }
                _ if !first => tally.pairs_skipped += 1,
                _ => {}
            }
            *prev = seen;
        }
        // Every method sees the same poses, so each has a pair here or none does.
        if let Some((reference, others)) = classed.split_first() {
            for (s, other) in shared.iter_mut().zip(others) {
                s.add(reference, other);
            }
        }
        prev_beams = record.ranges_mm.len();
        first = false;
    }
    Ok(LogReport {
        log: log.to_string(),
        beams,
        methods: methods
            .iter()
            .zip(&tallies)
            .map(|(m, t)| t.summary(m.name()))
            .collect(),
        shared,
    })
}

/// What the benchmark tells a method about a scan of a CARMEN log: no odometry, `sweeps`
/// interleaved sweeps (`None`: the record's own [`Record::sweeps`], else a SICK LMS2xx's for its
/// resolution, [`pfe_formats::sweeps_of`]) and the grid its ranges lie
/// on.
pub fn context_of(record: &Record, sweeps: Option<u8>) -> ScanContext {
    let carmen = pfe_formats::Format::Carmen;
    ScanContext {
        odometry: None,
        sweeps: usize::from(
            sweeps
                .or(record.sweeps)
                .unwrap_or_else(|| pfe_formats::sweeps_of(carmen, &record.geometry)),
        ),
        quantum: pfe_formats::range_quantum(&record.ranges_mm, record.geometry.r_max),
    }
}

/// A record's pose in mm and rad (the logs give m).
pub fn pose_of(record: &Record) -> Option<Pose> {
    record.pose.map(|[x, y, t]| [1000.0 * x, 1000.0 * y, t])
}

/// One scan of a CARMEN log as the benchmark reads it.
pub struct LogScan {
    /// The record.
    pub record: Record,
    /// What a method is told about it ([`context_of`]: the sweeps its line says, else a SICK
    /// LMS2xx's).
    pub context: ScanContext,
    /// Its pose, mm and rad.
    pub pose: Option<Pose>,
}

/// The scans of the CARMEN log `path` (gzip allowed), in order.
pub fn log_scans(path: &Path) -> anyhow::Result<impl Iterator<Item = anyhow::Result<LogScan>>> {
    let input = pfe_formats::open_for(path, pfe_formats::Format::Carmen, |r| r)
        .with_context(|| format!("opening {}", path.display()))?;
    let log = path.display().to_string();
    Ok(pfe_formats::carmen::Reader::new(input).map(move |r| {
        let record = r.map_err(|e| anyhow::anyhow!("{log}: {e}"))?;
        Ok(LogScan {
            context: context_of(&record, None),
            pose: pose_of(&record),
            record,
        })
    }))
}

/// Runs the four [`methods`] (σ_r = `sigma_r` mm) on the CARMEN log `path`.
pub fn run_log(
    path: &Path,
    sigma_r: f32,
    max_scans: usize,
    told: Told,
) -> anyhow::Result<LogReport> {
    let input = pfe_formats::open_for(path, pfe_formats::Format::Carmen, |r| r)
        .with_context(|| format!("opening {}", path.display()))?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    let name = name.trim_end_matches(".gz");
    let name = name
        .strip_suffix(".log")
        .or_else(|| name.strip_suffix(".clf"))
        .unwrap_or(name)
        .trim_end_matches("-corrected")
        .to_string();
    let reader = pfe_formats::carmen::Reader::new(input);
    run_records(&name, reader, &mut methods(sigma_r), max_scans, told)
}
