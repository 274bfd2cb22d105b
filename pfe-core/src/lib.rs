//! # pfe-core: prediction-based geometric feature extraction for 2D laser scans
//!
//! An implementation of Y. Zhao and X. Chen, "Prediction-based geometric feature extraction
//! for 2D laser scanner", *Robotics and Autonomous Systems* 59 (2011) 402–409, for
//! microcontrollers: `no_std`, no allocator, `f32`, fixed capacities, no panics.
//!
//! Data path (one module per step): [`scan`] (readings, [`correction`], [`deskew`]) →
//! [`predict`] (prediction point and threshold) → [`extract`] (mark, check step, segments,
//! typing) → [`mod@line`] and [`circle`] fits with covariance → [`feature`].
//!
//! ```
//! use pfe_core::{Config, Extractor, Scan, ScanGeometry};
//! let ranges = [3000.0_f32; 361]; // a round room of radius 3 m
//! let mut ex = Extractor::<361, 32>::new();
//! let stats = ex.extract(&Scan::from_mm(ScanGeometry::LMS200_180_050, &ranges), &Config::paper())?;
//! assert_eq!(stats.valid, 361);
//! # Ok::<(), pfe_core::ExtractError>(())
//! ```
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
pub use preprocess::deskew::Motion;
pub use scan::{Ranges, Scan, ScanGeometry, LMS_MAX_VALID_8M};
