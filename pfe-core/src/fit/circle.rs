//! Circle fits (paper §3.5): the paper's algebraic (Kåsa) fit on centred data, the less biased
//! Taubin and Hyper fits (Al-Sharadqah & Chernov 2009), a geometric (Gauss–Newton with
//! Levenberg damping) refinement, and the covariance `V[Θ] = σ² (WᵀW)⁻¹`.

use crate::error::FitError;
use crate::geometry::Point;
use crate::math;

/// A circle.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Circle {
    /// Centre, mm.
    pub center: Point,
    /// Radius, mm.
    pub radius: f32,
}

/// Which algebraic fit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CircleMethod {
    /// Kåsa: minimises Σ(x²+y²−2ax−2by+a²+b²−R²)²; biased to small radii on short arcs.
    Kasa,
    /// Taubin: gradient-weighted algebraic fit.
    Taubin,
    /// Hyper (Al-Sharadqah & Chernov): no essential bias to second order.
    Hyper,
}

/// Centred, scaled moments (means) of a point set: the common input of the algebraic fits.
struct Moments {
    mean: Point,
    scale: f32,
    mxx: f32,
    myy: f32,
    mxy: f32,
    mxz: f32,
    myz: f32,
    mzz: f32,
}

fn moments(points: &[Point]) -> Result<Moments, FitError> {
    let n = points.len();
    let Some(first) = points.first().filter(|_| n >= 3) else {
        return Err(FitError::TooFewPoints { got: n, need: 3 });
    };
    // Mean and spread in one pass, relative to the first point (an arc's points are close
    // together compared with their distance from the scanner: no cancellation to speak of).
    let (mut sx, mut sy, mut sq) = (0.0f32, 0.0f32, 0.0f32);
    for p in points {
        let (ex, ey) = (p.x - first.x, p.y - first.y);
        sx += ex;
        sy += ey;
        sq += ex * ex + ey * ey;
    }
    if !(math::finite(sx) && math::finite(sy) && math::finite(sq)) {
        return Err(FitError::NonFinite);
    }
    let inv_n = 1.0 / n as f32;
    let (mx, my) = (sx * inv_n, sy * inv_n);
    let mean = Point::new(first.x + mx, first.y + my);
    let scale = math::sqrt((sq - sx * mx - sy * my) * inv_n);
    if !(scale > 0.0) {
        return Err(FitError::Degenerate);
    }
    let inv_scale = 1.0 / scale;
    let mut m = Moments {
        mean,
        scale,
        mxx: 0.0,
        myy: 0.0,
        mxy: 0.0,
        mxz: 0.0,
        myz: 0.0,
        mzz: 0.0,
    };
    for p in points {
        let x = (p.x - mean.x) * inv_scale;
        let y = (p.y - mean.y) * inv_scale;
        let z = x * x + y * y;
        m.mxx += x * x;
        m.myy += y * y;
        m.mxy += x * y;
        m.mxz += x * z;
        m.myz += y * z;
        m.mzz += z * z;
    }
    m.mxx *= inv_n;
    m.myy *= inv_n;
    m.mxy *= inv_n;
    m.mxz *= inv_n;
    m.myz *= inv_n;
    m.mzz *= inv_n;
    Ok(m)
}

/// Sums of a short run of points about its middle point, enough for both its least-squares
/// line's residual sum and its Kåsa circle, from one pass (the extractor's arc test).
pub(crate) struct ArcSums {
    n: f32,
    origin: Point,
    /// Σx, Σy, Σx², Σy², Σxy, Σxz, Σyz with z = x² + y² (coordinates about `origin`).
    s: [f32; 7],
}

impl ArcSums {
    /// The sums of `points` (at least 3, finite).
    pub(crate) fn of(points: &[Point]) -> Option<Self> {
        let n = points.len();
        let o = *points.get(n / 2).filter(|_| n >= 3)?;
        let add = |s: [f32; 7], p: &Point| {
            let (x, y) = (p.x - o.x, p.y - o.y);
            let (xx, yy, xy) = (x * x, y * y, x * y);
            let z = xx + yy;
            [
                s[0] + x,
                s[1] + y,
                s[2] + xx,
                s[3] + yy,
                s[4] + xy,
                s[5] + x * z,
                s[6] + y * z,
            ]
        };
        // Two points an iteration (the same sums in the same order).
        let mut s = [0.0f32; 7];
        let mut pairs = points.chunks_exact(2);
        for pair in pairs.by_ref() {
            if let [a, b] = pair {
                s = add(add(s, a), b);
            }
        }
        let s = pairs.remainder().iter().fold(s, add);
        s.iter().all(|v| math::finite(*v)).then_some(Self {
            n: n as f32,
            origin: o,
            s,
        })
    }

    /// Mean offset from the origin and the centred second moments Suu, Svv, Suv.
    fn centred(&self) -> (f32, f32, f32, f32, f32) {
        let [sx, sy, sxx, syy, sxy, ..] = self.s;
        let (a, b) = (sx / self.n, sy / self.n);
        (a, b, sxx - sx * a, syy - sy * b, sxy - sx * b)
    }

    /// Residual sum of the least-squares line (the smaller scatter eigenvalue, ≥ 0).
    pub(crate) fn line_sse(&self) -> f32 {
        let (_, _, suu, svv, suv) = self.centred();
        crate::fit::line::smaller_eigenvalue(suu, svv, suv)
    }

    /// The Kåsa circle (as [`fit_circle`] with [`CircleMethod::Kasa`], from centred moments).
    pub(crate) fn kasa(&self) -> Option<Circle> {
        let [_, _, sxx, syy, sxy, sxz, syz] = self.s;
        let n = self.n;
        let (a, b, suu, svv, suv) = self.centred();
        // Centred third moments: Σu³ + Σuv² and Σu²v + Σv³ (u = x − a, v = y − b).
        let uz = sxz - 3.0 * a * sxx + 2.0 * n * a * a * a - 2.0 * b * sxy - a * syy
            + 2.0 * n * a * b * b;
        let vz = syz - 2.0 * a * sxy - b * sxx + 2.0 * n * a * a * b - 3.0 * b * syy
            + 2.0 * n * b * b * b;
        // [Suu Suv; Suv Svv] [B C]ᵀ = −[Suz Svz]ᵀ; centre (−B/2, −C/2) from the centroid.
        let det = suu * svv - suv * suv;
        let spread = suu + svv;
        if !(det > 1e-10 * spread * spread) {
            return None;
        }
        let bb = -(uz * svv - vz * suv) / det;
        let cc = -(vz * suu - uz * suv) / det;
        let (xc, yc) = (-0.5 * bb, -0.5 * cc);
        let r2 = xc * xc + yc * yc + spread / n;
        let circle = Circle {
            center: Point::new(self.origin.x + a + xc, self.origin.y + b + yc),
            radius: math::sqrt(r2),
        };
        (circle.center.is_valid() && math::finite(circle.radius) && circle.radius > 0.0)
            .then_some(circle)
    }
}

/// Algebraic circle fit of `points` (at least 3, finite, not collinear).
///
/// ```
/// use pfe_core::{fit_circle, CircleMethod, Point};
/// let pts: Vec<Point> = (0..20).map(|i| {
///     let t = 0.1 * i as f32;
///     Point::new(2000.0 + 300.0 * t.cos(), 100.0 + 300.0 * t.sin())
/// }).collect();
/// let c = fit_circle(&pts, CircleMethod::Hyper)?;
/// assert!((c.radius - 300.0).abs() < 0.1);
/// # Ok::<(), pfe_core::FitError>(())
/// ```
pub fn fit_circle(points: &[Point], method: CircleMethod) -> Result<Circle, FitError> {
    let m = moments(points)?;
    let mz = m.mxx + m.myy;
    let cov_xy = m.mxx * m.myy - m.mxy * m.mxy;
    let (xc, yc, r2) = match method {
        CircleMethod::Kasa => {
            // [Mxx Mxy; Mxy Myy] [B C]ᵀ = −[Mxz Myz]ᵀ, a = −B/2, b = −C/2, R² = a² + b² + Mz.
            if !(math::abs(cov_xy) > 1e-10) {
                return Err(FitError::Degenerate);
            }
            let b = -(m.mxz * m.myy - m.myz * m.mxy) / cov_xy;
            let c = -(m.myz * m.mxx - m.mxz * m.mxy) / cov_xy;
            let (xc, yc) = (-0.5 * b, -0.5 * c);
            (xc, yc, xc * xc + yc * yc + mz)
        }
        CircleMethod::Taubin | CircleMethod::Hyper => {
            // Chernov's Newton iteration on the characteristic polynomial, from η = 0.
            let var_z = m.mzz - mz * mz;
            let a1 = var_z * mz + 4.0 * cov_xy * mz - m.mxz * m.mxz - m.myz * m.myz;
            let a0 = m.mxz * (m.mxz * m.myy - m.myz * m.mxy)
                + m.myz * (m.myz * m.mxx - m.mxz * m.mxy)
                - var_z * cov_xy;
            let hyper = method == CircleMethod::Hyper;
            let (a2, a3) = if hyper {
                (4.0 * cov_xy - 3.0 * mz * mz - m.mzz, 0.0)
            } else {
                (-3.0 * mz * mz - m.mzz, 4.0 * mz)
            };
            let poly = |x: f32| {
                if hyper {
                    a0 + x * (a1 + x * (a2 + 4.0 * x * x))
                } else {
                    a0 + x * (a1 + x * (a2 + x * a3))
                }
            };
            let dpoly = |x: f32| {
                if hyper {
                    a1 + x * (2.0 * a2 + 16.0 * x * x)
                } else {
                    a1 + x * (2.0 * a2 + 3.0 * a3 * x)
                }
            };
            let (mut x, mut y) = (0.0f32, a0);
            for _ in 0..20 {
                let dy = dpoly(x);
                let xn = x - y / dy;
                if !math::finite(xn) || xn == x {
                    break;
                }
                let yn = poly(xn);
                if math::abs(yn) >= math::abs(y) {
                    break;
                }
                x = xn;
                y = yn;
            }
            let det = x * x - x * mz + cov_xy;
            if !(math::abs(det) > 1e-12) {
                return Err(FitError::Degenerate);
            }
            let xc = (m.mxz * (m.myy - x) - m.myz * m.mxy) / det / 2.0;
            let yc = (m.myz * (m.mxx - x) - m.mxz * m.mxy) / det / 2.0;
            let r2 = if hyper {
                xc * xc + yc * yc + mz - 2.0 * x
            } else {
                xc * xc + yc * yc + mz
            };
            (xc, yc, r2)
        }
    };
    let circle = Circle {
        center: Point::new(m.mean.x + xc * m.scale, m.mean.y + yc * m.scale),
        radius: math::sqrt(r2) * m.scale,
    };
    if circle.center.is_valid() && math::finite(circle.radius) && circle.radius > 0.0 {
        Ok(circle)
    } else {
        Err(FitError::Degenerate)
    }
}

/// Smallest refinement step worth evaluating, mm (a hundredth of a millimetre: far below the
/// fitted parameters' own uncertainty for any range noise worth modelling).
const STEP_TOL: f32 = 1e-2;

/// Relative residual-sum gain below which a refinement step ends the refinement (the sum's
/// own relative spread is √(2/n), tens of percent).
const GAIN_TOL: f32 = 1e-5;

/// Geometric refinement: Gauss–Newton with Levenberg damping on Σ(|P_i − c| − R)², at most
/// `iterations` steps, from `initial`. Returns the better of the refined and the initial circle.
pub fn refine_circle(
    points: &[Point],
    initial: Circle,
    iterations: usize,
) -> Result<Circle, FitError> {
    refine_from(
        points,
        initial,
        NormalEquations::at(points, &initial),
        iterations,
    )
    .map(|(c, _)| c)
}

/// [`refine_circle`] from `initial` whose normal equations `eq` are already known; also
/// returns the refined circle's [`geometric_sse`].
pub(crate) fn refine_from(
    points: &[Point],
    initial: Circle,
    mut eq: NormalEquations,
    iterations: usize,
) -> Result<(Circle, f32), FitError> {
    if points.len() < 3 {
        return Err(FitError::TooFewPoints {
            got: points.len(),
            need: 3,
        });
    }
    let mut best = initial;
    // One pass per candidate gives its SSE and, for the next step, its normal equations.
    if !math::finite(eq.sse) {
        return Err(FitError::NonFinite);
    }
    let mut lambda = 1e-3f32;
    for _ in 0..iterations {
        let mut improved = false;
        for _ in 0..4 {
            let mut a = eq.jtj;
            a[0][0] *= 1.0 + lambda;
            a[1][1] *= 1.0 + lambda;
            a[2][2] *= 1.0 + lambda;
            let Some(step) = solve3(&a, &eq.jtr) else {
                break;
            };
            // Converged: a step this small changes nothing that matters (and would cost a
            // pass over the points to evaluate).
            if step[0] * step[0] + step[1] * step[1] + step[2] * step[2] < STEP_TOL * STEP_TOL {
                break;
            }
            let cand = Circle {
                center: Point::new(best.center.x - step[0], best.center.y - step[1]),
                radius: best.radius - step[2],
            };
            // A candidate of no positive radius is never taken: not summed.
            if !(cand.radius > 0.0) {
                lambda *= 10.0;
                continue;
            }
            let at_cand = NormalEquations::at(points, &cand);
            let sse = at_cand.sse;
            if math::finite(sse) && sse < eq.sse {
                let gain = eq.sse - sse;
                best = cand;
                eq = at_cand;
                // (A comparison: `f32::max` is a libm call on thumbv7em.)
                let smaller = lambda * 0.3;
                lambda = if smaller > 1e-7 { smaller } else { 1e-7 };
                improved = gain > sse * GAIN_TOL;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    Ok((best, eq.sse))
}

/// Gauss–Newton normal equations `JᵀJ`, `Jᵀr` of the geometric residuals `|P_i − c| − R` at
/// one circle, with their sum of squares.
pub(crate) struct NormalEquations {
    jtj: [[f32; 3]; 3],
    /// `Jᵀr`: half the gradient of the residual sum in (centre x, centre y, radius).
    pub(crate) jtr: [f32; 3],
    /// `Σ (|P_i − c| − R)²` ([`geometric_sse`]).
    pub(crate) sse: f32,
}

impl NormalEquations {
    /// The equations of `points` at the circle `c` (not inlined, its sums locals written out
    /// once: they stay in registers, where sums in the answer's slot are stored at every point
    /// around the square root's call).
    #[inline(never)]
    pub(crate) fn at(points: &[Point], c: &Circle) -> Self {
        let (mut sse, mut jtr) = (0.0f32, [0.0f32; 3]);
        let mut jtj = OuterSum::default();
        for p in points {
            let (dx, dy) = (p.x - c.center.x, p.y - c.center.y);
            let d = math::hypot(dx, dy);
            let r = d - c.radius;
            sse += r * r;
            if !(d > 0.0) {
                continue;
            }
            // J_i = (−dx/d, −dy/d, −1).
            let inv_d = 1.0 / d;
            let (a, b) = (-dx * inv_d, -dy * inv_d);
            jtj.add([a, b, -1.0]);
            let [j0, j1, j2] = jtr;
            jtr = [j0 + a * r, j1 + b * r, j2 - r];
        }
        NormalEquations {
            jtj: jtj.matrix(),
            jtr,
            sse,
        }
    }
}

/// A symmetric 3×3 sum of outer products `j jᵀ` (its six distinct entries; products with ±1
/// are exact).
#[derive(Clone, Copy, Default)]
struct OuterSum([f32; 6]);

impl OuterSum {
    #[inline]
    fn add(&mut self, [a, b, c]: [f32; 3]) {
        let [s00, s01, s02, s11, s12, s22] = self.0;
        self.0 = [
            s00 + a * a,
            s01 + a * b,
            s02 + a * c,
            s11 + b * b,
            s12 + b * c,
            s22 + c * c,
        ];
    }

    fn matrix(&self) -> [[f32; 3]; 3] {
        let [s00, s01, s02, s11, s12, s22] = self.0;
        [[s00, s01, s02], [s01, s11, s12], [s02, s12, s22]]
    }
}

/// Sum of squared geometric distances `(|P_i − c| − R)²`.
pub fn geometric_sse(points: &[Point], c: &Circle) -> f32 {
    points
        .iter()
        .map(|p| {
            let r = p.distance(&c.center) - c.radius;
            r * r
        })
        .sum()
}

/// `V[Θ] = σ² (WᵀW)⁻¹` for Θ = (a, b, R), W's rows `(u_i, v_i, 1)`, `u_i = (x_i − a)/R_i`,
/// `v_i = (y_i − b)/R_i` (Al-Sharadqah & Chernov 2009), for isotropic point noise `σ`.
pub fn circle_covariance(
    points: &[Point],
    circle: &Circle,
    sigma: f32,
) -> Result<[[f32; 3]; 3], FitError> {
    let inv = wtw_inverse(points, circle)?;
    Ok(scale3(&inv, sigma * sigma))
}

/// Covariance for range noise `σ_r` along each beam from `origin`: the sandwich
/// `(WᵀW)⁻¹ Wᵀ Σ W (WᵀW)⁻¹` with `Σ_ii = σ_r² cos² γ_i`, γ_i the angle between beam i and the
/// circle's normal there. Equals `σ² (WᵀW)⁻¹` when every beam meets the circle head on.
pub fn circle_covariance_range(
    points: &[Point],
    circle: &Circle,
    origin: Point,
    sigma_r: f32,
) -> Result<[[f32; 3]; 3], FitError> {
    // WᵀW and WᵀΣW in one pass.
    let (mut wtw, mut mid) = (OuterSum::default(), OuterSum::default());
    for p in points {
        let (dx, dy) = (p.x - circle.center.x, p.y - circle.center.y);
        let d = math::hypot(dx, dy);
        if !(d > 0.0) {
            continue;
        }
        let (u, v) = (dx / d, dy / d);
        wtw.add([u, v, 1.0]);
        let (bx, by) = (p.x - origin.x, p.y - origin.y);
        let bn = math::hypot(bx, by);
        if !(bn > 0.0) {
            continue;
        }
        let w = sigma_r * ((u * bx + v * by) / bn);
        mid.add([u * w, v * w, w]);
    }
    let inv = invert(points, &wtw)?;
    Ok(mul3(&mul3(&inv, &mid.matrix()), &inv))
}

fn wtw_inverse(points: &[Point], circle: &Circle) -> Result<[[f32; 3]; 3], FitError> {
    let mut wtw = OuterSum::default();
    for p in points {
        let (dx, dy) = (p.x - circle.center.x, p.y - circle.center.y);
        let d = math::hypot(dx, dy);
        if !(d > 0.0) {
            continue;
        }
        wtw.add([dx / d, dy / d, 1.0]);
    }
    invert(points, &wtw)
}

/// `(WᵀW)⁻¹` of the `points`' W (at least 3 of them, finite).
fn invert(points: &[Point], wtw: &OuterSum) -> Result<[[f32; 3]; 3], FitError> {
    if points.len() < 3 {
        return Err(FitError::TooFewPoints {
            got: points.len(),
            need: 3,
        });
    }
    let inv = inverse3(&wtw.matrix()).ok_or(FitError::Degenerate)?;
    if inv.iter().flatten().all(|v| math::finite(*v)) {
        Ok(inv)
    } else {
        Err(FitError::Degenerate)
    }
}

fn det3(a: &[[f32; 3]; 3]) -> f32 {
    let [[a00, a01, a02], [a10, a11, a12], [a20, a21, a22]] = *a;
    a00 * (a11 * a22 - a12 * a21) - a01 * (a10 * a22 - a12 * a20) + a02 * (a10 * a21 - a11 * a20)
}

/// Inverse of a 3×3 matrix by cofactors; `None` when singular relative to its scale.
pub(crate) fn inverse3(a: &[[f32; 3]; 3]) -> Option<[[f32; 3]; 3]> {
    let [[a00, a01, a02], [a10, a11, a12], [a20, a21, a22]] = *a;
    let det = det3(a);
    // The largest |entry| (a comparison: `f32::max` is a libm call on thumbv7em; a NaN entry
    // is skipped here and caught by the determinant's test).
    let norm = a.iter().flatten().fold(0.0f32, |m, v| {
        let v = math::abs(*v);
        if v > m {
            v
        } else {
            m
        }
    });
    if !(math::abs(det) > norm * norm * norm * 1e-9) || !math::finite(det) {
        return None;
    }
    let inv = 1.0 / det;
    Some([
        [
            (a11 * a22 - a12 * a21) * inv,
            (a02 * a21 - a01 * a22) * inv,
            (a01 * a12 - a02 * a11) * inv,
        ],
        [
            (a12 * a20 - a10 * a22) * inv,
            (a00 * a22 - a02 * a20) * inv,
            (a02 * a10 - a00 * a12) * inv,
        ],
        [
            (a10 * a21 - a11 * a20) * inv,
            (a01 * a20 - a00 * a21) * inv,
            (a00 * a11 - a01 * a10) * inv,
        ],
    ])
}

fn solve3(a: &[[f32; 3]; 3], b: &[f32; 3]) -> Option<[f32; 3]> {
    let inv = inverse3(a)?;
    let mut x = [0.0f32; 3];
    for (xi, row) in x.iter_mut().zip(inv.iter()) {
        *xi = row.iter().zip(b.iter()).map(|(m, v)| m * v).sum();
    }
    x.iter().all(|v| math::finite(*v)).then_some(x)
}

fn mul3(a: &[[f32; 3]; 3], b: &[[f32; 3]; 3]) -> [[f32; 3]; 3] {
    let mut c = [[0.0f32; 3]; 3];
    for (ci, ai) in c.iter_mut().zip(a.iter()) {
        for (j, cij) in ci.iter_mut().enumerate() {
            *cij = ai
                .iter()
                .zip(b.iter())
                .map(|(aik, bk)| aik * bk.get(j).copied().unwrap_or(0.0))
                .sum();
        }
    }
    c
}

fn scale3(a: &[[f32; 3]; 3], s: f32) -> [[f32; 3]; 3] {
    let mut c = *a;
    c.iter_mut().flatten().for_each(|v| *v *= s);
    c
}

#[cfg(test)]
#[path = "circle_tests.rs"]
mod tests;
