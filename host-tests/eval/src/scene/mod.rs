//! Scene simulator with ground truth: 2D scenes of line segments and circles, an exact ray
//! caster and an LMS200 range model (Gaussian noise, optionally growing with the incidence
//! angle, optional systematic bias, 1 mm or 10 mm quantisation up to 8 m or 80 m, no-return
//! codes, optional mixed pixels). A moving scanner (constant forward speed and turn rate)
//! takes each beam at its real time: at 0.5° (0.25°) the LMS200 interleaves 2 (4) sweeps from
//! consecutive mirror turns ([`motion`]).
//!
//! Everything is deterministic from [`Scenario::seed`] (ChaCha8). The scanner frame is
//! pfe-core's: x forward, y left, bearings counter-clockwise, beam `i` at
//! `start + i · step`, ranges in mm. Ray casting runs in `f64`; outputs are `f32`/`u16` as
//! the extractors consume them.
//!
//! Ground truth: every beam records the primitive it hit (each wall segment, box side and
//! circle is its own primitive). A ground-truth feature is a maximal run of at least
//! [`MIN_RUN`] consecutive beams on one primitive, with that primitive's exact parameters in
//! the scanner frame; its first and last beams are true mark points.
//!
//! ```
//! use pfe_eval::scene::{Scenario, SceneKind};
//! let scan = Scenario::new(SceneKind::Office, 7).simulate();
//! assert_eq!(scan.ranges_mm.len(), 361);
//! assert!(scan.truth.iter().all(|f| f.last + 1 - f.first >= 4));
//! assert_eq!(scan.raw, Scenario::new(SceneKind::Office, 7).simulate().raw); // deterministic
//! ```
//!
//! Files by job: `vec2` maths, [`shape`] primitives and ray hits, [`raycast`] ray casting,
//! [`truth`] ground truth and Cramér–Rao bounds, [`range_model`] the LMS200 range model,
//! [`motion`] beam times and the moving scanner's pose, [`generate`] scene generators, [`drive`]
//! a robot driving through a room (consecutive scans from known poses), [`adversarial`] worst-case scans, [`scenario`] the recipe and the simulated scan, [`svg`] a
//! picture of it.

pub mod adversarial;
pub mod drive;
pub mod generate;
pub mod motion;
pub mod range_model;
pub mod raycast;
pub mod scenario;
pub mod shape;
pub mod svg;
pub mod truth;
pub(crate) mod vec2;

pub use generate::MIN_FORWARD_MM;
pub use motion::{pose_at, DEGREE_S, MIRROR_TURN_S};
pub use range_model::{render, systematic_bias_mm, BIAS_AMPLITUDE_MM, NO_RETURN_CODE};
pub use raycast::{bearing, cast, cast_moving, Hit};
pub use scenario::{
    incidence_noise_factor, RangeMode, Resolution, Scenario, SceneKind, SimScan, INCIDENCE_NOISE_C,
    INCIDENCE_NOISE_CAP,
};
pub use shape::Shape;
pub use truth::{crb, Crb, TruthFeature, TruthKind, MIN_RUN};
