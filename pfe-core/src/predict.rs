//! Prediction (paper §3.1–3.2): the least-squares line through the `Np` preceding points
//! (Line 1) meets the test point's beam (Line 2) at the prediction point; the test point's
//! distance from it is the prediction error `D`.

use crate::geometry::{ray_line_intersection, Point};
use crate::line::fit_line_iter;
use crate::math;

/// Outcome of predicting one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prediction {
    /// `D(P_k, P_k^p)`, mm; infinite when Line 1 is parallel to the beam or behind the scanner.
    pub error: f32,
    /// Measured range minus predicted range, mm (positive: the point is behind Line 1).
    pub signed: f32,
    /// ϕ: the acute angle between Line 1 and the beam, rad, in [0, π/2].
    pub phi: f32,
    /// Standard deviation of `error` in units of σ_r for pure range noise:
    /// `sqrt(1 + (1/n + u²/S_uu) · sin²ϕ̄ / sin²ϕ)`, u the prediction point's position along
    /// Line 1 from the window's centroid, ϕ̄ the mean incidence of the window's beams.
    pub sigma_factor: f32,
}

/// Predicts `target` (seen from `origin`) from the `window` points (at least 2).
/// `None` when the window does not define a line.
pub fn predict<I>(window: I, target: Point, origin: Point) -> Option<Prediction>
where
    I: Iterator<Item = Point> + Clone,
{
    let line = fit_line_iter(window.clone()).ok()?;
    let (bx, by) = (target.x - origin.x, target.y - origin.y);
    let r = math::hypot(bx, by);
    if !(r > 0.0) {
        return None;
    }
    let (dx, dy) = (bx / r, by / r);
    let (nc, ns) = line.normal();
    let (tx, ty) = (-ns, nc);
    // sin ϕ = |beam · normal|, cos ϕ = |beam · tangent|.
    let sin_phi = math::abs(dx * nc + dy * ns);
    let cos_phi = math::abs(dx * tx + dy * ty);
    let phi = math::atan2(sin_phi, cos_phi);
    let suu = line.sxx * tx * tx + line.syy * ty * ty + 2.0 * line.sxy * tx * ty;
    let n = line.n as f32;
    // Mean incidence of the window's beams (their noise across Line 1 is σ_r sin ϕ_i).
    let mut sin_w = 0.0f32;
    for p in window {
        let (wx, wy) = (p.x - origin.x, p.y - origin.y);
        let wn = math::hypot(wx, wy);
        if wn > 0.0 {
            sin_w += math::abs((wx * nc + wy * ns) / wn);
        }
    }
    let sin_w = sin_w / n;
    let Some((t, _)) = ray_line_intersection(origin, dx, dy, line.alpha, line.rho) else {
        return Some(Prediction {
            error: f32::INFINITY,
            signed: f32::INFINITY,
            phi,
            sigma_factor: f32::INFINITY,
        });
    };
    let error = if t > 0.0 {
        math::abs(r - t)
    } else {
        f32::INFINITY
    };
    let pp = Point::new(origin.x + dx * t, origin.y + dy * t);
    let u = (pp.x - line.centroid.x) * tx + (pp.y - line.centroid.y) * ty;
    let lever = if suu > 0.0 {
        1.0 / n + u * u / suu
    } else {
        f32::INFINITY
    };
    let ratio = if sin_phi > 1e-6 {
        sin_w / sin_phi
    } else {
        f32::INFINITY
    };
    let sigma_factor = math::sqrt(1.0 + lever * ratio * ratio);
    Some(Prediction {
        error,
        signed: r - t,
        phi,
        sigma_factor,
    })
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
