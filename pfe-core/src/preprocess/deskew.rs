//! Motion de-skew (paper §2, after Arras et al.): a robot moving at constant forward speed `v`
//! and turn rate `ω` takes beam `i` at time `i·Δt`. Every point is expressed in the scanner frame
//! at the time of beam 0.

use crate::geometry::Point;
use crate::math;

/// Constant-velocity motion of the scanner during one scan.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Motion {
    /// Forward speed, mm/s.
    pub v: f32,
    /// Turn rate, rad/s (counter-clockwise positive).
    pub omega: f32,
    /// Time between two consecutive beams, s.
    pub beam_dt: f32,
}

/// Pose of the scanner at some time, in the frame of beam 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Position, mm.
    pub origin: Point,
    /// Heading, rad.
    pub theta: f32,
}

impl Motion {
    /// True when all fields are finite.
    pub fn is_valid(&self) -> bool {
        math::all_finite(&[self.v, self.omega, self.beam_dt])
    }

    /// Scanner pose when beam `i` was taken, in the frame of beam 0 (exact arc of a circle).
    ///
    /// ```
    /// use pfe_core::Motion;
    /// let m = Motion { v: 1000.0, omega: 0.0, beam_dt: 0.001 };
    /// let p = m.pose(10);
    /// assert!((p.origin.x - 10.0).abs() < 1e-4 && p.origin.y == 0.0);
    /// ```
    pub fn pose(&self, i: usize) -> Pose {
        let t = i as f32 * self.beam_dt;
        let theta = self.omega * t;
        let (s, c) = math::sin_cos(theta);
        // x = v/ω sin ωt, y = v/ω (1 − cos ωt); series for small ωt keeps f32 exact.
        let (x, y) = if math::abs(theta) < 1e-3 {
            (
                self.v * t * (1.0 - theta * theta / 6.0),
                self.v * t * theta * 0.5,
            )
        } else {
            (self.v / self.omega * s, self.v / self.omega * (1.0 - c))
        };
        Pose {
            origin: Point::new(x, y),
            theta,
        }
    }

    /// Point measured by beam `i` at `(range, bearing)` in the frame of beam 0, and the
    /// scanner origin at that time.
    pub fn deskew(&self, i: usize, range: f32, bearing: f32) -> (Point, Point) {
        let pose = self.pose(i);
        let p = Point::from_polar(range, bearing + pose.theta);
        (
            Point::new(p.x + pose.origin.x, p.y + pose.origin.y),
            pose.origin,
        )
    }
}
