//! `pfe odometry --mcap`: the odometry's pose, trajectory and map as Foxglove messages, beside
//! the scans and their features of [`super::FoxgloveWriter::write_scan`] (frame `laser`).
//!
//! - [`TF`]: `foxglove.FrameTransform` per scan, [`ODOM_FRAME`] → `laser` (the odometry's
//!   pose of the scan), and [`WORLD_FRAME`] → [`ODOM_FRAME`] (the log's pose of the first
//!   scan) when the log has poses, so that Foxglove's 3D panel shows the scans, the features,
//!   the map and the log's trajectory together in either frame;
//! - [`POSE`]: `foxglove.PoseInFrame`, the scan's pose in [`ODOM_FRAME`];
//! - [`TRAJECTORY`]: `foxglove.PosesInFrame`, the poses so far in [`ODOM_FRAME`] (at most
//!   [`TRAJECTORY_POSES`] of them, evenly spaced), every scan for the first
//!   [`TRAJECTORY_MESSAGES`] scans, then every [`TRAJECTORY_EVERY`]-th and the last: the file's
//!   size stays linear in the log's length;
//! - [`MAP`]: `foxglove.SceneUpdate` in [`ODOM_FRAME`]: the local map's lines (segment and ±1σ
//!   band, as `/features` draws them) and points (their 3σ ellipse), and the pose's 3σ position
//!   ellipse and ±3σ heading (entity `pose`, its status and covariance in the metadata);
//! - [`LOG_TRAJECTORY`]: `foxglove.PosesInFrame`, the log's own poses in [`WORLD_FRAME`]
//!   (CARMEN's corrected poses), when it has them.

use pfe_core::{LineFeature, Point};
use pfe_pose::{Cov3, Observation, Pose};
use serde_json::{json, Value};

use super::scene::{
    color, entity, line_entity, line_primitive, point, time, LINE_LOOP, LINE_STRIP, MM,
};
use super::schema::{array, object, pose_schema, scene_update_schema, time_schema, vector3_schema};
use super::Channel;

/// The odometry's frame: the first scan's.
pub const ODOM_FRAME: &str = "odom";
/// The log's frame (its poses').
pub const WORLD_FRAME: &str = "world";
/// Most poses in one trajectory message.
pub const TRAJECTORY_POSES: usize = 1000;
/// The scans that each get a trajectory message.
pub const TRAJECTORY_MESSAGES: usize = 200;
/// After them, a trajectory message every this many scans.
pub const TRAJECTORY_EVERY: u64 = 64;

fn quaternion(theta: f64) -> Value {
    json!({ "x": 0.0, "y": 0.0, "z": (0.5 * theta).sin(), "w": (0.5 * theta).cos() })
}

/// A `foxglove.Pose` at (x, y) mm heading `theta` rad.
fn pose_value(x: f64, y: f64, theta: f64) -> Value {
    json!({ "position": point(x * MM, y * MM), "orientation": quaternion(theta) })
}

/// A `foxglove.FrameTransform`: `child` at (x, y) mm, heading `theta` rad in `parent`.
pub fn frame_transform(
    stamp_ns: u64,
    parent: &str,
    child: &str,
    (x, y, theta): (f64, f64, f64),
) -> Value {
    json!({
        "timestamp": time(stamp_ns),
        "parent_frame_id": parent,
        "child_frame_id": child,
        "translation": point(x * MM, y * MM),
        "rotation": quaternion(theta),
    })
}

/// A `foxglove.PoseInFrame` at (x, y) mm heading `theta` rad.
pub fn pose_in_frame(stamp_ns: u64, frame_id: &str, (x, y, theta): (f64, f64, f64)) -> Value {
    json!({
        "timestamp": time(stamp_ns),
        "frame_id": frame_id,
        "pose": pose_value(x, y, theta),
    })
}

/// A `foxglove.PosesInFrame` of `poses` (x mm, y mm, θ rad).
pub fn poses_in_frame(stamp_ns: u64, frame_id: &str, poses: &[[f64; 3]]) -> Value {
    let poses: Vec<Value> = poses.iter().map(|p| pose_value(p[0], p[1], p[2])).collect();
    json!({ "timestamp": time(stamp_ns), "frame_id": frame_id, "poses": poses })
}

/// At most `max` of `poses`, evenly spaced, the last one always in.
pub fn thin(poses: &[[f64; 3]], max: usize) -> Vec<[f64; 3]> {
    let n = poses.len();
    if n <= max || max < 2 {
        return poses.to_vec();
    }
    (0..max)
        .map(|k| k * (n - 1) / (max - 1))
        .filter_map(|i| poses.get(i).copied())
        .collect()
}

/// `m` points (m) around the ellipse `xᵀ C⁻¹ x = k²` of the 2×2 covariance `c` (mm²) at
/// (cx, cy) mm.
fn cov_ellipse(cx: f64, cy: f64, c: [[f64; 2]; 2], k: f64, m: usize) -> Vec<Value> {
    let (a, b, phi) = crate::figure::ellipse(c, k);
    (0..m)
        .map(|i| {
            let t = std::f64::consts::TAU * i as f64 / m as f64;
            let (u, v) = (a * t.cos(), b * t.sin());
            point(
                (cx + u * phi.cos() - v * phi.sin()) * MM,
                (cy + u * phi.sin() + v * phi.cos()) * MM,
            )
        })
        .collect()
}

/// A `foxglove.SceneUpdate` in `frame_id` of the odometry's local map `map` and of its pose
/// `pose` with covariance `cov` and registration `status`: deletes the previous one's
/// entities; lines `map-K` as `/features` draws a line, points `map-K` with their 3σ
/// ellipse, and entity `pose`.
pub fn map_update(
    stamp_ns: u64,
    frame_id: &str,
    map: &[Observation],
    pose: &Pose,
    cov: &Cov3,
    status: &str,
) -> Value {
    let mut entities: Vec<Value> = Vec::with_capacity(map.len() + 1);
    for (k, m) in map.iter().enumerate() {
        let mut e = match m {
            Observation::Line(l) => {
                let p = |v: [f32; 2]| Point::new(v[0], v[1]);
                let (start, end) = if l.has_extent() {
                    (p(l.start), p(l.end))
                } else {
                    // No extent: 1 m either side of the foot of the normal.
                    let (n, d) = (
                        (l.alpha.cos(), l.alpha.sin()),
                        (-l.alpha.sin(), l.alpha.cos()),
                    );
                    (
                        Point::new(l.rho * n.0 - 1000.0 * d.0, l.rho * n.1 - 1000.0 * d.1),
                        Point::new(l.rho * n.0 + 1000.0 * d.0, l.rho * n.1 + 1000.0 * d.1),
                    )
                };
                let f = LineFeature::new(
                    0,
                    0,
                    0,
                    l.alpha,
                    l.rho,
                    l.cov[0][0],
                    l.cov[1][1],
                    l.cov[0][1],
                    start,
                    end,
                );
                line_entity(stamp_ns, frame_id, k, &f)
            }
            Observation::Point(p) => {
                let c = [
                    [f64::from(p.cov[0][0]), f64::from(p.cov[0][1])],
                    [f64::from(p.cov[1][0]), f64::from(p.cov[1][1])],
                ];
                let (x, y) = (f64::from(p.x), f64::from(p.y));
                let mut e = entity(
                    stamp_ns,
                    frame_id,
                    k,
                    &[
                        ("kind", "point".into()),
                        ("x_mm", p.x.to_string()),
                        ("y_mm", p.y.to_string()),
                    ],
                );
                e["lines"] = json!([line_primitive(
                    LINE_LOOP,
                    cov_ellipse(x, y, c, 3.0, 24),
                    0.01,
                    color(0.9, 0.2, 0.2, 0.9)
                )]);
                e
            }
        };
        e["id"] = json!(format!("map-{k}"));
        entities.push(e);
    }
    // The pose: its 3σ position ellipse and its heading ± 3σ (0.5 m rays).
    let (x, y, th) = (f64::from(pose.x), f64::from(pose.y), f64::from(pose.theta));
    let c = |i: usize, j: usize| f64::from(cov[i][j]);
    let cov_text: Vec<String> = cov.iter().flatten().map(|v| v.to_string()).collect();
    let mut e = entity(
        stamp_ns,
        frame_id,
        0,
        &[
            ("kind", "pose".into()),
            ("status", status.into()),
            ("x_mm", pose.x.to_string()),
            ("y_mm", pose.y.to_string()),
            ("theta_rad", pose.theta.to_string()),
            ("cov", cov_text.join(" ")),
        ],
    );
    e["id"] = json!("pose");
    let sth = 3.0 * c(2, 2).max(0.0).sqrt();
    let ray = |a: f64| point((x + 500.0 * a.cos()) * MM, (y + 500.0 * a.sin()) * MM);
    let mut lines = vec![line_primitive(
        LINE_STRIP,
        vec![ray(th - sth), point(x * MM, y * MM), ray(th + sth)],
        0.01,
        color(0.2, 0.9, 0.3, 1.0),
    )];
    let xy = [[c(0, 0), c(0, 1)], [c(1, 0), c(1, 1)]];
    if xy.iter().flatten().all(|v| v.is_finite()) {
        lines.push(line_primitive(
            LINE_LOOP,
            cov_ellipse(x, y, xy, 3.0, 36),
            0.01,
            color(0.2, 0.9, 0.3, 1.0),
        ));
    }
    e["lines"] = json!(lines);
    entities.push(e);
    json!({
        "deletions": [{ "timestamp": time(stamp_ns), "type": 1, "id": "" }],
        "entities": entities,
    })
}

fn frame_transform_schema() -> Vec<u8> {
    let mut s = object(
        Some("foxglove.FrameTransform"),
        json!({
            "timestamp": time_schema(),
            "parent_frame_id": { "type": "string" },
            "child_frame_id": { "type": "string" },
            "translation": vector3_schema(),
            "rotation": object(
                Some("foxglove.Quaternion"),
                json!({ "x": { "type": "number" }, "y": { "type": "number" }, "z": { "type": "number" }, "w": { "type": "number" } }),
            ),
        }),
    );
    s["description"] = json!("A transform between two reference frames in 3D space");
    s.to_string().into_bytes()
}

fn pose_in_frame_schema() -> Vec<u8> {
    let mut s = object(
        Some("foxglove.PoseInFrame"),
        json!({
            "timestamp": time_schema(),
            "frame_id": { "type": "string" },
            "pose": pose_schema(),
        }),
    );
    s["description"] = json!("A timestamped pose for an object or reference frame in 3D space");
    s.to_string().into_bytes()
}

fn poses_in_frame_schema() -> Vec<u8> {
    let mut s = object(
        Some("foxglove.PosesInFrame"),
        json!({
            "timestamp": time_schema(),
            "frame_id": { "type": "string" },
            "poses": array(pose_schema()),
        }),
    );
    s["description"] =
        json!("An array of timestamped poses for an object or reference frame in 3D space");
    s.to_string().into_bytes()
}

/// The frames: `foxglove.FrameTransform` on `/tf`.
pub const TF: Channel = Channel::new("/tf", "foxglove.FrameTransform", frame_transform_schema);
/// The odometry's pose: `foxglove.PoseInFrame` on `/odometry/pose`.
pub const POSE: Channel = Channel::new(
    "/odometry/pose",
    "foxglove.PoseInFrame",
    pose_in_frame_schema,
);
/// The odometry's trajectory: `foxglove.PosesInFrame` on `/odometry/trajectory`.
pub const TRAJECTORY: Channel = Channel::new(
    "/odometry/trajectory",
    "foxglove.PosesInFrame",
    poses_in_frame_schema,
);
/// The odometry's map and pose covariance: `foxglove.SceneUpdate` on `/odometry/map`.
pub const MAP: Channel = Channel::new("/odometry/map", "foxglove.SceneUpdate", scene_update_schema);
/// The log's own poses: `foxglove.PosesInFrame` on `/log/trajectory`.
pub const LOG_TRAJECTORY: Channel = Channel::new(
    "/log/trajectory",
    "foxglove.PosesInFrame",
    poses_in_frame_schema,
);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_yaw_is_a_unit_quaternion_about_z() {
        let t = frame_transform(7, "odom", "laser", (1000.0, -500.0, 1.2));
        assert_eq!(t["translation"]["x"], 1.0);
        assert_eq!(t["translation"]["y"], -0.5);
        let (z, w) = (
            t["rotation"]["z"].as_f64().unwrap(),
            t["rotation"]["w"].as_f64().unwrap(),
        );
        assert!((2.0 * z.atan2(w) - 1.2).abs() < 1e-12 && (z * z + w * w - 1.0).abs() < 1e-12);
    }

    #[test]
    fn thinning_keeps_both_ends_and_the_bound() {
        let poses: Vec<[f64; 3]> = (0..5000).map(|k| [k as f64, 0.0, 0.0]).collect();
        let t = thin(&poses, 1000);
        assert_eq!(t.len(), 1000);
        assert_eq!((t[0][0], t[999][0]), (0.0, 4999.0));
        assert_eq!(thin(&poses[..10], 1000).len(), 10);
    }
}
