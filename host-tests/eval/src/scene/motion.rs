//! When the simulated LMS200 takes each beam, and where the moving scanner is then.
//!
//! The mirror turns at 75 Hz. At 1° one mirror turn gives the whole scan; at 0.5° (0.25°) the
//! scan merges 2 (4) sweeps of 1° from consecutive turns, sweep `k` shifted by `k` times the
//! resolution, so beam `i` belongs to sweep `i mod S` and is its beam `i div S`. It is taken at
//! `(i mod S) · T + (i div S) · T / 360` (`T` one mirror turn): the sweep's start plus the
//! beam's angle within the sweep at 1° per `T / 360` ≈ 37.04 µs. Computed here in `f64`,
//! independently of pfe-core's `BeamTiming`.

use super::Resolution;

/// One mirror turn of the LMS200 (75 Hz), s.
pub const MIRROR_TURN_S: f64 = 1.0 / 75.0;

/// Time the mirror takes to turn by 1°, s (≈ 37.04 µs).
pub const DEGREE_S: f64 = MIRROR_TURN_S / 360.0;

impl Resolution {
    /// Number of interleaved 1° sweeps a scan is made of (1, 2 or 4).
    pub fn sweeps(&self) -> usize {
        match self {
            Resolution::Quarter => 4,
            Resolution::Half => 2,
            Resolution::One => 1,
        }
    }

    /// The sweep beam `i` belongs to.
    pub fn sweep_of(&self, i: usize) -> usize {
        i % self.sweeps()
    }

    /// Time beam `i` is taken, s after beam 0.
    ///
    /// ```
    /// use pfe_eval::scene::Resolution;
    /// let r = Resolution::Half;
    /// assert!((r.beam_time(1) - 1.0 / 75.0).abs() < 1e-12); // next mirror turn
    /// assert!((r.beam_time(2) - 1.0 / 75.0 / 360.0).abs() < 1e-12); // 1° later
    /// ```
    pub fn beam_time(&self, i: usize) -> f64 {
        let s = self.sweeps();
        (i % s) as f64 * MIRROR_TURN_S + (i / s) as f64 * DEGREE_S
    }
}

/// Scanner pose `[x, y, θ]` (mm, mm, rad) at time `t` (s) in the frame of time 0, moving at
/// forward speed `v` (mm/s) and turn rate `omega` (rad/s): the exact arc of a circle.
pub fn pose_at(v: f64, omega: f64, t: f64) -> [f64; 3] {
    let theta = omega * t;
    if omega == 0.0 {
        return [v * t, 0.0, 0.0];
    }
    [
        v / omega * theta.sin(),
        v / omega * 2.0 * (0.5 * theta).sin().powi(2),
        theta,
    ]
}
