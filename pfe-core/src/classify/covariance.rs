//! How honest a feature's covariance is made in the default mode: the fit's covariance under
//! the range noise grows with a significant scatter the noise does not explain
//! ([`scatter_scale`]), or, when that scatter is also correlated from beam to beam (a rippled
//! or bent wall, a slowly varying bias: residuals that do not average out over the points),
//! with the scatter and its correlation ([`correlated_scale`]); the share of a systematic
//! range error its beams have in common is added ([`systematic_line`],
//! [`systematic_circle`]). (The error of the estimated offsets that moved interleaved sweeps
//! onto sweep 0 is added to every feature after the fits: `sweeps::inherit`.)

use crate::feature::{CircleFeature, LineFeature};
use crate::geometry::Point;
use crate::math;
use crate::pass::Pass;

/// Largest lag-one correlation of the correlated error [`correlated_scale`] takes.
const MAX_CORRELATION: f32 = 0.9;

/// The mean share of range noise along the fitted curve's normal, cos²β, over the points `pts`
/// of beams `s..` (β the incidence of each point's beam on the normal `normal(p)`, which need
/// not be a unit vector): the variance of a residual is σ_r² cos²β. 1 when no point tells.
pub(super) fn mean_cos2(
    pass: &Pass<'_>,
    s: usize,
    pts: &[Point],
    normal: impl Fn(Point) -> Point,
) -> f32 {
    if pass.motion.is_none() {
        return mean_cos2_still(pts, normal);
    }
    let mut mean = MeanCos2::default();
    for (i, &p) in pts.iter().enumerate() {
        mean.add(cos2(p, pass.origin(s + i), normal(p)));
    }
    mean.get()
}

/// [`mean_cos2`] with every beam from the origin (a scan not de-skewed): the shares of
/// [`BLOCK`] points at a time, element by element (which vectorises on the host), then summed
/// in order, as one at a time.
pub(super) fn mean_cos2_still(pts: &[Point], normal: impl Fn(Point) -> Point) -> f32 {
    let o = Point::new(0.0, 0.0);
    let mut mean = MeanCos2::default();
    let mut blocks = pts.chunks_exact(BLOCK);
    for block in &mut blocks {
        let mut c2 = [0.0f32; BLOCK];
        for (c, &p) in c2.iter_mut().zip(block) {
            *c = cos2(p, o, normal(p));
        }
        c2.into_iter().for_each(|c| mean.add(c));
    }
    for &p in blocks.remainder() {
        mean.add(cos2(p, o, normal(p)));
    }
    mean.get()
}

/// The running mean of [`mean_cos2`]: of the finite shares, in the order added.
#[derive(Default)]
struct MeanCos2 {
    sum: f32,
    n: usize,
}

impl MeanCos2 {
    #[inline(always)]
    fn add(&mut self, c2: f32) {
        if math::finite(c2) {
            self.sum += c2;
            self.n += 1;
        }
    }

    /// The mean, 1 when no share was finite.
    fn get(&self) -> f32 {
        if self.n > 0 {
            self.sum / self.n as f32
        } else {
            1.0
        }
    }
}

/// Points whose shares [`mean_cos2`] computes at once.
const BLOCK: usize = 8;

/// cos² of the angle between the beam from `o` to `p` and the normal `m` (NaN when either is
/// zero).
#[inline(always)]
fn cos2(p: Point, o: Point, m: Point) -> f32 {
    let d = Point::new(p.x - o.x, p.y - o.y);
    (d.x * m.x + d.y * m.y) * (d.x * m.x + d.y * m.y)
        / ((d.x * d.x + d.y * d.y) * (m.x * m.x + m.y * m.y))
}

/// Adds the share of a beam-to-beam systematic range error σ_sys (`s`, mm) to a line's
/// covariance: an offset σ_sys along the normal (ρ) and a tilt about the line's middle M of
/// variance 2σ_sys²/L² (its two ends independent), which moves ρ by the tilt times M's position
/// along the line.
pub(super) fn systematic_line(lf: &mut LineFeature, s: f32) {
    if !(s > 0.0) {
        return;
    }
    let (dx, dy) = (lf.end.x - lf.start.x, lf.end.y - lf.start.y);
    let len2 = dx * dx + dy * dy;
    if !(len2 > 0.0) {
        return;
    }
    let tilt = 2.0 * s * s / len2;
    let (sin, cos) = math::sin_cos(lf.alpha);
    // M · t, t = (−sin α, cos α) the line's direction.
    let along = 0.5 * ((lf.start.x + lf.end.x) * -sin + (lf.start.y + lf.end.y) * cos);
    lf.var_alpha += tilt;
    lf.cov_alpha_rho += tilt * along;
    lf.var_rho += s * s + tilt * along * along;
}

/// Adds the share of a beam-to-beam systematic range error σ_sys (`s`, mm) to a circle's
/// centre covariance: σ_sys² along the beam from the scanner (`origin`) to the centre (an
/// offset common to its beams moves every point, and so the centre, that way).
pub(super) fn systematic_circle(cf: &mut CircleFeature, origin: Point, s: f32) {
    let (dx, dy) = (cf.center.x - origin.x, cf.center.y - origin.y);
    let d2 = dx * dx + dy * dy;
    if !(s > 0.0 && d2 > 0.0) {
        return;
    }
    let k = s * s / d2;
    let [[xx, xy, _], [yx, yy, _], _] = &mut cf.cov;
    *xx += k * dx * dx;
    *xy += k * dx * dy;
    *yx += k * dx * dy;
    *yy += k * dy * dy;
}

/// Factor on a fit's covariance: its reduced χ², `sse / (var · dof)` (`var` the variance of a
/// residual under the noise model), when that exceeds 1 by more than three standard deviations
/// of its sampling spread √(2/dof); otherwise 1 (the noise model explains the scatter). No
/// division unless it scales.
pub(super) fn scatter_scale(sse: f32, var: f32, dof: f32) -> f32 {
    let expected = var * dof;
    // sse/expected − 1 > 3 √(2/dof), squared and times expected².
    let excess = sse - expected;
    if !(dof >= 1.0
        && expected > 0.0
        && excess > 0.0
        && excess * excess * dof > 18.0 * expected * expected)
    {
        return 1.0;
    }
    let ratio = sse / expected;
    if math::finite(ratio) {
        ratio
    } else {
        1.0
    }
}

/// Factor on a fit's covariance when its residuals `residuals` (in beam order) are correlated
/// from one beam to the next; `None` when they are not, or when the factor is not finite
/// (`var` = 0). The caller asks only where [`scatter_scale`] finds the scatter significant
/// (and keeps its factor on `None`): the correlation of a scatter the noise explains is
/// chance.
///
/// `var` is a residual's variance under the noise model and `dof` the residuals less the
/// fit's parameters. The residuals are taken as independent noise of variance `var` plus an
/// AR(1) error of variance τ² = sse/dof − var whose neighbours correlate by φ = γ₁/τ², γ₁ =
/// Σ eᵢeᵢ₊₁/(n − 1): the variance of a mean of n of them is (var + τ² f(φ, n))/n against
/// var/n, f the AR(1) variance factor [`ar1_factor`], so the factor is 1 + (τ²/var) f, used
/// for every parameter of the fit. Correlated: the residuals' lag-one autocorrelation
/// Σ eᵢeᵢ₊₁ / Σ eᵢ² exceeds two standard deviations of its spread under independent noise,
/// 2/√n, and τ² > 0. φ is taken at most 0.9. A correlated error that the fit absorbs (a slow
/// bend over the whole line moves the line) does not show in its residuals: one scan cannot
/// tell it.
pub(super) fn correlated_scale(
    residuals: impl Iterator<Item = f32>,
    var: f32,
    dof: f32,
) -> Option<f32> {
    let (mut sse, mut lag, mut n) = (0.0f32, 0.0f32, 0usize);
    let mut prev: Option<f32> = None;
    for e in residuals {
        sse += e * e;
        if let Some(p) = prev {
            lag += p * e;
        }
        prev = Some(e);
        n += 1;
    }
    let r = lag / sse;
    let tau2 = sse / dof - var;
    // r > 2/√n, squared; τ² > 0. (var = 0 gives an infinite factor, refused below.)
    if !(math::finite(r) && r > 0.0 && r * r * n as f32 > 4.0 && tau2 > 0.0) {
        return None;
    }
    let phi = lag / (n.saturating_sub(1) as f32 * tau2);
    let phi = phi.min(MAX_CORRELATION);
    let k = 1.0 + tau2 / var * ar1_factor(phi, n);
    math::finite(k).then_some(k)
}

/// How much more the mean of `n` consecutive values of an AR(1) process with lag-one
/// correlation `phi` (0 ≤ φ < 1) varies than that of `n` independent ones:
/// 1 + 2 Σₖ (1 − k/n) φᵏ = (1 + φ)/(1 − φ) − 2φ(1 − φⁿ)/(n(1 − φ)²).
pub(super) fn ar1_factor(phi: f32, n: usize) -> f32 {
    if n < 2 {
        return 1.0;
    }
    let q = 1.0 - phi;
    (1.0 + phi) / q - 2.0 * phi * (1.0 - powi(phi, n)) / (n as f32 * q * q)
}

/// `x` to the power `n` by squaring.
fn powi(mut x: f32, mut n: usize) -> f32 {
    let mut acc = 1.0f32;
    while n > 0 {
        if n & 1 == 1 {
            acc *= x;
        }
        x *= x;
        n >>= 1;
    }
    acc
}
