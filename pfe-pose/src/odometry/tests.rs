//! Tests of the odometry: the map kept, the heading from the lines, corridors.

use super::*;

const COV: [[f32; 2]; 2] = [[1e-6, 0.0], [0.0, 25.0]];

/// The lines (α, ρ) of the odometry frame as seen from `pose`.
fn seen_from<const N: usize>(walls: &[(f32, f32); N], pose: Pose) -> [Observation; N] {
    let inv = pose.inverse();
    walls.map(|(a, r)| {
        let (a, r) = inv.transform_line(a, r);
        Observation::Line(LineObs::new(a, r, COV))
    })
}

/// A scan that nothing registers (no features) keeps the map: the next scan re-localises
/// against it (the map used to restart from the empty scan, and the next scan had nothing
/// to register against).
#[test]
fn map_kept_through_a_scan_without_features() {
    let walls = [
        (0.0f32, 3000.0f32),
        (core::f32::consts::FRAC_PI_2, 2000.0),
        (core::f32::consts::PI, 1500.0),
        (-core::f32::consts::FRAC_PI_2, 2500.0),
    ];
    let mut odo = Odometry::<32>::new(Config::default());
    odo.update(&seen_from(&walls, Pose::IDENTITY), None);
    odo.update(&seen_from(&walls, Pose::new(200.0, 0.0, 0.05)), None);
    let lost = odo.update(&[], None);
    assert!(matches!(lost.status, Status::None(_)), "{:?}", lost.status);
    let truth = Pose::new(600.0, 0.0, 0.15);
    let step = odo.update(&seen_from(&walls, truth), None);
    assert_eq!(step.status, Status::Ok);
    let e = crate::geom::hypot(step.pose.x - truth.x, step.pose.y - truth.y);
    assert!(e < 5.0, "{:?}", step.pose);
    assert!(
        (step.pose.theta - truth.theta).abs() < 1e-3,
        "{:?}",
        step.pose
    );
}

/// A scan that cannot be registered (two parallel walls after a room's four) still tells
/// the heading: the last motion again, turned by what its lines say, with the heading's
/// variance measured and the translation's the motion bounds.
#[test]
fn heading_from_the_lines_of_an_unregistered_scan() {
    let walls = [
        (0.0f32, 3000.0f32),
        (core::f32::consts::FRAC_PI_2, 2000.0),
        (core::f32::consts::PI, 1500.0),
        (-core::f32::consts::FRAC_PI_2, 2500.0),
    ];
    let mut odo = Odometry::<32>::new(Config::default());
    odo.update(&seen_from(&walls, Pose::IDENTITY), None);
    odo.update(&seen_from(&walls, Pose::new(200.0, 0.0, 0.0)), None);
    let truth = Pose::new(400.0, 0.0, 0.15);
    let [_, left, _, right] = seen_from(&walls, truth);
    let step = odo.update(&[left, right], None);
    assert!(matches!(step.status, Status::None(_)), "{:?}", step.status);
    assert!(
        (step.pose.theta - truth.theta).abs() < 0.005,
        "{:?}",
        step.pose
    );
    assert!(step.rel_cov[2][2] < 0.02 * 0.02, "{:?}", step.rel_cov);
    assert!(step.rel_cov[0][0] >= 1e6, "{:?}", step.rel_cov);
}

/// Down a corridor whose end wall has gone out of sight, the scene tells nothing along it:
/// the odometry keeps the last motion along it (it used to take "no motion") and says
/// degenerate, with the unobservable variance along the corridor: with two walls through
/// the pair's registration (the first scan without the end is not registered), with three
/// through the tracking against the map.
#[test]
fn corridor_keeps_the_last_motion_along_it() {
    use core::f32::consts::FRAC_PI_2;
    corridor([(FRAC_PI_2, 1500.0), (-FRAC_PI_2, 1500.0)], false, 0.0);
    corridor(
        [
            (FRAC_PI_2, 1500.0),
            (-FRAC_PI_2, 1500.0),
            (FRAC_PI_2, 3000.0),
        ],
        true,
        0.0,
    );
}

/// Issue 40: the same corridor seen at a heading tilted from the scanner's axes, so that the
/// unobservable direction enters every entry of the covariance; the odometry must not take
/// the degenerate pair's sentinel as a finite prior.
#[test]
fn tilted_corridor_keeps_the_last_motion_along_it() {
    use core::f32::consts::FRAC_PI_2;
    for heading in [0.5, -0.5] {
        corridor([(FRAC_PI_2, 1500.0), (-FRAC_PI_2, 1500.0)], false, heading);
        corridor(
            [
                (FRAC_PI_2, 1500.0),
                (-FRAC_PI_2, 1500.0),
                (FRAC_PI_2, 3000.0),
            ],
            true,
            heading,
        );
    }
}

fn corridor<const N: usize>(side: [(f32, f32); N], tracked: bool, heading: f32) {
    let mut odo = Odometry::<32>::new(Config::default());
    let start = Pose::new(0.0, 0.0, heading);
    // Along the corridor in the first scan's frame.
    let (s, c) = (heading.sin(), heading.cos());
    let along = [c, -s];
    for k in 0..3 {
        // The end wall and a pillar near it fix the position along the corridor (two
        // features: the direction is confirmed).
        let pose = Pose::new(300.0 * k as f32, 0.0, heading);
        let [end] = seen_from(&[(0.0, 6000.0)], pose);
        let p = pose.inverse().transform_point([5000.0, 1000.0]);
        let pillar = Observation::Point(PointObs::new(p[0], p[1], [[25.0, 0.0], [0.0, 25.0]]));
        let walls = seen_from(&side, pose);
        let mut obs = [end; 8];
        for (o, s) in obs.iter_mut().zip(walls.iter().chain([&end, &pillar])) {
            *o = *s;
        }
        let step = odo.update(obs.get(..N + 2).unwrap_or(&[]), None);
        assert_eq!(step.status, Status::Ok, "{N} walls, scan {k}");
    }
    for k in 3..8 {
        let truth = start
            .inverse()
            .compose(&Pose::new(300.0 * k as f32, 0.0, heading));
        let step = odo.update(
            &seen_from(&side, Pose::new(300.0 * k as f32, 0.0, heading)),
            None,
        );
        // With two walls, scan 3, the first without the end, is not registered (its two
        // walls against the previous scan's four features: too few matches, and not a
        // corridor on both sides): the prediction, the last motion again.
        let expected = match step.status {
            Status::Degenerate { direction } => {
                (tracked || k > 3)
                    && (direction[0] * along[0] + direction[1] * along[1]).abs() > 0.99
            }
            Status::None(_) => !tracked && k == 3,
            Status::Ok => false,
        };
        assert!(expected, "{N} walls, scan {k}: {:?}", step.status);
        let rel_along = step.rel.x * along[0] + step.rel.y * along[1];
        assert!((rel_along - 300.0).abs() < 1.0, "scan {k}: {:?}", step.rel);
        assert!(
            crate::geom::hypot(step.pose.x - truth.x, step.pose.y - truth.y) < 5.0,
            "scan {k}: {:?} vs {truth:?}",
            step.pose
        );
        assert!(step.pose.theta.abs() < 1e-3, "{:?}", step.pose);
        // Unobservable along the corridor (the last motion is a guess, not a measurement);
        // the scan without any registration has the motion bounds as its covariance.
        let floor = if matches!(step.status, Status::None(_)) {
            1e6
        } else {
            0.1 * crate::UNOBSERVABLE_VARIANCE
        };
        let c = step.rel_cov;
        let var = along[0] * along[0] * c[0][0]
            + 2.0 * along[0] * along[1] * c[0][1]
            + along[1] * along[1] * c[1][1];
        assert!(var >= floor, "{N} walls, scan {k}: {:?}", step.rel_cov);
    }
}
