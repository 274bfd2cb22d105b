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
    /// The configuration is unusable (a non-finite or non-positive parameter, or `scrutiny` on
    /// in a build without the `scrutiny` feature).
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

#[cfg(test)]
mod tests {
    use super::*;
    use core::fmt::Write;

    /// The message of `e`.
    fn text(e: &dyn fmt::Display) -> heapless::String<96> {
        let mut s = heapless::String::new();
        // 96 bytes hold every message below.
        let _ = write!(s, "{e}");
        s
    }

    #[test]
    fn every_error_says_what_went_wrong() {
        let cases: [(&dyn fmt::Display, &str); 7] = [
            (
                &FitError::TooFewPoints { got: 2, need: 3 },
                "too few points for the fit: 2 < 3",
            ),
            (&FitError::NonFinite, "a point is not finite"),
            (
                &FitError::Degenerate,
                "degenerate point set: the fit is undetermined",
            ),
            (
                &ExtractError::TooManyReadings {
                    got: 800,
                    capacity: 721,
                },
                "scan has 800 readings, capacity is 721",
            ),
            (&ExtractError::InvalidGeometry, "invalid scan geometry"),
            (
                &ExtractError::InvalidConfig,
                "invalid extractor configuration",
            ),
            (
                &ExtractError::FeatureCapacity { dropped: 3 },
                "feature buffer full: 3 features dropped",
            ),
        ];
        for (e, want) in cases {
            assert_eq!(text(e).as_str(), want);
        }
    }
}
