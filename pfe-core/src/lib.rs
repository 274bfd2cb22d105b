#![doc = include_str!("../README.md")]
//!
//! ## Inside the crate
//!
//! The paper's steps, in the order [`Extractor::extract`] runs them, and where each lives:
//!
//! | step | paper | module |
//! |---|---|---|
//! | readings and beam geometry | | [`scan`] |
//! | readings to points: range correction, de-skew, interleaved sweeps | §2 | [`preprocess`] ([`preprocess::correction`], [`preprocess::deskew`], [`preprocess::sweeps`]) |
//! | prediction point and its error | §3.1 | [`predict`] |
//! | mark points: the paper's threshold, or the default mode's walk with boundary refinement | §3.2, §3.6 | `mark` (`paper`, `noise`, `refine`) |
//! | check step and pairing | §3.3 | `check` |
//! | segments (and arc merges) | §3.4 | `segment` |
//! | type of a segment (and the arc tests) | §3.5 | `classify` (`arc`) |
//! | line and circle fits with covariance | §3.5 | [`fit::line`], [`fit::circle`] |
//! | line ends over the beams beside them that lie on them | | `reach` |
//! | output | | [`feature`] |
//!
//! [`Extractor`] owns the beam table (what depends on the geometry only), the work buffers of
//! one scan and the output; every step is a function of slices, not generic over the
//! capacities, so it is compiled once, in this crate. [`config`] holds the two named
//! configurations, [`error`] the errors, [`geometry`] the shared plane geometry.
#![no_std]
// One audited exception: `math::sqrt`'s `vsqrt.f32` on hard-float Arm.
#![deny(unsafe_code)]
#![deny(missing_docs)]
// `!(x > 0.0)` is deliberate throughout: it is true for NaN, which must be rejected too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod beams;
mod check;
mod classify;
pub mod config;
pub mod error;
mod extractor;
pub mod feature;
pub mod fit;
mod flags;
pub mod geometry;
mod mark;
mod math;
mod pass;
pub mod predict;
pub mod preprocess;
mod reach;
pub mod scan;
mod segment;

pub use config::{Config, NoiseModel, Threshold, Typing, NP};
pub use error::{ExtractError, FitError};
pub use extractor::{Extractor, Stats};
pub use feature::{circle_feature, line_feature, CircleFeature, Feature, LineFeature};
pub use fit::circle::{
    circle_covariance, circle_covariance_range, fit_circle, refine_circle, Circle, CircleMethod,
};
pub use fit::line::{fit_line, LineCovariance, LineFit};
pub use geometry::Point;
pub use preprocess::correction::RangeCorrection;
pub use preprocess::deskew::{BeamTiming, Motion};
pub use preprocess::sweeps::SweepOffset;
pub use scan::{Ranges, Scan, ScanGeometry, LMS_MAX_VALID_8M};
