//! Points and the small pieces of plane geometry the extractor shares with the baselines
//! and the simulator (one place for them, so nobody writes them twice).

use crate::math;

/// A point in the scanner frame, in mm: x forward, y to the left.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(from = "[f32; 2]", into = "[f32; 2]")
)]
pub struct Point {
    /// Forward, mm.
    pub x: f32,
    /// Left, mm.
    pub y: f32,
}

impl From<[f32; 2]> for Point {
    fn from([x, y]: [f32; 2]) -> Self {
        Self { x, y }
    }
}

impl From<Point> for [f32; 2] {
    fn from(p: Point) -> Self {
        [p.x, p.y]
    }
}

impl Point {
    /// The "no point" marker used for invalid readings.
    pub const INVALID: Point = Point {
        x: f32::NAN,
        y: f32::NAN,
    };

    /// A point from its coordinates.
    pub const fn new(x: f32, y: f32) -> Self {
        Self { x, y }
    }

    /// A point from polar coordinates (range in mm, bearing in rad).
    pub fn from_polar(range: f32, bearing: f32) -> Self {
        let (s, c) = math::sin_cos(bearing);
        Self::new(range * c, range * s)
    }

    /// True when both coordinates are finite.
    pub fn is_valid(&self) -> bool {
        math::finite(self.x) && math::finite(self.y)
    }

    /// Euclidean distance to `other`.
    pub fn distance(&self, other: &Point) -> f32 {
        math::hypot(self.x - other.x, self.y - other.y)
    }

    /// Distance from the origin.
    pub fn norm(&self) -> f32 {
        math::hypot(self.x, self.y)
    }
}

/// Intersection of the line `x cos α + y sin α = ρ` with the ray from `origin` in the unit
/// direction `(dx, dy)`: returns the signed distance `t` along the ray and `|cos|` of the angle
/// between the ray and the line's normal (i.e. `sin` of the acute angle between ray and line).
/// `None` when the ray is parallel to the line (within `1e-6`).
pub fn ray_line_intersection(
    origin: Point,
    dx: f32,
    dy: f32,
    alpha: f32,
    rho: f32,
) -> Option<(f32, f32)> {
    let (s, c) = math::sin_cos(alpha);
    let denom = dx * c + dy * s;
    if math::abs(denom) < 1e-6 {
        return None;
    }
    let t = (rho - origin.x * c - origin.y * s) / denom;
    if math::finite(t) {
        Some((t, math::abs(denom)))
    } else {
        None
    }
}

/// Nearest intersection (t > 0) of the ray from `origin` in the unit direction `(dx, dy)` with
/// the circle `center`, `radius`; `None` when the ray misses it.
pub fn ray_circle_intersection(
    origin: Point,
    dx: f32,
    dy: f32,
    center: Point,
    radius: f32,
) -> Option<f32> {
    let (cx, cy) = (center.x - origin.x, center.y - origin.y);
    let b = dx * cx + dy * cy;
    let c = cx * cx + cy * cy - radius * radius;
    let disc = b * b - c;
    if !(disc >= 0.0) {
        return None;
    }
    let root = math::sqrt(disc);
    let t = if b - root > 0.0 { b - root } else { b + root };
    (t > 0.0 && math::finite(t)).then_some(t)
}
