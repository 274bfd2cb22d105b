//! The odometry's search of the map (when neither the tracking nor the pair registers a scan)
//! held to the scans' points: ranges ray-cast in a room from known poses.

use pfe_core::ScanGeometry;
use pfe_pose::points::{RangeScan, SCAN_BEAMS};
use pfe_pose::{wrap, LineObs, Observation, PointOdometry, Pose, Status};

mod common;
use common::{Rng, ROOM};

const GEOMETRY: ScanGeometry = ScanGeometry::LMS200_180_050;

/// Wall `k` of the room ([`common::ROOM`]), its ends in mm.
fn wall(k: usize) -> ([f64; 2], [f64; 2]) {
    let corner = |i: usize| ROOM[i % ROOM.len()].map(f64::from);
    (corner(k), corner(k + 1))
}

/// The ranges (mm, 10 mm noise) of a scanner at `pose` in the room.
fn ranges(pose: &Pose, rng: &mut Rng) -> Box<RangeScan<SCAN_BEAMS>> {
    let (px, py, pt) = (f64::from(pose.x), f64::from(pose.y), f64::from(pose.theta));
    let r: Vec<f32> = (0..361)
        .map(|i| {
            let b = pt + f64::from(GEOMETRY.bearing(i));
            let d = [b.cos(), b.sin()];
            let mut best = f64::INFINITY;
            for k in 0..ROOM.len() {
                let (s, e) = wall(k);
                let w = [e[0] - s[0], e[1] - s[1]];
                let den = d[0] * w[1] - d[1] * w[0];
                if den.abs() < 1e-12 {
                    continue;
                }
                let o = [s[0] - px, s[1] - py];
                let t = (o[0] * w[1] - o[1] * w[0]) / den;
                let u = (o[0] * d[1] - o[1] * d[0]) / den;
                if t > 0.0 && (0.0..=1.0).contains(&u) {
                    best = best.min(t);
                }
            }
            (best + 10.0 * rng.normal()) as f32
        })
        .collect();
    let mut s = Box::new(RangeScan::new());
    assert!(s.set(GEOMETRY.start_angle, GEOMETRY.angle_step, &r));
    s
}

/// The walls `walls` as line features seen from `pose` (σ 1 mrad and 10 mm).
fn lines(walls: &[usize], pose: &Pose) -> Vec<Observation> {
    let inv = pose.inverse();
    walls
        .iter()
        .map(|&k| {
            let (s, e) = wall(k);
            let a = (e[1] - s[1]).atan2(e[0] - s[0]) + std::f64::consts::FRAC_PI_2;
            let r = s[0] * a.cos() + s[1] * a.sin();
            let (a, r) = inv.transform_line(a as f32, r as f32);
            Observation::Line(LineObs::new(a, r, [[1e-6, 0.0], [0.0, 100.0]]))
        })
        .collect()
}

/// A sudden turn of 1 rad that neither the tracking nor the pair registers (the previous scan
/// saw other walls; the points' ICP does not reach so far a turn), and features that match the
/// map at a pose 0.8 m to the side of the truth (a wrong association): the map's search finds
/// that pose, the points contradict it, and it is not reported "ok" (it was before the map's
/// answer was held to the points).
#[test]
fn a_map_answer_the_points_contradict_is_not_ok() {
    let mut rng = Rng(40);
    let mut odo = Box::new(PointOdometry::new_default());
    let all = [0, 1, 2, 3, 4, 5, 6];
    let p0 = Pose::IDENTITY;
    odo.update_with_points(&lines(&all, &p0), &ranges(&p0, &mut rng), None);
    // Seen again with three walls only: tracked against the map, which keeps all seven.
    let p1 = Pose::new(150.0, 0.0, 0.02);
    let s1 = odo.update_with_points(&lines(&[0, 1, 2], &p1), &ranges(&p1, &mut rng), None);
    assert_eq!(s1.status, Status::Ok);
    let truth = p1.compose(&Pose::new(300.0, 100.0, 1.0));
    let wrong = truth.compose(&Pose::new(0.0, 800.0, 0.0));
    let step = odo.update_with_points(
        &lines(&[3, 4, 5, 6], &wrong),
        &ranges(&truth, &mut rng),
        None,
    );
    let e = (step.pose.x - truth.x).hypot(step.pose.y - truth.y);
    let et = wrap(step.pose.theta - truth.theta).abs();
    assert!(
        !(matches!(step.status, Status::Ok) && (e > 200.0 || et > 0.087)),
        "{:?} {:?}: {e} mm, {et} rad off",
        step.status,
        step.pose
    );
}

/// The same turn with the features seen from the truth: the map's search finds it, the points
/// agree, and it is taken ("ok", within 50 mm and 0.01 rad).
#[test]
fn a_map_answer_the_points_confirm_is_taken() {
    let mut rng = Rng(41);
    let mut odo = Box::new(PointOdometry::new_default());
    let p0 = Pose::IDENTITY;
    odo.update_with_points(
        &lines(&[0, 1, 2, 3, 4, 5, 6], &p0),
        &ranges(&p0, &mut rng),
        None,
    );
    let p1 = Pose::new(150.0, 0.0, 0.02);
    odo.update_with_points(&lines(&[0, 1, 2], &p1), &ranges(&p1, &mut rng), None);
    let truth = p1.compose(&Pose::new(300.0, 100.0, 1.0));
    let step = odo.update_with_points(
        &lines(&[3, 4, 5, 6], &truth),
        &ranges(&truth, &mut rng),
        None,
    );
    let e = (step.pose.x - truth.x).hypot(step.pose.y - truth.y);
    let et = wrap(step.pose.theta - truth.theta).abs();
    assert_eq!(step.status, Status::Ok);
    assert!(
        e < 50.0 && et < 0.01,
        "{:?}: {e} mm, {et} rad off",
        step.pose
    );
}
