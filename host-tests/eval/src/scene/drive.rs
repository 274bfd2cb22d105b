//! A robot driving through a simulated room: consecutive scans from known poses, for the pose
//! step on the board (`cargo xtask bench-mcu`'s pose scans, the end-to-end pose test).
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
    let shapes = room();
    (0..n)
        .map(|k| {
            let pose = pose(k);
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
