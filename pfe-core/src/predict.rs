//! Prediction (paper §3.1–3.2): the least-squares line through the `Np` preceding points
//! (Line 1) meets the test point's beam (Line 2) at the prediction point; the test point's
//! distance from it is the prediction error `D`. No trigonometry: the line's direction is the
//! principal axis of the window's centred moments (one square root).

use crate::geometry::Point;
use crate::math;

/// Outcome of predicting one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prediction {
    /// `D(P_k, P_k^p)`, mm; infinite when Line 1 is parallel to the beam or meets it behind
    /// the scanner.
    pub error: f32,
    /// Measured range minus predicted range, mm (positive: the point is behind Line 1).
    pub signed: f32,
    /// Beam direction · Line 1's (unnormalised) normal: ∝ sin ϕ.
    dn: f32,
    /// Beam direction · Line 1's (unnormalised) direction: ∝ cos ϕ.
    dt: f32,
    /// Variance of `error` in units of σ_r² for pure range noise:
    /// `1 + (1/n + u²/S_uu) · sin²ϕ̄ / sin²ϕ`, u the prediction point's position along Line 1
    /// from the window's centroid, `S_uu` the window's spread along Line 1, ϕ̄ the incidence of
    /// Line 1 at the window's last point (its points' noise across Line 1 is σ_r sin ϕ̄).
    pub var_factor: f32,
}

impl Prediction {
    /// ϕ, the acute angle between Line 1 and the beam, in [0, π/2].
    pub fn phi(&self) -> f32 {
        math::atan2(math::abs(self.dn), math::abs(self.dt))
    }

    /// Standard deviation of `error` in units of σ_r.
    pub fn sigma_factor(&self) -> f32 {
        math::sqrt(self.var_factor)
    }

    /// True when `error > k · σ_r · sigma_factor + floor` (computed without a square root).
    pub fn exceeds(&self, k: f32, sigma_r: f32, floor: f32) -> bool {
        if !(self.error > floor) {
            return false;
        }
        let e = self.error - floor;
        !(e * e <= k * k * sigma_r * sigma_r * self.var_factor)
    }
}

/// Predicts the point at range `r` (mm, from `origin`) along the unit beam direction
/// `(dx, dy)` from the `window` points (at least 2). `None` when the window does not define a
/// line (fewer than 2 points, all equal, or not finite). One pass over the window and one
/// square root.
pub fn predict_beam(
    window: &[Point],
    origin: Point,
    dx: f32,
    dy: f32,
    r: f32,
) -> Option<Prediction> {
    let (first, last) = (window.first()?, window.last()?);
    let n = window.len();
    if n < 2 {
        return None;
    }
    // Moments relative to the first point (the window is small: no cancellation).
    let (mut sx, mut sy, mut sxx, mut syy, mut sxy) = (0.0f32, 0.0f32, 0.0f32, 0.0f32, 0.0f32);
    for p in window {
        let (ex, ey) = (p.x - first.x, p.y - first.y);
        sx += ex;
        sy += ey;
        sxx += ex * ex;
        syy += ey * ey;
        sxy += ex * ey;
    }
    let nf = n as f32;
    let (mx, my) = (sx / nf, sy / nf);
    let (sxx, syy, sxy) = (sxx - sx * mx, syy - sy * my, sxy - sx * my);
    let c = Point::new(first.x + mx, first.y + my);
    // Principal axis (tx, ty) of [[sxx, sxy], [sxy, syy]], not normalised; normal (−ty, tx).
    let half = 0.5 * (sxx - syy);
    let suu = 0.5 * (sxx + syy) + math::sqrt(half * half + sxy * sxy);
    let (tx, ty) = if sxx >= syy {
        (suu - syy, sxy)
    } else {
        (sxy, suu - sxx)
    };
    let t2 = tx * tx + ty * ty;
    if !(t2 > 0.0) || !math::finite(t2) || !(suu > 0.0) {
        return None;
    }
    let (nx, ny) = (-ty, tx);
    let dn = dx * nx + dy * ny;
    let dt = dx * tx + dy * ty;
    let (wx, wy) = (c.x - origin.x, c.y - origin.y);
    // |dn| < 1e-6·|t| without a second square root (each costs ~50 instructions on the M4F).
    if dn * dn < 1e-12 * t2 {
        return Some(Prediction {
            error: f32::INFINITY,
            signed: f32::INFINITY,
            dn,
            dt,
            var_factor: f32::INFINITY,
        });
    }
    let t = (wx * nx + wy * ny) / dn;
    let (error, signed) = if t > 0.0 && math::finite(t) {
        (math::abs(r - t), r - t)
    } else {
        (f32::INFINITY, f32::INFINITY)
    };
    let ut = (origin.x + dx * t - c.x) * tx + (origin.y + dy * t - c.y) * ty;
    let lever = 1.0 / nf + ut * ut / (t2 * suu);
    // Incidence at the window's last point: sin²ϕ̄ = (l·n)² / (|l|² |n|²); sin²ϕ = dn²/|n|².
    let (lx, ly) = (last.x - origin.x, last.y - origin.y);
    let ln = lx * nx + ly * ny;
    let l2 = lx * lx + ly * ly;
    let ratio2 = if l2 > 0.0 {
        ln * ln / (l2 * dn * dn)
    } else {
        1.0 / (dn * dn) * t2
    };
    Some(Prediction {
        error,
        signed,
        dn,
        dt,
        var_factor: 1.0 + lever * ratio2,
    })
}

/// Predicts `target` (seen from `origin`) from the `window` points (at least 2).
///
/// ```
/// use pfe_core::{predict::predict, Point};
/// // Three points of the wall x = 1000; the next beam hits it at (1000, 300).
/// let w = [Point::new(1000.0, 0.0), Point::new(1000.0, 100.0), Point::new(1000.0, 200.0)];
/// let p = predict(&w, Point::new(1010.0, 303.0), Point::new(0.0, 0.0));
/// assert!(p.is_some_and(|p| (p.signed - 1010.0f32.hypot(303.0) + 1000.0f32.hypot(300.0)).abs() < 1e-2));
/// ```
pub fn predict(window: &[Point], target: Point, origin: Point) -> Option<Prediction> {
    let (bx, by) = (target.x - origin.x, target.y - origin.y);
    let r = math::hypot(bx, by);
    if !(r > 0.0) || !math::finite(r) {
        return None;
    }
    predict_beam(window, origin, bx / r, by / r, r)
}

/// The paper's adaptive threshold (§3.6): `d_m = (d_0/λ)(r/r_max + (π − ϕ)/π)`, with
/// `r/r_max` clamped to (0, 1] and ϕ the acute angle between Line 1 and the beam.
///
/// ```
/// use pfe_core::predict::paper_threshold;
/// use core::f32::consts::FRAC_PI_2;
/// // Head-on at the maximum range: (50/2)(1 + 0.5) = 37.5 mm.
/// assert!((paper_threshold(50.0, 2.0, 8000.0, 8000.0, FRAC_PI_2) - 37.5).abs() < 1e-4);
/// ```
pub fn paper_threshold(d0: f32, lambda: f32, r: f32, r_max: f32, phi: f32) -> f32 {
    let rr = (r / r_max).clamp(0.0, 1.0);
    let phi = phi.clamp(0.0, core::f32::consts::FRAC_PI_2);
    (d0 / lambda) * (rr + (core::f32::consts::PI - phi) / core::f32::consts::PI)
}
