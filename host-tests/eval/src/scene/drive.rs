//! A robot driving through a simulated room or corridor: consecutive scans from known poses,
//! for the pose step on the board (`cargo xtask bench-mcu`'s pose scans, the end-to-end pose
//! test) and the pose's tests against exact truth, with wheel odometry that drifts
//! ([`wheel_odometry`]).
//!
//! The room (10 m × 7 m, a chamfered corner, a box in the middle, a shelf and four pillars) is
//! fixed; the robot drives an ellipse around the box (5 m × 3 m, heading along the path), a
//! loop in [`LOOP`] scans (about 100 mm and 0.05 rad apart), standing still during each scan.
//! Each scan is rendered by [`render`] with a [`Scenario`]'s range model (σ_r = 5 mm, mm
//! mode up to 8 m, 0.5°), its noise seeded per scan.
//!
//! ```
//! use pfe_eval::scene::drive;
//! let d = drive::room_drive(3, 1);
//! assert_eq!(d.len(), 3);
//! assert_eq!(d[0].scan.raw.len(), 361);
//! let step = ((d[1].pose[0] - d[0].pose[0]).powi(2) + (d[1].pose[1] - d[0].pose[1]).powi(2)).sqrt();
//! assert!(step > 50.0 && step < 150.0, "{step}");
//! ```

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::range_model::render;
use super::{Scenario, SceneKind, Shape, SimScan};

/// Scans in one loop around the room.
pub const LOOP: usize = 128;

/// One scan of the drive.
#[derive(Clone, Debug)]
pub struct DriveScan {
    /// The scanner's pose in the room, `[x mm, y mm, θ rad]`.
    pub pose: [f64; 3],
    /// The scan taken there, with its ground truth in the scanner frame.
    pub scan: SimScan,
}

/// The room, in room coordinates (mm).
pub fn room() -> Vec<Shape> {
    let seg = |a: [f64; 2], b: [f64; 2]| Shape::Segment { a, b };
    let circle = |x: f64, y: f64, radius: f64| Shape::Circle {
        center: [x, y],
        radius,
    };
    vec![
        seg([0.0, 0.0], [10_000.0, 0.0]),
        seg([10_000.0, 0.0], [10_000.0, 6_000.0]),
        seg([10_000.0, 6_000.0], [9_000.0, 7_000.0]),
        seg([9_000.0, 7_000.0], [0.0, 7_000.0]),
        seg([0.0, 7_000.0], [0.0, 0.0]),
        // The box in the middle.
        seg([4_600.0, 3_200.0], [5_400.0, 3_200.0]),
        seg([5_400.0, 3_200.0], [5_400.0, 3_800.0]),
        seg([5_400.0, 3_800.0], [4_600.0, 3_800.0]),
        seg([4_600.0, 3_800.0], [4_600.0, 3_200.0]),
        // A shelf along the top wall.
        seg([6_000.0, 6_300.0], [8_000.0, 6_300.0]),
        circle(1_200.0, 1_200.0, 150.0),
        circle(8_800.0, 1_200.0, 120.0),
        circle(1_500.0, 5_500.0, 250.0),
        circle(7_800.0, 4_900.0, 100.0),
    ]
}

/// The pose of scan `k` on the loop: the ellipse about (5000, 3500) mm with half-axes 2500
/// and 1500 mm, counter-clockwise, heading along the path.
pub fn pose(k: usize) -> [f64; 3] {
    let t = std::f64::consts::TAU * k as f64 / LOOP as f64;
    let (s, c) = t.sin_cos();
    let (ax, ay) = (2_500.0, 1_500.0);
    let heading = (ay * c).atan2(-ax * s);
    [5_000.0 + ax * c, 3_500.0 + ay * s, heading]
}

/// `n` consecutive scans of the drive, the noise of scan `k` seeded with `seed + k`.
pub fn room_drive(n: usize, seed: u64) -> Vec<DriveScan> {
    let poses: Vec<[f64; 3]> = (0..n).map(pose).collect();
    drive(&room(), &poses, seed)
}

/// The scans taken at `poses` among `shapes` (room coordinates), the noise of scan `k`
/// seeded with `seed + k`.
pub fn drive(shapes: &[Shape], poses: &[[f64; 3]], seed: u64) -> Vec<DriveScan> {
    poses
        .iter()
        .enumerate()
        .map(|(k, &pose)| {
            let scenario = Scenario::new(SceneKind::Office, seed + k as u64);
            let local: Vec<Shape> = shapes.iter().map(|s| s.to_frame(pose)).collect();
            let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_mul(1_000_003) + k as u64);
            DriveScan {
                pose,
                scan: render(&local, &scenario, &mut rng),
            }
        })
        .collect()
}

/// A corridor 2 m wide and 60 m long along x, its walls at y = ±1000 mm and nothing else:
/// within the scanner's 8 m every scan sees two parallel walls, so its position along the
/// corridor cannot be told.
pub fn corridor() -> Vec<Shape> {
    vec![
        Shape::Segment {
            a: [-30_000.0, -1_000.0],
            b: [30_000.0, -1_000.0],
        },
        Shape::Segment {
            a: [-30_000.0, 1_000.0],
            b: [30_000.0, 1_000.0],
        },
    ]
}

/// The pose of scan `k` in the corridor: 150 mm a scan along it from x = −10 m, weaving
/// (±300 mm across, the heading following the path).
pub fn corridor_pose(k: usize) -> [f64; 3] {
    let x = -10_000.0 + 150.0 * k as f64;
    let w = std::f64::consts::TAU / 40.0;
    let y = 300.0 * (w * k as f64).sin();
    let slope = 300.0 * w * (w * k as f64).cos() / 150.0;
    [x, y, slope.atan()]
}

/// `n` consecutive scans of the corridor drive ([`corridor_pose`]).
pub fn corridor_drive(n: usize, seed: u64) -> Vec<DriveScan> {
    let poses: Vec<[f64; 3]> = (0..n).map(corridor_pose).collect();
    drive(&corridor(), &poses, seed)
}

/// The motion from pose `a` to pose `b`, `[x mm, y mm, θ rad]` in `a`'s frame.
pub fn relative(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    let (s, c) = a[2].sin_cos();
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let mut dth = (b[2] - a[2]).rem_euclid(std::f64::consts::TAU);
    if dth > std::f64::consts::PI {
        dth -= std::f64::consts::TAU;
    }
    [c * dx + s * dy, -s * dx + c * dy, dth]
}

/// Wheel odometry that drifts: the motion from `a` to `b` as a differential-drive robot's
/// encoders report it, with a 3 % scale error on the distance and a 0.02 rad/m heading bias
/// (a wheel radius off), plus white noise of σ = 10 mm + 2 % per axis and 0.005 rad + 2 % of
/// the turn (seeded with `seed`). Returns the motion and the covariance a robot would state
/// for it: σ = 20 mm + 5 % of the distance per axis, 0.01 rad + 5 % of the turn + 0.03 rad
/// per metre, which covers the drift.
pub fn wheel_odometry(a: [f64; 3], b: [f64; 3], seed: u64) -> ([f64; 3], [[f64; 3]; 3]) {
    use rand_distr::Distribution as _;
    let t = relative(a, b);
    let d = t[0].hypot(t[1]);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut n = || -> f64 { rand_distr::StandardNormal.sample(&mut rng) };
    let sxy = 10.0 + 0.02 * d;
    let sth = 0.005 + 0.02 * t[2].abs();
    let m = [
        1.03 * t[0] + sxy * n(),
        1.03 * t[1] + sxy * n(),
        t[2] + 0.02 * d / 1000.0 + sth * n(),
    ];
    let cxy = (20.0 + 0.05 * d).powi(2);
    let cth = (0.01 + 0.05 * t[2].abs() + 0.03 * d / 1000.0).powi(2);
    (m, [[cxy, 0.0, 0.0], [0.0, cxy, 0.0], [0.0, 0.0, cth]])
}
