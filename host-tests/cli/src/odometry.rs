//! `pfe odometry`: the pose of every scan (pfe-pose's feature odometry on pfe-core's
//! features), one JSON object per scan on stdout (docs/JSON.md).

use std::path::PathBuf;

use serde::Serialize;

use super::input::{
    self, bad_input, flush, nothing_found, open_scans, stdout, write_json, MethodArgs,
};
use super::{interrupt, Failure};
use pfe_formats::{carmen, Format, InputError, Record};
use pfe_pose::{Cov3, FeatureOdometry, Observation, Pose, Status, Step};

/// Features the local map of the odometry holds (the firmware's too).
pub const MAP: usize = pfe_pose::ODOMETRY_MAP;

/// Arguments of `pfe odometry`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    method: MethodArgs,
    /// Input file (gzip is read transparently; `-` = stdin).
    file: PathBuf,
    /// Motion prior of each scan: `none`, or `odometry`, the log's wheel odometry where it
    /// has one (CARMEN `FLASER` lines' `odom_x odom_y odom_θ`; scans without it get none),
    /// the motion between consecutive odometry poses with σ = --prior-sigma-xy +
    /// --prior-sigma-rel × translation per axis and --prior-sigma-theta + --prior-sigma-rel ×
    /// rotation, independent.
    #[arg(long, default_value = "none")]
    prior: PriorArg,
    /// The prior's σ per axis at rest, mm (finite, > 0).
    #[arg(long, default_value_t = 50.0, value_parser = input::sigma_mm)]
    prior_sigma_xy: f32,
    /// The prior's heading σ at rest, degrees (finite, > 0).
    #[arg(long, default_value_t = 2.0, value_parser = positive)]
    prior_sigma_theta: f32,
    /// The part of the motion added to the prior's σ (0.1: 10 % of the translation and of the
    /// rotation), finite, ≥ 0.
    #[arg(long, default_value_t = 0.1, value_parser = non_negative)]
    prior_sigma_rel: f32,
}

/// A finite number > 0.
fn positive(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("must be a finite number > 0, got {s:?}")),
    }
}

/// A finite number ≥ 0.
fn non_negative(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!("must be a finite number ≥ 0, got {s:?}")),
    }
}

/// `--prior`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum PriorArg {
    /// No prior: registration from the features alone.
    None,
    /// The log's wheel odometry (CARMEN `FLASER`).
    Odometry,
}

/// A pose with its covariance in the output (docs/JSON.md).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PoseJson {
    /// mm.
    pub x: f32,
    /// mm.
    pub y: f32,
    /// rad.
    pub theta: f32,
    /// 3×3 row-major, (x mm, y mm, θ rad).
    pub cov: [f32; 9],
}

impl PoseJson {
    /// The pose `p` with covariance `c`.
    pub fn new(p: &Pose, c: &Cov3) -> Self {
        let mut cov = [0.0; 9];
        for (i, v) in c.iter().flatten().enumerate() {
            if let Some(slot) = cov.get_mut(i) {
                *slot = *v;
            }
        }
        PoseJson {
            x: p.x,
            y: p.y,
            theta: p.theta,
            cov,
        }
    }
}

/// One scan's odometry result as output: `rel`, `pose`, `status`, `direction`, `reason` of
/// `pfe odometry`'s lines, and `pfe listen`'s `odometry` object (docs/JSON.md).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StepJson {
    /// This scan's pose in the previous scan's frame.
    pub rel: PoseJson,
    /// This scan's pose in the first scan's frame.
    pub pose: PoseJson,
    /// `"ok"`, `"degenerate"` or `"none"`.
    pub status: &'static str,
    /// The direction the scene cannot tell (x mm, y mm, θ × 1000 mm), for "degenerate".
    #[serde(skip_serializing_if = "Option::is_none")]
    pub direction: Option<[f32; 3]>,
    /// Why there is no registration, for "none".
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

impl StepJson {
    /// The output of `step`.
    pub fn new(step: &Step) -> Self {
        let (status, direction, reason) = match step.status {
            Status::Ok => ("ok", None, None),
            Status::Degenerate { direction } => ("degenerate", Some(direction), None),
            Status::None(f) => ("none", None, Some(format!("{f:?}"))),
        };
        StepJson {
            rel: PoseJson::new(&step.rel, &step.rel_cov),
            pose: PoseJson::new(&step.pose, &step.cov),
            status,
            direction,
            reason,
        }
    }
}

/// One output line.
#[derive(Serialize)]
struct Line {
    scan: u64,
    #[serde(flatten)]
    step: StepJson,
    /// Features of the scan given to the odometry.
    features: usize,
    /// Whether a motion prior was given.
    prior: bool,
    /// The log's own pose of the scan, [x m, y m, θ rad] (CARMEN), as `pfe extract` prints it.
    #[serde(skip_serializing_if = "Option::is_none")]
    log_pose: Option<[f64; 3]>,
}

/// A scan and the log's odometry pose for it.
type Item = Result<(Record, Option<[f64; 3]>), InputError>;

/// The scans of a CARMEN log with the odometry of their lines.
struct WithOdometry(carmen::Reader);

impl Iterator for WithOdometry {
    type Item = Item;
    fn next(&mut self) -> Option<Item> {
        let r = self.0.next()?;
        Some(r.map(|record| (record, self.0.odometry())))
    }
}

/// The motion prior between two odometry poses (m, rad) with the stated σ.
fn prior_between(a: &Args, p0: [f64; 3], p1: [f64; 3]) -> Option<(Pose, Cov3)> {
    let mm = |p: [f64; 3]| Pose::new((p[0] * 1000.0) as f32, (p[1] * 1000.0) as f32, p[2] as f32);
    let rel = mm(p0).inverse().compose(&mm(p1));
    if !(rel.x.is_finite() && rel.y.is_finite() && rel.theta.is_finite()) {
        return None;
    }
    let k = a.prior_sigma_rel;
    let sxy = a.prior_sigma_xy + k * rel.x.hypot(rel.y);
    let sth = a.prior_sigma_theta.to_radians() + k * rel.theta.abs();
    let mut cov = [[0.0f32; 3]; 3];
    cov[0][0] = sxy * sxy;
    cov[1][1] = sxy * sxy;
    cov[2][2] = sth * sth;
    Some((rel, cov))
}

/// Runs `pfe odometry`.
pub fn run(a: Args) -> Result<(), Failure> {
    let (format, file) = (a.method.format, a.file.as_path());
    let mut method = a.method.method();
    let (scans, bar, bytes): (Box<dyn Iterator<Item = Item>>, _, _) =
        if format == Format::Carmen && a.method.topic.is_none() {
            let input = input::open(file, format)?;
            (
                Box::new(WithOdometry(carmen::Reader::new(input.reader))),
                input.bar,
                input.bytes,
            )
        } else {
            let source = open_scans(file, format, a.method.topic.as_deref())?;
            (
                Box::new(source.scans.map(|s| s.map(|s| (s.record, None)))),
                source.bar,
                source.bytes,
            )
        };
    let mut odometry = Box::new(FeatureOdometry::new_default());
    let mut out = stdout();
    let mut count = [0u64; 3];
    let mut n = 0u64;
    let mut error = None;
    let mut interrupted = false;
    let mut last_odometry: Option<[f64; 3]> = None;
    let mut without_odometry = 0u64;
    for scan in scans {
        if interrupt::requested() {
            interrupted = true;
            break;
        }
        let (record, odo) = match scan {
            Ok(s) => s,
            Err(e) => {
                error = Some(bad_input(file, format, n, &e));
                break;
            }
        };
        let context = a.method.context(&record);
        let ex = pfe_eval::methods::Method::extract_in(
            &mut method,
            &record.geometry,
            &record.ranges_mm,
            &context,
        );
        // What the odometry takes of the features (the firmware's pose step is the same call).
        let used = ex
            .features
            .iter()
            .filter(|f| Observation::from_feature(f).is_some())
            .count();
        let prior = match (a.prior, last_odometry, odo) {
            (PriorArg::Odometry, Some(p0), Some(p1)) => prior_between(&a, p0, p1),
            _ => None,
        };
        if a.prior == PriorArg::Odometry && n > 0 && prior.is_none() {
            without_odometry += 1;
        }
        last_odometry = odo;
        let step = odometry.update_features(&ex.features, prior);
        n += 1;
        if n % 256 == 0 {
            bar.set_message(format!("{n} scans"));
        }
        let step = StepJson::new(&step);
        count[match step.status {
            "ok" => 0,
            "degenerate" => 1,
            _ => 2,
        }] += 1;
        let line = Line {
            scan: record.id,
            step,
            features: used,
            prior: prior.is_some(),
            log_pose: record.pose,
        };
        if !write_json(&mut out, &line)? {
            break;
        }
    }
    flush(&mut out)?;
    bar.finish_and_clear();
    if interrupted && error.is_none() {
        error = Some(Failure {
            code: 130,
            message: format!("interrupted after {n} scans"),
        });
    }
    if let Some(e) = error {
        return Err(e);
    }
    if n == 0 {
        let bytes = bytes.load(std::sync::atomic::Ordering::Relaxed);
        return Err(nothing_found(file, format, "scan", bytes));
    }
    if without_odometry > 0 {
        eprintln!(
            "pfe: --prior odometry: {without_odometry} of {} scans had no odometry pair in the input (registered without a prior)",
            n - 1
        );
    }
    eprintln!(
        "pfe: {n} scans: {} ok, {} degenerate, {} none",
        count[0], count[1], count[2]
    );
    Ok(())
}
