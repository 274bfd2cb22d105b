//! Scene primitives (segments, circles) and their ray intersections.

use super::vec2::{add, cross, dot, norm, scale, sub, V2};

/// A scene primitive, in mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// A straight segment from `a` to `b` (a wall, a box side).
    Segment {
        /// One end.
        a: [f64; 2],
        /// The other end.
        b: [f64; 2],
    },
    /// A circle (pillar, bin).
    Circle {
        /// Centre.
        center: [f64; 2],
        /// Radius, > 0.
        radius: f64,
    },
}

impl Shape {
    /// Distance `t > 0` along the ray `origin + t · d` (`d` a unit vector) to its first hit of
    /// this shape, or `None`. Rays parallel to a segment do not hit it.
    ///
    /// ```
    /// use pfe_eval::scene::Shape;
    /// let wall = Shape::Segment { a: [2000.0, -1000.0], b: [2000.0, 1000.0] };
    /// let t = wall.ray_hit([0.0, 0.0], [1.0, 0.0]).unwrap();
    /// assert!((t - 2000.0).abs() < 1e-9);
    /// ```
    pub fn ray_hit(&self, origin: [f64; 2], d: [f64; 2]) -> Option<f64> {
        const EPS: f64 = 1e-9;
        match *self {
            Shape::Segment { a, b } => {
                let e = sub(b, a);
                let den = cross(d, e);
                if den.abs() < 1e-12 * norm(e).max(1.0) {
                    return None;
                }
                let w = sub(a, origin);
                let t = cross(w, e) / den;
                let s = cross(w, d) / den;
                (t > EPS && (0.0..=1.0).contains(&s)).then_some(t)
            }
            Shape::Circle { center, radius } => {
                let c = sub(center, origin);
                let b = dot(d, c);
                let disc = b * b - (dot(c, c) - radius * radius);
                if disc < 0.0 {
                    return None;
                }
                let root = disc.sqrt();
                if b - root > EPS {
                    Some(b - root)
                } else if b + root > EPS {
                    Some(b + root)
                } else {
                    None
                }
            }
        }
    }

    /// Distance from `p` to the shape's outline.
    pub fn distance(&self, p: [f64; 2]) -> f64 {
        match *self {
            Shape::Segment { a, b } => {
                let e = sub(b, a);
                let l2 = dot(e, e);
                let s = if l2 > 0.0 {
                    (dot(sub(p, a), e) / l2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                norm(sub(p, add(a, scale(e, s))))
            }
            Shape::Circle { center, radius } => (norm(sub(p, center)) - radius).abs(),
        }
    }

    /// The shape seen from a scanner at `pose = (x, y, heading)` (world → scanner frame).
    pub fn to_frame(&self, pose: [f64; 3]) -> Shape {
        let (s, c) = pose[2].sin_cos();
        let f = |p: V2| {
            let q = [p[0] - pose[0], p[1] - pose[1]];
            [c * q[0] + s * q[1], -s * q[0] + c * q[1]]
        };
        match *self {
            Shape::Segment { a, b } => Shape::Segment { a: f(a), b: f(b) },
            Shape::Circle { center, radius } => Shape::Circle {
                center: f(center),
                radius,
            },
        }
    }
}
