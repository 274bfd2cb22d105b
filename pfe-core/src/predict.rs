//! Prediction (paper §3.1–3.2): the least-squares line through the `Np` preceding points
//! (Line 1) meets the test point's beam (Line 2) at the prediction point; the test point's
//! distance from it is the prediction error `D`. No trigonometry: the line's direction is the
//! principal axis of the window's centred moments (two square roots).

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
    /// sin ϕ, ϕ the acute angle between Line 1 and the beam.
    pub sin_phi: f32,
    /// cos ϕ.
    pub cos_phi: f32,
    /// Standard deviation of `error` in units of σ_r for pure range noise:
    /// `sqrt(1 + (1/n + u²/S_uu) · sin²ϕ̄ / sin²ϕ)`, u the prediction point's position along
    /// Line 1 from the window's centroid, `S_uu` the window's spread along Line 1, ϕ̄ the
    /// incidence of Line 1 at the window's centroid (its points' noise across Line 1 is
    /// σ_r sin ϕ̄).
    pub sigma_factor: f32,
}

impl Prediction {
    /// ϕ in radians, in [0, π/2].
    pub fn phi(&self) -> f32 {
        math::atan2(self.sin_phi, self.cos_phi)
    }
}

/// Predicts the point at range `r` (mm, from `origin`) along the unit beam direction
/// `(dx, dy)` from the `window` points (at least 2). `None` when the window does not define a
/// line (fewer than 2 points, all equal, or not finite).
pub fn predict_beam<I>(window: I, origin: Point, dx: f32, dy: f32, r: f32) -> Option<Prediction>
where
    I: Iterator<Item = Point> + Clone,
{
    let (mut n, mut sx, mut sy) = (0usize, 0.0f32, 0.0f32);
    for p in window.clone() {
        n += 1;
        sx += p.x;
        sy += p.y;
    }
    if n < 2 {
        return None;
    }
    let nf = n as f32;
    let c = Point::new(sx / nf, sy / nf);
    let (mut sxx, mut syy, mut sxy) = (0.0f32, 0.0f32, 0.0f32);
    for p in window {
        let (ex, ey) = (p.x - c.x, p.y - c.y);
        sxx += ex * ex;
        syy += ey * ey;
        sxy += ex * ey;
    }
    // Principal axis of [[sxx, sxy], [sxy, syy]].
    let half = 0.5 * (sxx - syy);
    let root = math::sqrt(half * half + sxy * sxy);
    let suu = 0.5 * (sxx + syy) + root;
    let (tx, ty) = if sxx >= syy {
        (suu - syy, sxy)
    } else {
        (sxy, suu - sxx)
    };
    let norm = math::hypot(tx, ty);
    if !(norm > 0.0) || !norm.is_finite() || !(suu > 0.0) {
        return None;
    }
    let (tx, ty) = (tx / norm, ty / norm);
    let (nx, ny) = (-ty, tx);
    let denom = dx * nx + dy * ny;
    let sin_phi = math::abs(denom);
    let cos_phi = math::abs(dx * tx + dy * ty);
    // Incidence of Line 1 at the window's centroid.
    let (wx, wy) = (c.x - origin.x, c.y - origin.y);
    let wn = math::hypot(wx, wy);
    let sin_w = if wn > 0.0 {
        math::abs(wx * nx + wy * ny) / wn
    } else {
        1.0
    };
    if sin_phi < 1e-6 {
        return Some(Prediction {
            error: f32::INFINITY,
            signed: f32::INFINITY,
            sin_phi,
            cos_phi,
            sigma_factor: f32::INFINITY,
        });
    }
    let t = (wx * nx + wy * ny) / denom;
    let (error, signed) = if t > 0.0 && t.is_finite() {
        (math::abs(r - t), r - t)
    } else {
        (f32::INFINITY, f32::INFINITY)
    };
    let u = (origin.x + dx * t - c.x) * tx + (origin.y + dy * t - c.y) * ty;
    let lever = 1.0 / nf + u * u / suu;
    let ratio = sin_w / sin_phi;
    let sigma_factor = math::sqrt(1.0 + lever * ratio * ratio);
    Some(Prediction {
        error,
        signed,
        sin_phi,
        cos_phi,
        sigma_factor,
    })
}

/// Predicts `target` (seen from `origin`) from the `window` points (at least 2).
///
/// ```
/// use pfe_core::{predict::predict, Point};
/// // Three points of the wall x = 1000; the next beam hits it at (1000, 300).
/// let w = [Point::new(1000.0, 0.0), Point::new(1000.0, 100.0), Point::new(1000.0, 200.0)];
/// let p = predict(w.iter().copied(), Point::new(1010.0, 303.0), Point::new(0.0, 0.0)).unwrap();
/// assert!((p.signed - 1010.0f32.hypot(303.0) + 1000.0f32.hypot(300.0)).abs() < 1e-2);
/// ```
pub fn predict<I>(window: I, target: Point, origin: Point) -> Option<Prediction>
where
    I: Iterator<Item = Point> + Clone,
{
    let (bx, by) = (target.x - origin.x, target.y - origin.y);
    let r = math::hypot(bx, by);
    if !(r > 0.0) || !r.is_finite() {
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
