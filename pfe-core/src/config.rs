//! The two named configurations, `paper` and `default`, and every knob of the method.

use crate::correction::RangeCorrection;
use crate::fit::circle::CircleMethod;
use crate::math;

/// How the mark-point threshold is computed.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Threshold {
    /// Paper §3.6: `d_m = (d_0/λ)(r/r_max + (π − ϕ)/π)`.
    Paper {
        /// d_0, mm (paper: 50).
        d0: f32,
        /// λ (paper: 2).
        lambda: f32,
    },
    /// From the range noise and the prediction's geometry (default mode, see [`NoiseModel`]).
    Noise(NoiseModel),
}

/// The default mode's mark-point test. A point is a mark when its prediction error exceeds
/// `k · σ_r · f + floor`, `f` the prediction's standard deviation in units of σ_r
/// ([`crate::predict::Prediction::sigma_factor`]), or when it is farther from its predecessor
/// than any surface seen at ≥ 10° incidence allows. Predictions use up to `window` points of
/// the current segment only (never a window straddling a boundary).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NoiseModel {
    /// Detection level, in standard deviations of the prediction error.
    pub k: f32,
    /// Boundary localisation level: after a detection, the preceding points that already
    /// deviate by more than this (same side, from the line before them) move to the new segment.
    pub k_locate: f32,
    /// Constant allowance, mm (quantisation, small systematic errors).
    pub floor: f32,
    /// Points in the prediction window (the paper uses 3; more averages the noise down).
    pub window: usize,
    /// The window grows up to this many points until it spans `min_span · σ_r`.
    pub max_window: usize,
    /// Smallest span of the prediction window, in units of σ_r.
    pub min_span: f32,
    /// Arc continuation: when the line prediction fails, the last `arc_window` points of the
    /// segment are fitted with a circle; if it explains them significantly better than a line
    /// and predicts the point, the point continues the arc. 0 disables it.
    pub arc_window: usize,
    /// Required drop of the squared residual sum (units of σ_r²) for the arc test.
    pub arc_chi2: f32,
    /// Largest radius for the arc test, mm.
    pub arc_max_radius: f32,
}

/// How a segment's type is decided.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Typing {
    /// Paper §3.5: a line when the mean distance to the fitted line is ≤ `d_f` mm (paper: 20).
    MeanDistance {
        /// d_f, mm.
        d_f: f32,
    },
    /// Compare the line and circle fits: a circle when its residual sum is lower than the
    /// line's by more than `chi2 · σ_r²` and by a factor `ratio`, and its radius is at most
    /// `max_radius`.
    CompareFits {
        /// Required drop of the sum of squared residuals, in units of σ_r².
        chi2: f32,
        /// Circle SSE must be below `ratio` × line SSE.
        ratio: f32,
        /// Largest radius accepted as a circle, mm.
        max_radius: f32,
    },
}

/// Extractor configuration. Build one with [`Config::paper`] or [`Config::default`] and adjust.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub struct Config {
    /// Mark-point threshold.
    pub threshold: Threshold,
    /// Apply the paper's check step (§3.3) to runs of Np marks.
    pub check_step: bool,
    /// Feature typing.
    pub typing: Typing,
    /// Minimum points of a segment (paper: 4).
    pub min_points: usize,
    /// Algebraic circle fit.
    pub circle_method: CircleMethod,
    /// Geometric refinement steps after the algebraic fit (0 = none).
    pub circle_refine: usize,
    /// Range noise σ_r, mm, for the covariances (and the `Noise` threshold).
    pub sigma_r: f32,
    /// Systematic range error σ_sys, mm, that differs from beam to beam but not from scan to
    /// scan (a SICK LMS200's data sheet gives ±15 mm typical in mm mode): what a feature's beams
    /// share of it moves the feature between scans, seen by other beams. With `scrutiny`, a
    /// line of length L gets σ_sys² on ρ and 2σ_sys²/L² on α (its two ends independent), a
    /// circle σ_sys² on its centre along the beam to it. 0 (the default): none. The part of a
    /// scan's rounding its beams share ([`Scan::shared_rounding`](crate::Scan::shared_rounding),
    /// at most q²/12 for [`Scan::quantum`](crate::Scan::quantum) q) is added to σ_sys².
    pub sigma_sys: f32,
    /// Systematic range correction applied to every reading.
    pub correction: Option<RangeCorrection>,
    /// The default mode's checks for real scans: runs of short segments that lie on one line
    /// within the noise are joined (distant walls at grazing incidence); a circle must cover
    /// at least 6 points and 30° of arc and beat the best two-line (corner) split; a line that
    /// two lines explain far better (a corner the walk followed) is split there; a line's
    /// ends reach over the beams beside them that lie on it (the beams the walk leaves between
    /// two features at a corner); line and circle covariances grow with the fit's reduced χ²
    /// where the scatter significantly exceeds σ_r, and more where that excess is also
    /// correlated from beam to beam (it does not average out over the points). They cost a few instructions a point on a Cortex-M4F
    /// (docs/PERFORMANCE.md). A build
    /// without the `scrutiny` feature leaves them out and refuses this on (not
    /// [`Config::is_valid`]).
    pub scrutiny: bool,
}

/// Points in the prediction window (paper: Np = 3).
pub const NP: usize = 3;

/// Range noise of a SICK LMS2xx, mm ([`Config::for_lms2xx`]).
pub const LMS2XX_SIGMA_R: f32 = 5.0;
/// Beam-to-beam systematic range error of a SICK LMS2xx, mm ([`Config::for_lms2xx`]): the
/// data sheet's ±15 mm typical, taken as 3σ.
pub const LMS2XX_SIGMA_SYS: f32 = 5.0;

impl Config {
    /// The paper's method, faithfully: Np 3, d_0 50 mm, λ 2, check step, d_f 20 mm, Kåsa fit.
    pub const fn paper() -> Self {
        Self {
            threshold: Threshold::Paper {
                d0: 50.0,
                lambda: 2.0,
            },
            check_step: true,
            typing: Typing::MeanDistance { d_f: 20.0 },
            min_points: 4,
            circle_method: CircleMethod::Kasa,
            circle_refine: 0,
            sigma_r: 5.0,
            sigma_sys: 0.0,
            correction: None,
            scrutiny: false,
        }
    }

    /// The best measured configuration (see README "Configurations"): noise-derived threshold
    /// with boundary localisation, fit-comparison typing, Hyper fit with geometric refinement.
    pub const fn default_config() -> Self {
        Self {
            threshold: Threshold::Noise(NoiseModel {
                k: 4.0,
                k_locate: 2.5,
                floor: 3.0,
                window: 10,
                max_window: 24,
                min_span: 12.0,
                arc_window: 24,
                arc_chi2: 16.0,
                arc_max_radius: 2000.0,
            }),
            check_step: true,
            typing: Typing::CompareFits {
                chi2: 25.0,
                ratio: 0.5,
                max_radius: 2000.0,
            },
            min_points: 4,
            circle_method: CircleMethod::Hyper,
            circle_refine: 5,
            sigma_r: 5.0,
            sigma_sys: 0.0,
            correction: None,
            scrutiny: true,
        }
    }

    /// Whether the checks for real scans run: [`Self::scrutiny`], in a build with the
    /// `scrutiny` feature (without it their code is left out, and [`Self::is_valid`] refuses
    /// them on). The one switch every step asks.
    #[inline(always)]
    pub(crate) const fn scrutinised(&self) -> bool {
        cfg!(feature = "scrutiny") && self.scrutiny
    }

    /// The same configuration with the checks for real scans ([`Self::scrutiny`]) on or off.
    pub const fn with_scrutiny(mut self, on: bool) -> Self {
        self.scrutiny = on;
        self
    }

    /// The same configuration for a scanner with range noise `sigma_r` mm.
    pub const fn with_sigma_r(mut self, sigma_r: f32) -> Self {
        self.sigma_r = sigma_r;
        self
    }

    /// The same configuration for a scanner with a beam-to-beam systematic range error of
    /// `sigma_sys` mm (see [`Self::sigma_sys`]).
    pub const fn with_sigma_sys(mut self, sigma_sys: f32) -> Self {
        self.sigma_sys = sigma_sys;
        self
    }

    /// The same configuration for a SICK LMS2xx: σ_r [`LMS2XX_SIGMA_R`], σ_sys
    /// [`LMS2XX_SIGMA_SYS`]. With [`Scan::lms2xx`](crate::Scan::lms2xx), what `pfe extract
    /// --format lms200` and the firmware run.
    ///
    /// ```
    /// use pfe_core::Config;
    /// let c = Config::default().for_lms2xx();
    /// assert_eq!((c.sigma_r, c.sigma_sys, c.scrutiny), (5.0, 5.0, true));
    /// ```
    pub const fn for_lms2xx(self) -> Self {
        self.with_sigma_r(LMS2XX_SIGMA_R)
            .with_sigma_sys(LMS2XX_SIGMA_SYS)
    }

    /// The same configuration with a systematic range correction.
    pub const fn with_correction(mut self, correction: RangeCorrection) -> Self {
        self.correction = Some(correction);
        self
    }

    /// True when every parameter is usable (and `scrutiny` is off in a build without the
    /// `scrutiny` feature).
    pub fn is_valid(&self) -> bool {
        let t = match self.threshold {
            Threshold::Paper { d0, lambda } => {
                math::finite(d0) && d0 > 0.0 && math::finite(lambda) && lambda > 0.0
            }
            Threshold::Noise(m) => {
                math::finite(m.k)
                    && m.k > 0.0
                    && math::finite(m.k_locate)
                    && math::finite(m.floor)
                    && m.floor >= 0.0
                    && m.window >= 2
                    && math::finite(m.min_span)
                    && math::finite(m.arc_chi2)
                    && m.arc_max_radius > 0.0
            }
        };
        let ty = match self.typing {
            Typing::MeanDistance { d_f } => math::finite(d_f) && d_f >= 0.0,
            Typing::CompareFits {
                chi2,
                ratio,
                max_radius,
            } => math::finite(chi2) && math::finite(ratio) && max_radius > 0.0,
        };
        t && ty
            && math::finite(self.sigma_r)
            && self.sigma_r > 0.0
            && math::finite(self.sigma_sys)
            && self.sigma_sys >= 0.0
            && self.min_points >= 2
            && (cfg!(feature = "scrutiny") || !self.scrutiny)
    }
}

impl Default for Config {
    fn default() -> Self {
        Self::default_config()
    }
}
