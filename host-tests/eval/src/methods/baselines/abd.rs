//! Adaptive breakpoint detector (ABD) of G. A. Borges and M.-J. Aldon, "Line extraction in 2D
//! range images for mobile robotics", *Journal of Intelligent and Robotic Systems* 40 (2004)
//! 267–297, §3.
//!
//! Two consecutive points P_{n−1}, P_n are a breakpoint when
//!
//! ```text
//! ‖P_n − P_{n−1}‖ > D_max = r_{n−1} · sin(Δφ) / sin(λ − Δφ) + 3 σ_r
//! ```
//!
//! Δφ is the angular step, λ the smallest incidence angle (between the beam and the surface)
//! still accepted as one surface (Borges & Aldon: λ = 10°), σ_r the range noise. The first term
//! is the distance between two beams hitting a surface at incidence λ. An invalid reading
//! (no return) is a breakpoint as well: it ends the segment before it and starts a new one
//! after it.

use pfe_core::{Point, ScanGeometry};

/// ABD parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Abd {
    /// λ, rad (Borges & Aldon: 10°).
    pub lambda: f32,
    /// σ_r, mm.
    pub sigma_r: f32,
}

impl Default for Abd {
    fn default() -> Self {
        Self {
            lambda: 10f32.to_radians(),
            sigma_r: super::DEFAULT_SIGMA_R,
        }
    }
}

impl Abd {
    /// D_max for a point at range `r_prev` (mm) followed by the next beam, `step` rad apart.
    /// An unusable λ (λ ≤ Δφ, NaN) gives an infinite threshold: no geometric breakpoints.
    ///
    /// ```
    /// use pfe_eval::methods::baselines::Abd;
    /// let abd = Abd::default();
    /// let d = abd.d_max(2000.0, 0.5f32.to_radians());
    /// // 2000 · sin 0.5° / sin 9.5° + 3 · 5 ≈ 120.7 mm
    /// assert!((d - 120.7).abs() < 0.5);
    /// ```
    pub fn d_max(&self, r_prev: f32, step: f32) -> f32 {
        let step = step.abs();
        let den = (self.lambda - step).sin();
        let geometric = if den > 0.0 && self.lambda > step {
            r_prev * step.sin() / den
        } else {
            f32::INFINITY
        };
        geometric + 3.0 * self.sigma()
    }

    /// The range noise σ_r (mm) the thresholds use: `sigma_r`, or the default when it is unusable.
    pub fn sigma(&self) -> f32 {
        super::sane_sigma(self.sigma_r)
    }

    /// Segments of consecutive valid points, as inclusive index ranges in increasing order.
    /// `points[i]` is beam i's point (`None` = no return). Single points are segments too.
    ///
    /// ```
    /// use pfe_eval::methods::baselines::{scan_points, Abd};
    /// use pfe_core::ScanGeometry;
    /// let g = ScanGeometry::LMS200_180_050;
    /// let mut r = vec![2000.0_f32; 361];
    /// r[100] = f32::NAN; // a hole
    /// for v in &mut r[200..] { *v = 4000.0 } // a jump
    /// let segs = Abd::default().segments(&g, &scan_points(&g, &r));
    /// assert_eq!(segs, vec![(0, 99), (101, 199), (200, 360)]);
    /// ```
    pub fn segments(
        &self,
        geometry: &ScanGeometry,
        points: &[Option<Point>],
    ) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        let mut start: Option<usize> = None;
        let mut prev: Option<(usize, Point)> = None;
        for (i, p) in points.iter().enumerate() {
            let Some(p) = *p else {
                if let (Some(s), Some((e, _))) = (start.take(), prev) {
                    out.push((s, e));
                }
                prev = None;
                continue;
            };
            if let Some((j, q)) = prev {
                let d_max = self.d_max(q.norm(), geometry.angle_step);
                // A NaN distance is a break too.
                let d = p.distance(&q);
                if d.is_nan() || d > d_max {
                    if let Some(s) = start.take() {
                        out.push((s, j));
                    }
                }
            }
            if start.is_none() {
                start = Some(i);
            }
            prev = Some((i, p));
        }
        if let (Some(s), Some((e, _))) = (start, prev) {
            out.push((s, e));
        }
        out
    }
}
