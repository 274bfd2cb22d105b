#![doc = include_str!("../README.md")]
//!
//! ## Inside the crate
//!
//! The paper's steps and ours, in the order [`Extractor::extract`] runs them, and where each
//! lives:
//!
//! | step | paper | module |
//! |---|---|---|
//! | readings to points: range correction, de-skew | §2 | `preprocess`, with the scanner's models [`correction`], [`motion`] |
//! | the scan's own σ, where it scatters well beyond σ_r ([`Config::scrutiny`]) | ours | `preprocess::scatter` |
//! | mark points by prediction: the paper's threshold, or the default mode's walk with boundary refinement and arc continuation | §3.1–3.2, §3.6 | [`predict`], `mark` (`paper`, `noise`, `refine`, `arc`) |
//! | interleaved sweeps out of place moved onto sweep 0 and marked again | ours | `sweeps` |
//! | check step | §3.3 | `check` |
//! | segments and pairing, arc merges (`arc`) | §3.4 | `segment` |
//! | type of each segment, its covariance | §3.5 | `classify` |
//! | line and circle fits with covariance | §3.5 | [`fit::line`], [`fit::circle`] |
//! | the features inherit the sweep offsets' error | ours | `sweeps` |
//! | line ends over the beams beside them that lie on them ([`Config::scrutiny`]) | ours | `reach` |
//! | no line the scanner cannot see; small objects ([`ObjectFeature`]) ([`Config::scrutiny`]) | ours | `sift` |
//! | output | | [`feature`], [`Stats`] |
//!
//! A module imports only modules below it: the steps import none of each other (but `segment`
//! calls `classify` for each segment), and the shared vocabulary lies below every step: the
//! rules (`rule`), the work state (`pass`), statistics and sinks (`output`), the configuration,
//! flags, geometry and maths. [`Extractor`] owns the beam table (what depends on the geometry
//! only), the work buffers of one scan and the output; every step is a function of slices, not
//! generic over the capacities, so it is compiled once, in this crate. [`config`] holds the two
//! named configurations, [`error`] the errors, [`geometry`] the shared plane geometry.
//! [`interleave::detect`] tells from a scan's ranges alone whether it is made of 2 or 4
//! interleaved sweeps, for a caller that does not know its scanner (the extractor does not
//! call it: [`Scan::sweeps`] says what to align).
#![no_std]
// One audited exception: `math::sqrt`'s `vsqrt.f32` on hard-float Arm.
#![deny(unsafe_code)]
#![deny(missing_docs)]
// Beyond the workspace lints: no indexing that can panic in the library.
#![deny(clippy::indexing_slicing)]
// `!(x > 0.0)` is deliberate throughout: it is true for NaN, which must be rejected too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

// Only for the square root of the loops meant to vectorise (`math::sqrt_lanes`), with the
// `std` feature.
#[cfg(feature = "std")]
extern crate std;

mod arc;
mod beams;
mod check;
mod classify;
pub mod config;
pub mod correction;
pub mod error;
mod extractor;
pub mod feature;
pub mod fit;
mod flags;
pub mod geometry;
pub mod interleave;
mod mark;
mod math;
pub mod motion;
mod output;
mod pass;
pub mod predict;
#[cfg(feature = "internals")]
pub mod preprocess;
#[cfg(not(feature = "internals"))]
mod preprocess;
mod reach;
mod rule;
pub mod scan;
mod segment;
mod sift;
#[cfg(feature = "internals")]
pub mod sweeps;
#[cfg(not(feature = "internals"))]
mod sweeps;

pub use config::{Config, NoiseModel, Threshold, Typing, NP};
pub use correction::RangeCorrection;
pub use error::{ExtractError, FitError};
pub use extractor::Extractor;
pub use feature::{
    circle_feature, line_feature, CircleFeature, Feature, LineFeature, ObjectFeature,
};
pub use fit::circle::{
    circle_covariance, circle_covariance_range, fit_circle, refine_circle, Circle, CircleMethod,
};
pub use fit::line::{fit_line, LineCovariance, LineFit};
pub use geometry::Point;
pub use math::sin_cos_f32;
pub use motion::{BeamTiming, Motion};
pub use output::{Stage, StageObserver, Stats};
pub use scan::{Ranges, Scan, ScanGeometry, LMS_MAX_VALID_8M};
