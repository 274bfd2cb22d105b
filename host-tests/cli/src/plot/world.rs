//! `pfe plot --world`: the scans of a log in the world frame by its poses, with pfe-pose's
//! odometry beside the log's own trajectory.

use std::path::Path;

use super::{write_output, Args};
use crate::input::{bad_input, nothing_found, open_scans};
use crate::Failure;
use pfe_eval::methods::Method;

/// Most scans whose points `pfe plot --world` draws without --every.
pub const WORLD_DRAWN: usize = 200;

/// `pfe plot --world`: the scans in the world frame, with the odometry beside the log's poses.
pub(super) fn run_world(a: &Args, output: &Path) -> Result<(), Failure> {
    use crate::figure::world::{self, MapFeature, OdometryTrack, Placed, Pose, World};
    use pfe_core::Feature;
    let (file, format) = (a.file.as_path(), a.method.format);
    let mut method = a.method.method();
    let input = open_scans(file, format, a.method.topic.as_deref())?;
    let bar = input.bar.clone();
    let mut scans: Vec<(pfe_formats::Record, Vec<Feature>)> = Vec::new();
    let mut count = 0u64;
    let mut auto = a.method.auto_sweeps();
    for s in input.scans {
        if crate::interrupt::requested() {
            return Err(Failure {
                code: 130,
                message: format!("interrupted after {count} scans"),
            });
        }
        let s = s.map_err(|e| bad_input(file, format, count, &e))?;
        count += 1;
        if a.scans.as_ref().is_some_and(|r| !r.contains(&s.record.id)) {
            if a.scans.as_ref().is_some_and(|r| s.record.id > *r.end()) {
                break;
            }
            continue;
        }
        let context = a.method.context(&s.record, &mut auto);
        let ex = method.extract_in(&s.record.geometry, &s.record.ranges_mm, &context);
        scans.push((s.record, ex.features));
        if count % 256 == 0 {
            bar.set_message(format!("{count} scans"));
        }
    }
    bar.finish_and_clear();
    if count == 0 {
        let bytes = input.bytes.load(std::sync::atomic::Ordering::Relaxed);
        return Err(nothing_found(file, format, "scan", bytes));
    }
    if scans.is_empty() {
        let r = a.scans.clone().unwrap_or(0..=0);
        return Err(Failure::input(format!(
            "{}: no scan with an ID in {}..{} ({count} scans read)",
            file.display(),
            r.start(),
            r.end()
        )));
    }
    let mm = |p: [f64; 3]| -> Pose { [p[0] * 1000.0, p[1] * 1000.0, p[2]] };
    let log: Vec<Pose> = scans
        .iter()
        .filter_map(|(r, _)| r.pose.map(mm))
        .filter(|p| p.iter().all(|v| v.is_finite()))
        .collect();
    if log.is_empty() && !a.odometry {
        return Err(Failure::input(format!(
            "{}: no scan has a pose (a CARMEN log has them); --world needs them, or --odometry to draw the scans in the odometry's frame",
            file.display()
        )));
    }
    let every = a
        .every
        .map(|n| usize::try_from(n).unwrap_or(usize::MAX))
        .unwrap_or_else(|| scans.len().div_ceil(WORLD_DRAWN).max(1));
    let odometry_poses: Option<(Vec<Pose>, OdometryTrack)> = a.odometry.then(|| {
        let mut odo = Box::new(pfe_pose::PointOdometry::new_default());
        let mut track = OdometryTrack {
            poses: Vec::with_capacity(scans.len()),
            covs: Vec::with_capacity(scans.len()),
            degenerate: Vec::new(),
            none: Vec::new(),
            map: Vec::new(),
            segments: Vec::new(),
            points: a.points,
        };
        let mut raw: Vec<(Pose, [[f64; 2]; 2])> = Vec::with_capacity(scans.len());
        for (k, (record, features)) in scans.iter().enumerate() {
            let step = if a.points {
                odo.update_scan(features, &record.geometry, &record.ranges_mm, None)
            } else {
                odo.update_features(features, None)
            };
            match step.status {
                pfe_pose::Status::Ok => {}
                pfe_pose::Status::Degenerate { .. } => track.degenerate.push(k),
                pfe_pose::Status::None(_) => track.none.push(k),
            }
            let p = step.pose;
            let c = |i: usize, j: usize| f64::from(step.cov[i][j]);
            raw.push((
                [f64::from(p.x), f64::from(p.y), f64::from(p.theta)],
                [[c(0, 0), c(0, 1)], [c(1, 0), c(1, 1)]],
            ));
        }
        // The odometry's frame in the log's: where the first scan with a log pose is in both
        // (the first scan's log pose when it has one), else the origin.
        let anchor: Pose = scans
            .iter()
            .zip(&raw)
            .find_map(|((r, _), (o, _))| {
                let l = mm(r.pose?);
                let (s, c) = o[2].sin_cos();
                let inv = [-(c * o[0] + s * o[1]), s * o[0] - c * o[1], -o[2]];
                Some(world::compose(&l, &inv))
            })
            .unwrap_or([0.0; 3]);
        let (s0, c0) = anchor[2].sin_cos();
        for (p, cov) in &raw {
            let pose = world::compose(&anchor, p);
            // The position's covariance turned into the world's axes: R C Rᵀ.
            let (xx, xy, yy) = (cov[0][0], 0.5 * (cov[0][1] + cov[1][0]), cov[1][1]);
            track.covs.push([
                [
                    c0 * c0 * xx - 2.0 * s0 * c0 * xy + s0 * s0 * yy,
                    s0 * c0 * (xx - yy) + (c0 * c0 - s0 * s0) * xy,
                ],
                [
                    s0 * c0 * (xx - yy) + (c0 * c0 - s0 * s0) * xy,
                    s0 * s0 * xx + 2.0 * s0 * c0 * xy + c0 * c0 * yy,
                ],
            ]);
            track.poses.push(pose);
        }
        for m in odo.map() {
            let at = |v: [f32; 2]| world::place(&anchor, (f64::from(v[0]), f64::from(v[1])));
            match m {
                pfe_pose::Observation::Line(l) if l.has_extent() => {
                    track.map.push(MapFeature::Segment(at(l.start), at(l.end)));
                }
                pfe_pose::Observation::Point(p) => {
                    track.map.push(MapFeature::Point(at([p.x, p.y])));
                }
                _ => {}
            }
        }
        (track.poses.clone(), track)
    });
    let (placed_by, poses): (String, Vec<Option<Pose>>) = if log.is_empty() {
        let odo = odometry_poses
            .as_ref()
            .map(|(p, _)| p.iter().copied().map(Some).collect())
            .unwrap_or_default();
        ("the odometry".into(), odo)
    } else {
        (
            "the log's poses".into(),
            scans.iter().map(|(r, _)| r.pose.map(mm)).collect(),
        )
    };
    let mut drawn: Vec<Placed> = Vec::new();
    let mut track = odometry_poses.map(|(_, t)| t);
    for (k, ((record, features), pose)) in scans.iter().zip(&poses).enumerate() {
        if k % every != 0 {
            continue;
        }
        if let Some(pose) = pose {
            drawn.push(Placed {
                record,
                features,
                pose: *pose,
            });
        }
        // The lines by the odometry's poses, beside those by the log's (not twice).
        if let Some(t) = track.as_mut().filter(|_| !log.is_empty()) {
            if let Some(p) = t.poses.get(k).copied() {
                for f in features {
                    if let Feature::Line(l) = f {
                        let a = world::place(&p, (f64::from(l.start.x), f64::from(l.start.y)));
                        let e = world::place(&p, (f64::from(l.end.x), f64::from(l.end.y)));
                        t.segments.push((a, e));
                    }
                }
            }
        }
    }
    let name = file
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let (first, last) = (
        scans.first().map_or(0, |s| s.0.id),
        scans.last().map_or(0, |s| s.0.id),
    );
    let frame = if log.is_empty() { "odometry" } else { "world" };
    let figure = World {
        title: format!(
            "{name} — scans {first}..{last} in the {frame} frame — {}",
            method.name()
        ),
        frame: frame.into(),
        placed_by,
        scans: drawn,
        read: scans.len(),
        every,
        log,
        odometry: track,
    };
    write_output(output, &world::svg(&figure), a.force)?;
    eprintln!(
        "pfe: wrote {} ({} scans, {} drawn{})",
        output.display(),
        figure.read,
        figure.scans.len(),
        figure
            .odometry
            .as_ref()
            .map(|o| format!(
                "; odometry: {} degenerate, {} none",
                o.degenerate.len(),
                o.none.len()
            ))
            .unwrap_or_default()
    );
    Ok(())
}
