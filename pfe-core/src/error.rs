//! Errors as values: nothing in this crate panics.

use core::fmt;

/// Why a fit could not be made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum FitError {
    /// Fewer points than the model needs.
    TooFewPoints {
        /// Points given.
        got: usize,
        /// Points needed.
        need: usize,
    },
    /// A point was NaN or infinite.
    NonFinite,
    /// The points do not determine the model (all equal, collinear for a circle, singular system).
    Degenerate,
}

impl fmt::Display for FitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FitError::TooFewPoints { got, need } => {
                write!(f, "too few points for the fit: {got} < {need}")
            }
            FitError::NonFinite => f.write_str("a point is not finite"),
            FitError::Degenerate => f.write_str("degenerate point set: the fit is undetermined"),
        }
    }
}

impl core::error::Error for FitError {}

/// Why an extraction did not complete normally. The features found before the problem stay
/// readable from the extractor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ExtractError {
    /// The scan has more readings than the extractor's capacity `N`; nothing was extracted.
    TooManyReadings {
        /// Readings given.
        got: usize,
        /// Capacity.
        capacity: usize,
    },
    /// The scan geometry is unusable (non-finite or zero angular step, r_max ≤ 0).
    InvalidGeometry,
    /// The configuration is unusable (a non-finite or non-positive parameter).
    InvalidConfig,
    /// More features than the capacity `M`: the first `M` are kept, `dropped` were not stored.
    FeatureCapacity {
        /// Features that did not fit.
        dropped: usize,
    },
}

impl fmt::Display for ExtractError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ExtractError::TooManyReadings { got, capacity } => {
                write!(f, "scan has {got} readings, capacity is {capacity}")
            }
            ExtractError::InvalidGeometry => f.write_str("invalid scan geometry"),
            ExtractError::InvalidConfig => f.write_str("invalid extractor configuration"),
            ExtractError::FeatureCapacity { dropped } => {
                write!(f, "feature buffer full: {dropped} features dropped")
            }
        }
    }
}

impl core::error::Error for ExtractError {}
