//! Motion de-skew (paper §2, after Arras et al.): a robot moving at constant forward speed `v`
//! and turn rate `ω` takes beam `i` at the time its [`BeamTiming`] gives. Every point is
//! expressed in the scanner frame at time 0 (the first beam of the first sweep).

use crate::geometry::Point;
use crate::math;

/// When each beam of a scan is taken. A scan is `sweeps` interleaved sweeps: beam `i` belongs
/// to sweep `i mod sweeps` and is beam `i div sweeps` of it, so it is taken at
/// `(i mod sweeps)·sweep_dt + (i div sweeps)·beam_dt`.
///
/// An LMS2xx at 0.5° (0.25°) merges 2 (4) sweeps of 1° from consecutive mirror turns
/// ([`BeamTiming::lms2xx`]); one sweep is the uniform case `t = i·beam_dt`.
///
/// ```
/// use pfe_core::BeamTiming;
/// let t = BeamTiming::lms2xx(0.5);
/// // Beams 0 and 2 are one degree apart in one sweep; beam 1 is a mirror turn later.
/// assert!((t.time(2) - 1.0 / 75.0 / 360.0).abs() < 1e-9);
/// assert!((t.time(1) - 1.0 / 75.0).abs() < 1e-9);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BeamTiming {
    /// Time between consecutive beams of one sweep, s.
    pub beam_dt: f32,
    /// Number of interleaved sweeps (1: no interleaving; 0 counts as 1).
    pub sweeps: u8,
    /// Time between the starts of consecutive sweeps, s.
    pub sweep_dt: f32,
}

impl BeamTiming {
    /// Time of one LMS2xx mirror turn (75 Hz), s.
    pub const LMS2XX_TURN: f32 = 1.0 / 75.0;

    /// One sweep: beam `i` at `i·beam_dt`.
    pub const fn uniform(beam_dt: f32) -> Self {
        Self {
            beam_dt,
            sweeps: 1,
            sweep_dt: 0.0,
        }
    }

    /// `sweeps` interleaved sweeps starting `sweep_dt` apart, beams `beam_dt` apart within one.
    pub const fn interleaved(sweeps: u8, sweep_dt: f32, beam_dt: f32) -> Self {
        Self {
            beam_dt,
            sweeps,
            sweep_dt,
        }
    }

    /// An LMS2xx at `resolution_deg` (1, 0.5 or 0.25): sweeps of 1° beams, one mirror turn
    /// apart, `1 / resolution` of them (at least one).
    pub fn lms2xx(resolution_deg: f32) -> Self {
        let per_degree = Self::LMS2XX_TURN / 360.0;
        let sweeps = if resolution_deg < 0.375 {
            4
        } else if resolution_deg < 0.75 {
            2
        } else {
            1
        };
        if sweeps == 1 {
            Self::uniform(per_degree * resolution_deg)
        } else {
            Self::interleaved(sweeps, Self::LMS2XX_TURN, per_degree)
        }
    }

    /// Number of sweeps (at least 1).
    pub fn sweep_count(&self) -> usize {
        usize::from(self.sweeps.max(1))
    }

    /// The sweep beam `i` belongs to.
    pub fn sweep(&self, i: usize) -> usize {
        i % self.sweep_count()
    }

    /// Time beam `i` is taken, s, after beam 0.
    pub fn time(&self, i: usize) -> f32 {
        let s = self.sweep_count();
        (i % s) as f32 * self.sweep_dt + (i / s) as f32 * self.beam_dt
    }

    /// True when both times are finite.
    pub fn is_valid(&self) -> bool {
        math::all_finite(&[self.beam_dt, self.sweep_dt])
    }
}

/// Constant-velocity motion of the scanner during one scan.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Motion {
    /// Forward speed, mm/s.
    pub v: f32,
    /// Turn rate, rad/s (counter-clockwise positive).
    pub omega: f32,
    /// When each beam is taken.
    pub timing: BeamTiming,
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
    /// Motion with beam `i` taken at `i·beam_dt` (one sweep).
    pub const fn uniform(v: f32, omega: f32, beam_dt: f32) -> Self {
        Self {
            v,
            omega,
            timing: BeamTiming::uniform(beam_dt),
        }
    }

    /// True when all fields are finite.
    pub fn is_valid(&self) -> bool {
        math::all_finite(&[self.v, self.omega]) && self.timing.is_valid()
    }

    /// Whether interleaved sweeps are taken from different poses (more than one sweep and
    /// the scanner moving): their de-skewed points are then not evenly spaced in bearing.
    pub(crate) fn sweeps_apart(&self) -> bool {
        self.timing.sweep_count() > 1 && self.moves()
    }

    /// Whether the scanner moves (v or ω not zero).
    pub(crate) fn moves(&self) -> bool {
        self.v != 0.0 || self.omega != 0.0
    }

    /// Scanner pose when beam `i` was taken, in the frame of beam 0 (exact arc of a circle).
    ///
    /// ```
    /// use pfe_core::{BeamTiming, Motion};
    /// let m = Motion::uniform(1000.0, 0.0, 0.001);
    /// let p = m.pose(10);
    /// assert!((p.origin.x - 10.0).abs() < 1e-4 && p.origin.y == 0.0);
    /// // Interleaved: beam 1 of a 0.5° LMS2xx scan is one mirror turn (13.3 ms) later.
    /// let m = Motion { v: 600.0, omega: 0.0, timing: BeamTiming::lms2xx(0.5) };
    /// assert!((m.pose(1).origin.x - 8.0).abs() < 1e-3);
    /// ```
    pub fn pose(&self, i: usize) -> Pose {
        self.pose_at(self.timing.time(i))
    }

    /// Scanner pose at time `t`, s.
    pub fn pose_at(&self, t: f32) -> Pose {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Interleaved sweeps are apart exactly when there is more than one and the scanner moves
    /// (forwards or turning).
    #[test]
    fn sweeps_are_apart_when_several_are_taken_on_the_move() {
        let cases = [
            (1.0, 600.0, 0.0, false),
            (1.0, 0.0, 0.4, false),
            (0.5, 0.0, 0.0, false),
            (0.5, 600.0, 0.0, true),
            (0.5, 0.0, -0.4, true),
            (0.25, 0.0, 0.0, false),
            (0.25, -300.0, 0.0, true),
        ];
        for (resolution, v, omega, want) in cases {
            let m = Motion {
                v,
                omega,
                timing: BeamTiming::lms2xx(resolution),
            };
            assert_eq!(
                m.sweeps_apart(),
                want,
                "{resolution}° at {v} mm/s, {omega} rad/s"
            );
        }
    }
}
