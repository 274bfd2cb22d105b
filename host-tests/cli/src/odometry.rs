//! `pfe odometry`: the pose of every scan (pfe-pose's feature odometry on pfe-core's
//! features), one JSON object per scan on stdout (docs/JSON.md).

use std::path::PathBuf;

use serde::Serialize;

use super::extract::{create_foxglove, mcap_failure, DEFAULT_FRAME, SYNTHETIC_PERIOD_NS};
use super::input::{
    self, bad_input, flush, nothing_found, open_scans, stdout, write_json, MethodArgs,
};
use super::{interrupt, Failure};
use crate::foxglove::odometry as fox;
use crate::foxglove::FoxgloveWriter;
use pfe_formats::{carmen, Format, InputError, Record};
use pfe_pose::{Cov3, Observation, PointOdometry, Pose, Status, Step};

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
    /// Also write a Foxglove MCAP file: per scan, the scan (/scan) and its features
    /// (/features) in frame "laser" as `pfe extract --mcap` writes them, the odometry's frames
    /// (/tf: odom → laser, and world → odom at the log's first pose when it has poses), pose
    /// (/odometry/pose), trajectory (/odometry/trajectory) and local map with the pose's
    /// covariance (/odometry/map), and the log's own poses (/log/trajectory). Stamps as
    /// `pfe extract --mcap`'s. Never replaces an existing file without --force.
    #[arg(long, value_name = "OUT.mcap")]
    mcap: Option<PathBuf>,
    /// Let --mcap replace an existing file.
    #[arg(long, requires = "mcap")]
    force: bool,
    /// Also use the scans' own points (host only: the firmware registers features alone):
    /// they verify the features' registration, resolve what the features leave degenerate,
    /// and a point-to-line ICP registers the scans the features cannot (pfe-pose's
    /// `PointOdometry::update_scan`; docs/POSE.md).
    #[arg(long)]
    points: bool,
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

/// A scan, the log's odometry pose for it, its stamp (ns) and frame (bags).
type Item = Result<(Record, Option<[f64; 3]>, Option<u64>, Option<String>), InputError>;

/// The scans of a CARMEN log with the odometry of their lines.
struct WithOdometry(carmen::Reader);

impl Iterator for WithOdometry {
    type Item = Item;
    fn next(&mut self) -> Option<Item> {
        let r = self.0.next()?;
        Some(r.map(|record| (record, self.0.odometry(), None, None)))
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
                Box::new(
                    source
                        .scans
                        .map(|s| s.map(|s| (s.record, None, s.stamp_ns, s.frame_id))),
                ),
                source.bar,
                source.bytes,
            )
        };
    let mut foxglove = match &a.mcap {
        Some(path) => Some(OdometryMcap::create(path, a.force)?),
        None => None,
    };
    let mut odometry = Box::new(PointOdometry::new_default());
    let mut out = stdout();
    let mut count = [0u64; 3];
    let mut n = 0u64;
    let mut error = None;
    let mut interrupted = false;
    let mut last_odometry: Option<[f64; 3]> = None;
    let mut without_odometry = 0u64;
    let mut auto = a.method.auto_sweeps();
    for scan in scans {
        if interrupt::requested() {
            interrupted = true;
            break;
        }
        let (record, odo, stamp_ns, frame_id) = match scan {
            Ok(s) => s,
            Err(e) => {
                error = Some(bad_input(file, format, n, &e));
                break;
            }
        };
        let context = a.method.context(&record, &mut auto);
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
        let step = if a.points {
            odometry.update_scan(&ex.features, &record.geometry, &record.ranges_mm, prior)
        } else {
            odometry.update_features(&ex.features, prior)
        };
        n += 1;
        if n % 256 == 0 {
            bar.set_message(format!("{n} scans"));
        }
        let raw = step;
        let step = StepJson::new(&raw);
        count[match step.status {
            "ok" => 0,
            "degenerate" => 1,
            _ => 2,
        }] += 1;
        if let Some(f) = foxglove.as_mut() {
            let stamp = stamp_ns.unwrap_or((n - 1).saturating_mul(SYNTHETIC_PERIOD_NS));
            let frame = frame_id.as_deref().unwrap_or(DEFAULT_FRAME);
            let map: Vec<Observation> = odometry.map().collect();
            let status = step.status;
            if let Err(e) = f.write(stamp, frame, &record, &ex.features, &raw, status, &map) {
                error = Some(mcap_failure(a.mcap.as_deref(), &e));
                break;
            }
        }
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
    // The scans read before an error or Ctrl-C are kept in the Foxglove file too.
    if let Some(f) = foxglove {
        match f.finish() {
            Ok(path) => eprintln!("pfe: wrote {} ({n} scans)", path.display()),
            Err(e) => {
                error.get_or_insert(mcap_failure(a.mcap.as_deref(), &e));
            }
        }
    }
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

/// `--mcap`: the scans, features and the odometry's frames, pose, trajectory and map.
struct OdometryMcap {
    w: FoxgloveWriter,
    tf: u16,
    pose: u16,
    trajectory: u16,
    map: u16,
    log_trajectory: u16,
    /// Every pose so far, odometry frame (mm, mm, rad).
    poses: Vec<[f64; 3]>,
    /// Every log pose so far, its frame (mm, mm, rad).
    log: Vec<[f64; 3]>,
    /// The log's pose of the first scan: the odometry frame in the log's.
    anchor: Option<[f64; 3]>,
    scans: u64,
    /// The last scan's stamp and the scans when the trajectories were last written.
    last_stamp: u64,
    trajectories_at: u64,
}

impl OdometryMcap {
    fn create(path: &std::path::Path, force: bool) -> Result<Self, Failure> {
        let mut w = create_foxglove(path, force)?;
        let mut add = |c| w.add_channel(c).map_err(|e| mcap_failure(Some(path), &e));
        let (tf, pose, trajectory, map, log_trajectory) = (
            add(&fox::TF)?,
            add(&fox::POSE)?,
            add(&fox::TRAJECTORY)?,
            add(&fox::MAP)?,
            add(&fox::LOG_TRAJECTORY)?,
        );
        Ok(Self {
            w,
            tf,
            pose,
            trajectory,
            map,
            log_trajectory,
            poses: Vec::new(),
            log: Vec::new(),
            anchor: None,
            scans: 0,
            last_stamp: 0,
            trajectories_at: 0,
        })
    }

    /// One scan: its scan and features, then the odometry's messages.
    #[allow(clippy::too_many_arguments)]
    fn write(
        &mut self,
        stamp: u64,
        frame: &str,
        record: &Record,
        features: &[pfe_core::Feature],
        step: &pfe_pose::Step,
        status: &str,
        map: &[Observation],
    ) -> std::io::Result<()> {
        self.w.write_scan(stamp, frame, record, features)?;
        let p = &step.pose;
        let pose = (f64::from(p.x), f64::from(p.y), f64::from(p.theta));
        self.poses.push([pose.0, pose.1, pose.2]);
        self.scans += 1;
        let tf = fox::frame_transform(stamp, fox::ODOM_FRAME, frame, pose);
        self.w.write_message(self.tf, stamp, &tf)?;
        let log = record
            .pose
            .map(|q| [q[0] * 1000.0, q[1] * 1000.0, q[2]])
            .filter(|q| q.iter().all(|v| v.is_finite()));
        if self.scans == 1 {
            self.anchor = log;
        }
        if let Some(q) = log {
            self.log.push(q);
        }
        if let Some(a) = self.anchor {
            let tf =
                fox::frame_transform(stamp, fox::WORLD_FRAME, fox::ODOM_FRAME, (a[0], a[1], a[2]));
            self.w.write_message(self.tf, stamp, &tf)?;
        }
        let m = fox::pose_in_frame(stamp, fox::ODOM_FRAME, pose);
        self.w.write_message(self.pose, stamp, &m)?;
        let m = fox::map_update(stamp, fox::ODOM_FRAME, map, &step.pose, &step.cov, status);
        self.w.write_message(self.map, stamp, &m)?;
        // The trajectories: every scan at first, then every TRAJECTORY_EVERY-th (and the
        // last scan's, at finish).
        self.last_stamp = stamp;
        if self.scans <= fox::TRAJECTORY_MESSAGES as u64 || self.scans % fox::TRAJECTORY_EVERY == 0
        {
            self.write_trajectories(stamp)?;
        }
        Ok(())
    }

    fn write_trajectories(&mut self, stamp: u64) -> std::io::Result<()> {
        self.trajectories_at = self.scans;
        let m = fox::poses_in_frame(
            stamp,
            fox::ODOM_FRAME,
            &fox::thin(&self.poses, fox::TRAJECTORY_POSES),
        );
        self.w.write_message(self.trajectory, stamp, &m)?;
        if !self.log.is_empty() {
            let m = fox::poses_in_frame(
                stamp,
                fox::WORLD_FRAME,
                &fox::thin(&self.log, fox::TRAJECTORY_POSES),
            );
            self.w.write_message(self.log_trajectory, stamp, &m)?;
        }
        Ok(())
    }

    fn finish(mut self) -> std::io::Result<PathBuf> {
        if self.trajectories_at != self.scans {
            self.write_trajectories(self.last_stamp)?;
        }
        self.w.finish()
    }
}
