//! # pfe-pose: the robot's motion from pfe-core's features
//!
//! Scan registration and feature odometry for 2D laser scans on a microcontroller: `no_std`,
//! no allocator, `f32`, fixed capacities, no panics. It takes the lines and circles that
//! [`pfe_core::Extractor`] finds, with their covariances, and returns the motion between two
//! scans with its 3×3 covariance and an honest status:
//!
//! - [`register()`]: the pose of the current scan in the previous scan's frame, with no first
//!   guess needed (hypotheses from pairs of lines and of points, consensus, weighted least
//!   squares; see [the `register` module](mod@crate::register) for the method), optionally gated by
//!   a prior (wheel odometry, a gyro) that also enters the least squares.
//! - [`Status::Degenerate`] when the scene cannot tell a direction (a corridor): the
//!   covariance along it is the prior's or [`UNOBSERVABLE_VARIANCE`]; [`Status::None`] when
//!   there is no registration.
//! - [`Odometry`]: every scan's pose in the first scan's frame, registered against a small
//!   local map of features.
//!
//! Conventions: x forward, y left, angles counter-clockwise, lengths in mm, angles in rad. A
//! line is pfe-core's `x cos α + y sin α = ρ` with ρ ≥ 0. A pose (x, y, θ) of frame B in frame
//! A maps B's point p to `R(θ) p + (x, y)` and B's line (α, ρ) to
//! `(α + θ, ρ + x cos(α + θ) + y sin(α + θ))` ([`Pose::transform_line`]).
//!
//! ```
//! use pfe_core::{Config, Extractor, Scan, ScanGeometry};
//! use pfe_pose::{register, Observation};
//! // A square room 6 m wide, seen from its centre and from 0.4 m to the left.
//! let room = |dy: f32| -> Vec<f32> {
//!     (0..361).map(|i| {
//!         let b = (-90.0 + 0.5 * i as f32).to_radians();
//!         let (s, c) = b.sin_cos();
//!         let mut r = f32::INFINITY;
//!         if c > 1e-6 { r = r.min(3000.0 / c); }
//!         if s > 1e-6 { r = r.min((3000.0 - dy) / s); }
//!         if s < -1e-6 { r = r.min((-3000.0 - dy) / s); }
//!         r
//!     }).collect()
//! };
//! let features = |ranges: &[f32]| -> Vec<Observation> {
//!     let mut ex = Extractor::<361, 32>::new();
//!     ex.extract(&Scan::from_mm(ScanGeometry::LMS200_180_050, ranges), &Config::default().with_sigma_r(10.0)).ok();
//!     ex.features().iter().filter_map(Observation::from_feature).collect()
//! };
//! let reg = register(&features(&room(0.0)), &features(&room(400.0)), None);
//! assert!(reg.is_registered());
//! assert!((reg.rel.y - 400.0).abs() < 30.0 && reg.rel.x.abs() < 30.0);
//! ```
#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
// `!(x > 0.0)` is deliberate: it is true for NaN, which must be rejected too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// 3×3 matrix algebra reads best with row and column indices (all over fixed arrays).
#![allow(clippy::needless_range_loop)]

mod geom;
mod obs;
mod odometry;
pub mod points;
pub mod register;
mod set;

pub use geom::{compose_covariance, wrap, Cov3, Pose};
pub use obs::{LineObs, Observation, PointObs};
pub use odometry::{FeatureOdometry, Odometry, PointOdometry, Step, ODOMETRY_MAP};
pub use register::{
    register, register_with, Config, Failure, Registration, Status, ROTATION_SCALE,
    UNOBSERVABLE_VARIANCE,
};
pub use set::MAX_OBS;
