//! What the registration takes: lines and points of one scan with their covariances.

use pfe_core::Feature;

/// A line `x cos α + y sin α = ρ` in the scanner frame (pfe-core's convention: α the normal's
/// angle in rad, ρ ≥ 0 in mm), with its covariance and, when known, the segment seen.
///
/// ```
/// use pfe_pose::LineObs;
/// let l = LineObs::new(0.0, 2000.0, [[1e-6, 0.0], [0.0, 25.0]]).with_extent([2000.0, -500.0], [2000.0, 500.0]);
/// assert!(l.is_valid());
/// assert!((l.length() - 1000.0).abs() < 1e-3);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineObs {
    /// Normal angle, rad.
    pub alpha: f32,
    /// Distance from the scanner, mm (≥ 0).
    pub rho: f32,
    /// Covariance of (α, ρ): rad², rad·mm, mm².
    pub cov: [[f32; 2]; 2],
    /// First end of the segment seen, mm (NaN when unknown).
    pub start: [f32; 2],
    /// Last end of the segment seen, mm (NaN when unknown).
    pub end: [f32; 2],
}

impl LineObs {
    /// An infinite line (no extent) with covariance `cov` of (α, ρ).
    pub fn new(alpha: f32, rho: f32, cov: [[f32; 2]; 2]) -> Self {
        Self {
            alpha,
            rho,
            cov,
            start: [f32::NAN; 2],
            end: [f32::NAN; 2],
        }
    }

    /// The same line, seen from `start` to `end` (points on or near it, mm).
    pub fn with_extent(mut self, start: [f32; 2], end: [f32; 2]) -> Self {
        self.start = start;
        self.end = end;
        self
    }

    /// True when the extent is known (both ends finite).
    pub fn has_extent(&self) -> bool {
        self.start.iter().chain(&self.end).all(|v| v.is_finite())
    }

    /// Length of the segment seen, mm (0 without extent).
    pub fn length(&self) -> f32 {
        if self.has_extent() {
            crate::geom::hypot(self.end[0] - self.start[0], self.end[1] - self.start[1])
        } else {
            0.0
        }
    }

    /// True when α and ρ are finite, ρ ≥ 0 and the covariance is finite, symmetric and
    /// positive definite.
    pub fn is_valid(&self) -> bool {
        let [[a, b], [b2, c]] = self.cov;
        self.alpha.is_finite()
            && self.rho.is_finite()
            && self.rho >= 0.0
            && [a, b, b2, c].iter().all(|v| v.is_finite())
            && (b - b2).abs() <= 1e-3 * crate::geom::sqrt((a * c).abs()) + f32::MIN_POSITIVE
            && a > 0.0
            && c > 0.0
            && a * c - b * b > 0.0
    }
}

/// A point feature (a circle's or a small object's centre) in the scanner frame, mm, with its
/// 2×2 covariance (mm²).
///
/// ```
/// use pfe_pose::PointObs;
/// assert!(PointObs::new(1000.0, 500.0, [[25.0, 0.0], [0.0, 25.0]]).is_valid());
/// assert!(!PointObs::new(f32::NAN, 500.0, [[25.0, 0.0], [0.0, 25.0]]).is_valid());
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointObs {
    /// mm.
    pub x: f32,
    /// mm.
    pub y: f32,
    /// Covariance of (x, y), mm².
    pub cov: [[f32; 2]; 2],
}

impl PointObs {
    /// The point (x, y) with covariance `cov`.
    pub fn new(x: f32, y: f32, cov: [[f32; 2]; 2]) -> Self {
        Self { x, y, cov }
    }

    /// True when finite with a symmetric positive definite covariance.
    pub fn is_valid(&self) -> bool {
        let [[a, b], [b2, c]] = self.cov;
        self.x.is_finite()
            && self.y.is_finite()
            && [a, b, b2, c].iter().all(|v| v.is_finite())
            && (b - b2).abs() <= 1e-3 * crate::geom::sqrt((a * c).abs()) + f32::MIN_POSITIVE
            && a > 0.0
            && c > 0.0
            && a * c - b * b > 0.0
    }
}

/// One feature of a scan, as the registration sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Observation {
    /// A line.
    Line(LineObs),
    /// A point.
    Point(PointObs),
}

impl Observation {
    /// A pfe-core feature as an observation: a line keeps (α, ρ), its covariance and its
    /// segment; a circle or a small object becomes its centre with the centre's covariance. `None` when the
    /// feature is not well formed or its covariance is not positive definite (a fit from
    /// noise-free points has zero variance: give such scans a range noise).
    ///
    /// ```
    /// use pfe_core::{Feature, LineFeature, Point};
    /// use pfe_pose::Observation;
    /// let f = Feature::Line(LineFeature::new(
    ///     0, 9, 10, 0.5, 2000.0, 1e-6, 4.0, 0.0, Point::new(1.0, 2.0), Point::new(3.0, 4.0),
    /// ));
    /// assert!(matches!(Observation::from_feature(&f), Some(Observation::Line(l)) if l.rho == 2000.0));
    /// ```
    pub fn from_feature(f: &Feature) -> Option<Observation> {
        if !f.is_well_formed() {
            return None;
        }
        let o = match f {
            Feature::Line(l) => Observation::Line(
                LineObs::new(
                    l.alpha,
                    l.rho,
                    [[l.var_alpha, l.cov_alpha_rho], [l.cov_alpha_rho, l.var_rho]],
                )
                .with_extent([l.start.x, l.start.y], [l.end.x, l.end.y]),
            ),
            Feature::Circle(c) => Observation::Point(PointObs::new(
                c.center.x,
                c.center.y,
                [[c.cov[0][0], c.cov[0][1]], [c.cov[1][0], c.cov[1][1]]],
            )),
            // A small object: its centre with the centre's covariance (which holds where on an
            // object of its extent the visible points lie, so another viewpoint stays within it).
            Feature::Object(o) => Observation::Point(PointObs::new(o.center.x, o.center.y, o.cov)),
            // A feature kind this crate does not know yet is not used.
            _ => return None,
        };
        o.is_valid().then_some(o)
    }

    /// True when the observation can be used (see [`LineObs::is_valid`],
    /// [`PointObs::is_valid`]).
    pub fn is_valid(&self) -> bool {
        match self {
            Observation::Line(l) => l.is_valid(),
            Observation::Point(p) => p.is_valid(),
        }
    }
}
