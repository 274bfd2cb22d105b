//! The extractor's output: lines, circles and small objects with their uncertainty and point
//! range.

use crate::fit::circle::{circle_covariance_range, Circle};
use crate::fit::line::{LineCovariance, LineFit};
use crate::geometry::Point;
use crate::math;

#[cfg(feature = "serde")]
mod tagged;

/// A line feature `x cos α + y sin α = ρ`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct LineFeature {
    /// Index of the first beam of the segment (counting every beam, valid or not).
    pub first: u16,
    /// Index of the last beam of the segment.
    pub last: u16,
    /// Number of valid points fitted.
    pub points: u16,
    /// Normal angle, rad, in (−π, π].
    pub alpha: f32,
    /// Distance from the scanner, mm, ≥ 0.
    pub rho: f32,
    /// σ_α², rad².
    pub var_alpha: f32,
    /// σ_ρ², mm².
    pub var_rho: f32,
    /// cov(α, ρ), rad·mm.
    pub cov_alpha_rho: f32,
    /// Projection of the first point on the line.
    pub start: Point,
    /// Projection of the last point on the line.
    pub end: Point,
}

impl LineFeature {
    /// A line feature from all its fields, in declaration order.
    ///
    /// ```
    /// use pfe_core::{LineFeature, Point};
    /// let l = LineFeature::new(
    ///     0, 9, 10, 0.5, 2000.0, 1e-6, 4.0, 0.0, Point::new(1.0, 2.0), Point::new(3.0, 4.0),
    /// );
    /// assert_eq!((l.last, l.rho), (9, 2000.0));
    /// ```
    #[allow(clippy::too_many_arguments)] // one per field, in declaration order
    pub const fn new(
        first: u16,
        last: u16,
        points: u16,
        alpha: f32,
        rho: f32,
        var_alpha: f32,
        var_rho: f32,
        cov_alpha_rho: f32,
        start: Point,
        end: Point,
    ) -> Self {
        Self {
            first,
            last,
            points,
            alpha,
            rho,
            var_alpha,
            var_rho,
            cov_alpha_rho,
            start,
            end,
        }
    }

    /// Its numbers in declaration order: α, ρ, σ_α², σ_ρ², cov(α, ρ), start x, y, end x, y.
    ///
    /// ```
    /// use pfe_core::{LineFeature, Point};
    /// let l = LineFeature::new(
    ///     0, 9, 10, 0.5, 2000.0, 1e-6, 4.0, 0.0, Point::new(1.0, 2.0), Point::new(3.0, 4.0),
    /// );
    /// assert_eq!(l.values(), [0.5, 2000.0, 1e-6, 4.0, 0.0, 1.0, 2.0, 3.0, 4.0]);
    /// ```
    pub fn values(&self) -> [f32; 9] {
        let (s, e) = (self.start, self.end);
        [
            self.alpha,
            self.rho,
            self.var_alpha,
            self.var_rho,
            self.cov_alpha_rho,
            s.x,
            s.y,
            e.x,
            e.y,
        ]
    }
}

impl CircleFeature {
    /// A circle feature from all its fields, in declaration order.
    ///
    /// ```
    /// use pfe_core::{CircleFeature, Point};
    /// let c = CircleFeature::new(0, 9, 10, Point::new(1.0, 2.0), 3.0, [[0.0; 3]; 3], -0.5, 0.5);
    /// assert_eq!((c.points, c.radius), (10, 3.0));
    /// ```
    #[allow(clippy::too_many_arguments)] // one per field, in declaration order
    pub const fn new(
        first: u16,
        last: u16,
        points: u16,
        center: Point,
        radius: f32,
        cov: [[f32; 3]; 3],
        start_angle: f32,
        end_angle: f32,
    ) -> Self {
        Self {
            first,
            last,
            points,
            center,
            radius,
            cov,
            start_angle,
            end_angle,
        }
    }

    /// Its numbers in declaration order: centre x, y, radius, the covariance row by row, start
    /// and end angle.
    ///
    /// ```
    /// use pfe_core::{CircleFeature, Point};
    /// let c = CircleFeature::new(
    ///     0, 9, 10, Point::new(1.0, 2.0), 3.0,
    ///     [[4.0, 5.0, 6.0], [5.0, 7.0, 8.0], [6.0, 8.0, 9.0]],
    ///     -0.5, 0.5,
    /// );
    /// assert_eq!(c.values()[..5], [1.0, 2.0, 3.0, 4.0, 5.0]);
    /// assert_eq!(c.values()[11..], [9.0, -0.5, 0.5]);
    /// ```
    pub fn values(&self) -> [f32; 14] {
        let [[a, b, d], [e, f, g], [h, i, j]] = self.cov;
        let c = self.center;
        [
            c.x,
            c.y,
            self.radius,
            a,
            b,
            d,
            e,
            f,
            g,
            h,
            i,
            j,
            self.start_angle,
            self.end_angle,
        ]
    }
}

/// A circle (or arc) feature.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct CircleFeature {
    /// Index of the first beam of the segment.
    pub first: u16,
    /// Index of the last beam of the segment.
    pub last: u16,
    /// Number of valid points fitted.
    pub points: u16,
    /// Centre, mm.
    pub center: Point,
    /// Radius, mm.
    pub radius: f32,
    /// Covariance of (centre x, centre y, radius), mm².
    pub cov: [[f32; 3]; 3],
    /// Bearing from the centre to the first point, rad.
    pub start_angle: f32,
    /// Bearing from the centre to the last point, rad.
    pub end_angle: f32,
}

/// One extracted feature.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(tag = "kind", rename_all = "lowercase"),
    serde(try_from = "tagged::Tagged")
)]
#[non_exhaustive]
pub enum Feature {
    /// A straight segment.
    Line(LineFeature),
    /// A circular arc.
    Circle(CircleFeature),
    /// A small object: a short run of returns, apart from its neighbours, that is neither a
    /// determined line nor a circle.
    Object(ObjectFeature),
}

/// A small object (a chair or table leg, a person's leg, a post): a run of at least three
/// returns, separated from its neighbours by a range jump or no return on both sides, at
/// most 0.3 m across, too short or too little determined for a line or a circle.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct ObjectFeature {
    /// Index of the first beam of the run.
    pub first: u16,
    /// Index of the last beam of the run.
    pub last: u16,
    /// Number of valid points.
    pub points: u16,
    /// Centre: the mean of its points, mm.
    pub center: Point,
    /// Covariance of the centre, mm²: the range noise along the beam, the points' scatter,
    /// and where on an object as wide as its extent the points can lie.
    pub cov: [[f32; 2]; 2],
    /// Extent across (the widest distance between its points), mm.
    pub extent: f32,
}

impl ObjectFeature {
    /// An object of beams `first..=last` with `points` valid points, centre `center`, its
    /// covariance `cov` and extent `extent` (the struct is `#[non_exhaustive]`).
    ///
    /// ```
    /// use pfe_core::{ObjectFeature, Point};
    /// let o = ObjectFeature::new(10, 13, 4, Point::new(1000.0, 0.0), [[4.0, 0.0], [0.0, 9.0]], 30.0);
    /// assert_eq!(o.values(), [1000.0, 0.0, 4.0, 0.0, 0.0, 9.0, 30.0]);
    /// ```
    pub const fn new(
        first: u16,
        last: u16,
        points: u16,
        center: Point,
        cov: [[f32; 2]; 2],
        extent: f32,
    ) -> Self {
        Self {
            first,
            last,
            points,
            center,
            cov,
            extent,
        }
    }

    /// Its numbers in declaration order: centre x, y, the covariance row by row, extent.
    pub fn values(&self) -> [f32; 7] {
        let [[a, b], [c, d]] = self.cov;
        [self.center.x, self.center.y, a, b, c, d, self.extent]
    }
}

impl Feature {
    /// Index of the first beam.
    pub fn first(&self) -> usize {
        match self {
            Feature::Line(l) => usize::from(l.first),
            Feature::Circle(c) => usize::from(c.first),
            Feature::Object(o) => usize::from(o.first),
        }
    }

    /// Index of the last beam.
    pub fn last(&self) -> usize {
        match self {
            Feature::Line(l) => usize::from(l.last),
            Feature::Circle(c) => usize::from(c.last),
            Feature::Object(o) => usize::from(o.last),
        }
    }

    /// True for a line.
    pub fn is_line(&self) -> bool {
        matches!(self, Feature::Line(_))
    }

    /// True for a small object.
    pub fn is_object(&self) -> bool {
        matches!(self, Feature::Object(_))
    }

    /// True when every parameter is finite and first ≤ last.
    pub fn is_well_formed(&self) -> bool {
        match self {
            Feature::Line(l) => l.first <= l.last && math::all_finite(&l.values()),
            Feature::Circle(c) => c.first <= c.last && math::all_finite(&c.values()),
            Feature::Object(o) => o.first <= o.last && math::all_finite(&o.values()),
        }
    }
}

/// The line feature of the points `pts` of beams `first..=last` fitted by `line`, with the
/// range-noise covariance for a scanner at `origin` (`None` when not well formed or the
/// indices do not fit in `u16`).
pub fn line_feature(
    pts: &[Point],
    first: usize,
    last: usize,
    line: &LineFit,
    origin: Point,
    sigma_r: f32,
) -> Option<Feature> {
    let cov = line.covariance_range_of(pts, origin, sigma_r);
    line_feature_with(pts, first, last, line, cov)
}

/// [`line_feature`] with its covariance.
pub(crate) fn line_feature_with(
    pts: &[Point],
    first: usize,
    last: usize,
    line: &LineFit,
    cov: LineCovariance,
) -> Option<Feature> {
    let l = LineFeature {
        first: u16::try_from(first).ok()?,
        last: u16::try_from(last).ok()?,
        points: u16::try_from(pts.len()).ok()?,
        alpha: line.alpha,
        rho: line.rho,
        var_alpha: cov.var_alpha,
        var_rho: cov.var_rho,
        cov_alpha_rho: cov.cov_alpha_rho,
        start: line.project(pts.first()?),
        end: line.project(pts.last()?),
    };
    // [`Feature::is_well_formed`] on the fields, the feature built once in its place.
    (l.first <= l.last && math::all_finite(&l.values())).then_some(Feature::Line(l))
}

/// The circle feature of the points `pts` of beams `first..=last` fitted by `circle`, with the
/// range-noise covariance for a scanner at `origin` and the arc's extent.
pub fn circle_feature(
    pts: &[Point],
    first: usize,
    last: usize,
    circle: &Circle,
    origin: Point,
    sigma_r: f32,
) -> Option<Feature> {
    let cov = circle_covariance_range(pts, circle, origin, sigma_r).ok()?;
    let angle = |p: &Point| math::atan2(p.y - circle.center.y, p.x - circle.center.x);
    let f = Feature::Circle(CircleFeature {
        first: u16::try_from(first).ok()?,
        last: u16::try_from(last).ok()?,
        points: u16::try_from(pts.len()).ok()?,
        center: circle.center,
        radius: circle.radius,
        cov,
        start_angle: angle(pts.first()?),
        end_angle: angle(pts.last()?),
    });
    f.is_well_formed().then_some(f)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::line::fit_line;

    /// [`line_feature_with`] checks the line's fields before it becomes a feature: it is the
    /// feature built first and kept when [`Feature::is_well_formed`], for covariances finite,
    /// NaN and infinite, beams in and out of order and indices past `u16`.
    #[test]
    fn the_line_checked_before_it_is_a_feature_is_the_well_formed_feature() {
        let pts: [Point; 6] =
            core::array::from_fn(|i| Point::new(1000.0 + 3.0 * i as f32, 20.0 * i as f32));
        let line = fit_line(&pts).expect("a line");
        let bad = [1e-6, f32::NAN, f32::INFINITY, -f32::INFINITY];
        let (mut kept, mut refused) = (0, 0);
        for (first, last) in [(3, 8), (8, 3), (5, 5), (70_000, 70_005), (0, 65_535)] {
            for k in 0..bad.len() * 3 {
                let v = |j: usize| {
                    if k / bad.len() == j {
                        bad[k % bad.len()]
                    } else {
                        1e-6
                    }
                };
                let cov = LineCovariance {
                    var_alpha: v(0),
                    var_rho: v(1),
                    cov_alpha_rho: v(2),
                };
                let built = (|| {
                    let f = Feature::Line(LineFeature {
                        first: u16::try_from(first).ok()?,
                        last: u16::try_from(last).ok()?,
                        points: u16::try_from(pts.len()).ok()?,
                        alpha: line.alpha,
                        rho: line.rho,
                        var_alpha: cov.var_alpha,
                        var_rho: cov.var_rho,
                        cov_alpha_rho: cov.cov_alpha_rho,
                        start: line.project(pts.first()?),
                        end: line.project(pts.last()?),
                    });
                    f.is_well_formed().then_some(f)
                })();
                let got = line_feature_with(&pts, first, last, &line, cov);
                assert_eq!(got, built, "{first} {last} {k}");
                match got {
                    Some(_) => kept += 1,
                    None => refused += 1,
                }
            }
        }
        assert!(kept >= 3 && refused >= 10, "{kept} {refused}");
    }
}
