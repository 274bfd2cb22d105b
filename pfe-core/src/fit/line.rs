//! Line fit (paper §3.5): least squares in polar form `x cos α + y sin α = ρ`, from centred
//! moments in O(n) (the paper's double sums give the same estimate in O(n²)), and its covariance.

use crate::error::FitError;
use crate::geometry::Point;
use crate::math;

/// Points whose terms [`LineFit::covariance_range_of`] computes at once.
const BLOCK: usize = 8;

/// A fitted line and the moments it came from.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LineFit {
    /// Angle of the normal, rad, in (−π, π].
    pub alpha: f32,
    /// Distance from the origin, mm, ≥ 0.
    pub rho: f32,
    /// cos α (the unit normal's x).
    pub cos_alpha: f32,
    /// sin α (the unit normal's y).
    pub sin_alpha: f32,
    /// Number of points.
    pub n: usize,
    /// Centroid of the points.
    pub centroid: Point,
    /// Centred second moments Σ(x−x̄)², Σ(y−ȳ)², Σ(x−x̄)(y−ȳ).
    pub sxx: f32,
    /// See `sxx`.
    pub syy: f32,
    /// See `sxx`.
    pub sxy: f32,
}

/// Covariance of (α, ρ).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LineCovariance {
    /// σ_α², rad².
    pub var_alpha: f32,
    /// σ_ρ², mm².
    pub var_rho: f32,
    /// cov(α, ρ), rad·mm.
    pub cov_alpha_rho: f32,
}

/// Fits a line to `points` (all must be finite, at least 2, not all equal).
///
/// ```
/// use pfe_core::{fit_line, Point};
/// let pts = [Point::new(1000.0, -500.0), Point::new(1000.0, 0.0), Point::new(1000.0, 500.0)];
/// let l = fit_line(&pts)?;
/// assert!(l.alpha.abs() < 1e-6 && (l.rho - 1000.0).abs() < 1e-3);
/// # Ok::<(), pfe_core::FitError>(())
/// ```
pub fn fit_line(points: &[Point]) -> Result<LineFit, FitError> {
    LineFit::from_axis(fit_axis(points)?)
}

/// [`fit_line`] over any re-iterable sequence of points (two passes: mean, then centred sums).
pub fn fit_line_iter<I>(points: I) -> Result<LineFit, FitError>
where
    I: Iterator<Item = Point> + Clone,
{
    LineFit::from_axis(fit_axis_iter(points)?)
}

/// The line from centred moments: the normal is the minor principal axis (no trigonometry
/// but one `atan2` for α).
pub fn from_moments(
    n: usize,
    centroid: Point,
    sxx: f32,
    syy: f32,
    sxy: f32,
) -> Result<LineFit, FitError> {
    LineFit::from_axis(axis_from_moments(n, centroid, sxx, syy, sxy)?)
}

/// A fitted line without its angle α (no `atan2`): what the extractor's internal tests
/// (boundary refinement, arc test, boundary consistency) need.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LineAxis {
    n: usize,
    centroid: Point,
    /// Unit normal, pointing away from the origin.
    nx: f32,
    ny: f32,
    rho: f32,
    sxx: f32,
    syy: f32,
    sxy: f32,
}

impl LineAxis {
    /// Signed distance of `p` from the line.
    pub(crate) fn signed_distance(&self, p: &Point) -> f32 {
        p.x * self.nx + p.y * self.ny - self.rho
    }
}

/// A run of consecutive beams from the origin, as [`LineFit::covariance_beams`] needs it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BeamSpan {
    /// Number of beams.
    pub(crate) count: usize,
    /// Unit direction of the run's middle (a beam's, or halfway between two).
    pub(crate) mid: Point,
    /// Unit directions of the first and the last beam.
    pub(crate) ends: [Point; 2],
    /// `E = Σ_j 2 sin²(jδ)` over the beams' offsets `j` from the middle (…, −½, ½, … or
    /// …, −1, 0, 1, …) in steps `δ`: how far their directions fan out.
    pub(crate) spread: f32,
}

/// Fills `table[k]` with the [`BeamSpan::spread`] of `k + 1` beams `step` apart.
pub(crate) fn fill_spreads(table: &mut [f32], step: f32) {
    // From k − 1 to k + 1 beams, E grows by the two outermost, ±k/2 steps from the middle.
    let mut last = [0.0f32; 2];
    for (k, e) in table.iter_mut().enumerate() {
        let s = math::sin(0.5 * k as f32 * step);
        let [older, newer] = last;
        *e = older + 4.0 * s * s;
        last = [newer, *e];
    }
}

/// The mean offset `(x̄, ȳ)` and the centred moments `[Sxx, Syy, Sxy]` of points from their
/// sums `[Σx, Σy, Σx², Σy², Σxy]` about a point and `inv_n` = 1 / their number.
#[inline]
pub(crate) fn centre(sums: [f32; 5], inv_n: f32) -> ((f32, f32), [f32; 3]) {
    let [sx, sy, sxx, syy, sxy] = sums;
    let (mx, my) = (sx * inv_n, sy * inv_n);
    ((mx, my), [sxx - sx * mx, syy - sy * my, sxy - sx * my])
}

/// The larger eigenvalue of the scatter matrix `[[sxx, sxy], [sxy, syy]]` and an eigenvector
/// `(tx, ty)` of it (not normalised): a fitted line's spread along it and its direction.
pub(crate) fn major_axis(sxx: f32, syy: f32, sxy: f32) -> (f32, f32, f32) {
    let half = 0.5 * (sxx - syy);
    let major = 0.5 * (sxx + syy) + math::sqrt(half * half + sxy * sxy);
    let (tx, ty) = if sxx >= syy {
        (major - syy, sxy)
    } else {
        (sxy, major - sxx)
    };
    (major, tx, ty)
}

/// The smaller eigenvalue of `[[sxx, sxy], [sxy, syy]]`, at least 0: the residual sum of the
/// least-squares line.
pub(crate) fn smaller_eigenvalue(sxx: f32, syy: f32, sxy: f32) -> f32 {
    let half = 0.5 * (sxx - syy);
    let v = 0.5 * (sxx + syy) - math::sqrt(half * half + sxy * sxy);
    if v > 0.0 {
        v
    } else {
        0.0
    }
}

/// `[Σx, Σy, Σx², Σy², Σxy]` of `points` about `o` (a point near them: the sums stay small).
#[inline]
pub(crate) fn sums_about(points: &[Point], o: &Point) -> [f32; 5] {
    let mut s = [0.0f32; 5];
    let add = |[sx, sy, sxx, syy, sxy]: [f32; 5], p: &Point| {
        let (ex, ey) = (p.x - o.x, p.y - o.y);
        [
            sx + ex,
            sy + ey,
            sxx + ex * ex,
            syy + ey * ey,
            sxy + ex * ey,
        ]
    };
    // Two points an iteration (the same sums in the same order: half the loop overhead).
    let mut pairs = points.chunks_exact(2);
    for pair in pairs.by_ref() {
        if let [a, b] = pair {
            s = add(add(s, a), b);
        }
    }
    pairs.remainder().iter().fold(s, add)
}

/// Count, centroid and centred second moments of `points` in one pass (moments about the
/// middle point, centred afterwards).
fn centred_moments(points: &[Point]) -> Result<(usize, Point, f32, f32, f32), FitError> {
    let n = points.len();
    let Some(o) = points.get(n / 2).filter(|_| n >= 2) else {
        return Err(FitError::TooFewPoints { got: n, need: 2 });
    };
    let sums = sums_about(points, o);
    let [_, _, sxx, syy, sxy] = sums;
    if !(math::finite(sxx + syy) && math::finite(sxy)) {
        return Err(FitError::NonFinite);
    }
    let ((mx, my), [sxx, syy, sxy]) = centre(sums, 1.0 / n as f32);
    Ok((n, Point::new(o.x + mx, o.y + my), sxx, syy, sxy))
}

/// [`fit_line`] without α, in one pass over the points, with moments about the middle point
/// (centred afterwards: the moments about the middle point are at most about four times the
/// centred ones, so the rounding stays of the order of a two-pass fit's).
pub(crate) fn fit_axis(points: &[Point]) -> Result<LineAxis, FitError> {
    let (n, c, sxx, syy, sxy) = centred_moments(points)?;
    axis_from_moments(n, c, sxx, syy, sxy)
}

fn fit_axis_iter<I>(points: I) -> Result<LineAxis, FitError>
where
    I: Iterator<Item = Point> + Clone,
{
    let (mut n, mut sx, mut sy) = (0usize, 0.0f32, 0.0f32);
    for p in points.clone() {
        if !p.is_valid() {
            return Err(FitError::NonFinite);
        }
        n += 1;
        sx += p.x;
        sy += p.y;
    }
    if n < 2 {
        return Err(FitError::TooFewPoints { got: n, need: 2 });
    }
    let c = Point::new(sx / n as f32, sy / n as f32);
    let (mut sxx, mut syy, mut sxy) = (0.0f32, 0.0f32, 0.0f32);
    for p in points {
        let (dx, dy) = (p.x - c.x, p.y - c.y);
        sxx += dx * dx;
        syy += dy * dy;
        sxy += dx * dy;
    }
    axis_from_moments(n, c, sxx, syy, sxy)
}

fn axis_from_moments(
    n: usize,
    centroid: Point,
    sxx: f32,
    syy: f32,
    sxy: f32,
) -> Result<LineAxis, FitError> {
    let spread = sxx + syy;
    if !(spread > 0.0) || !math::finite(spread) {
        return Err(FitError::Degenerate);
    }
    // Major axis (tx, ty); the normal is (−ty, tx).
    let (_, tx, ty) = major_axis(sxx, syy, sxy);
    let norm = math::hypot(tx, ty);
    if !(norm > 0.0) || !math::finite(norm) {
        return Err(FitError::Degenerate);
    }
    let (mut nx, mut ny) = (-ty / norm, tx / norm);
    let mut rho = centroid.x * nx + centroid.y * ny;
    if rho < 0.0 {
        rho = -rho;
        nx = -nx;
        ny = -ny;
    }
    if !math::finite(rho) {
        return Err(FitError::Degenerate);
    }
    Ok(LineAxis {
        n,
        centroid,
        nx,
        ny,
        rho,
        sxx,
        syy,
        sxy,
    })
}

/// `Σ (residual)²` of centred moments about the line with unit normal `(c, s)`.
fn residual_sse(sxx: f32, syy: f32, sxy: f32, c: f32, s: f32) -> f32 {
    let v = sxx * c * c + syy * s * s + 2.0 * sxy * s * c;
    if v > 0.0 {
        v
    } else {
        0.0
    }
}

impl LineFit {
    fn from_axis(a: LineAxis) -> Result<LineFit, FitError> {
        let alpha = math::atan2(a.ny, a.nx);
        if !math::finite(alpha) {
            return Err(FitError::Degenerate);
        }
        Ok(LineFit {
            alpha,
            rho: a.rho,
            cos_alpha: a.nx,
            sin_alpha: a.ny,
            n: a.n,
            centroid: a.centroid,
            sxx: a.sxx,
            syy: a.syy,
            sxy: a.sxy,
        })
    }

    /// Unit normal (cos α, sin α).
    pub fn normal(&self) -> (f32, f32) {
        (self.cos_alpha, self.sin_alpha)
    }

    /// Signed distance of `p` from the line.
    pub fn signed_distance(&self, p: &Point) -> f32 {
        let (c, s) = self.normal();
        p.x * c + p.y * s - self.rho
    }

    /// Foot of the perpendicular from `p`.
    pub fn project(&self, p: &Point) -> Point {
        let (c, s) = self.normal();
        let d = p.x * c + p.y * s - self.rho;
        Point::new(p.x - d * c, p.y - d * s)
    }

    /// Sum of squared orthogonal residuals, from the moments (no pass over the points).
    pub fn sse(&self) -> f32 {
        residual_sse(self.sxx, self.syy, self.sxy, self.cos_alpha, self.sin_alpha)
    }

    /// Mean absolute distance of `points` from the line (the paper's d̄).
    pub fn mean_abs_distance(&self, points: &[Point]) -> f32 {
        if points.is_empty() {
            return 0.0;
        }
        let sum: f32 = points
            .iter()
            .map(|p| math::abs(self.signed_distance(p)))
            .sum();
        sum / points.len() as f32
    }

    /// Jensfelt & Christensen (2001) covariance for points that all have the Cartesian
    /// covariance `[[σxx², σxy²], [σxy², σyy²]]`:
    /// `A = (a σyy² − b σxy² + c σxx²) / ((a − c)² + b²)`, `σ_α² = A`,
    /// `σ_ρ² = (σyy² cos²χ + σxx² sin²χ − 2 σxy² sinχ cosχ)/N + d² A`, with `a = Sxx`,
    /// `b = 2 Sxy`, `c = Syy`, `χ = α + π/2`, `d = ȳ sinχ + x̄ cosχ`.
    pub fn covariance_jc(&self, var_xx: f32, var_yy: f32, var_xy: f32) -> LineCovariance {
        let (a, b, c) = (self.sxx, 2.0 * self.sxy, self.syy);
        let den = (a - c) * (a - c) + b * b;
        let big_a = if den > 0.0 {
            (a * var_yy - b * var_xy + c * var_xx) / den
        } else {
            f32::INFINITY
        };
        // χ = α + π/2: sin χ = cos α, cos χ = −sin α.
        let (sc, cc) = (self.cos_alpha, -self.sin_alpha);
        let d = self.centroid.y * sc + self.centroid.x * cc;
        let n = self.n.max(1) as f32;
        let var_rho =
            (var_yy * cc * cc + var_xx * sc * sc - 2.0 * var_xy * sc * cc) / n + d * d * big_a;
        LineCovariance {
            var_alpha: big_a,
            var_rho,
            // ρ = x̄cosα + ȳsinα moves with α through d (see `covariance_range`).
            cov_alpha_rho: d * big_a,
        }
    }

    /// Covariance for range noise `σ_r` along each beam from `origin` (first-order propagation,
    /// exact for an unweighted fit): a point's error across the line is `σ_r |cos β_i|`, β_i the
    /// angle between its beam and the normal. With `u_i` the position along the line, `d` the
    /// centroid's, `e` the perpendicular errors: `δα = −Σu_i e_i / Σu_i²`, `δρ = ē + d δα`.
    pub fn covariance_range<I>(&self, points: I, origin: Point, sigma_r: f32) -> LineCovariance
    where
        I: Iterator<Item = Point>,
    {
        let (nc, ns) = self.normal();
        let (tx, ty) = (-ns, nc);
        // Sums of u², u² cos²β, u cos²β and cos²β (σ_r² applied after), with b the beam
        // vector and u = b·t − (c − origin)·t.
        let ct = (self.centroid.x - origin.x) * tx + (self.centroid.y - origin.y) * ty;
        let (mut suu, mut suu_s, mut su_s, mut s_s) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
        for p in points {
            let (bx, by) = (p.x - origin.x, p.y - origin.y);
            let bdot = bx * nc + by * ns;
            // cos²β = (b·n)² / |b|², without a square root (0 for a point at the origin).
            let cos2b = bdot * bdot / (bx * bx + by * by + f32::MIN_POSITIVE);
            let u = bx * tx + by * ty - ct;
            let uc = u * cos2b;
            suu += u * u;
            suu_s += u * uc;
            su_s += uc;
            s_s += cos2b;
        }
        let d = self.centroid.x * tx + self.centroid.y * ty;
        self.covariance_from([suu, suu_s, su_s, s_s], d, sigma_r)
    }

    /// [`LineFit::covariance_range`] of the points `pts`, the same bit for bit: each point's
    /// terms (its lever and incidence, a division) [`BLOCK`] points at a time, element by element
    /// (which vectorises on the host), then summed in order.
    pub(crate) fn covariance_range_of(
        &self,
        pts: &[Point],
        origin: Point,
        sigma_r: f32,
    ) -> LineCovariance {
        let (nc, ns) = self.normal();
        let (tx, ty) = (-ns, nc);
        let ct = (self.centroid.x - origin.x) * tx + (self.centroid.y - origin.y) * ty;
        let terms = |p: &Point| {
            let (bx, by) = (p.x - origin.x, p.y - origin.y);
            let bdot = bx * nc + by * ns;
            let cos2b = bdot * bdot / (bx * bx + by * by + f32::MIN_POSITIVE);
            (bx * tx + by * ty - ct, cos2b)
        };
        let mut sums = [0.0f32; 4];
        let mut add = |(u, cos2b): (f32, f32)| {
            let uc = u * cos2b;
            sums = [
                sums[0] + u * u,
                sums[1] + u * uc,
                sums[2] + uc,
                sums[3] + cos2b,
            ];
        };
        let mut blocks = pts.chunks_exact(BLOCK);
        for block in &mut blocks {
            let mut t = [(0.0f32, 0.0f32); BLOCK];
            for (t, p) in t.iter_mut().zip(block) {
                *t = terms(p);
            }
            t.into_iter().for_each(&mut add);
        }
        blocks.remainder().iter().map(terms).for_each(&mut add);
        let d = self.centroid.x * tx + self.centroid.y * ty;
        self.covariance_from(sums, d, sigma_r)
    }

    /// `covariance_range` for the points of consecutive `beams` from the origin (`ends`: the
    /// first and the last), with each point's lever and incidence taken where its beam meets
    /// the line (the same first-order propagation, evaluated at the fitted points instead of
    /// the measured ones) and summed in closed form: no pass over the points. `None` when the
    /// beams meet the line more than 2 % of the run's length away from the measured ends (at
    /// grazing incidence, or for a line along the beams): then the fitted points are not a
    /// stand-in for the measured ones.
    pub(crate) fn covariance_beams(
        &self,
        beams: &BeamSpan,
        ends: [&Point; 2],
        sigma_r: f32,
    ) -> Option<LineCovariance> {
        let (nc, ns) = self.normal();
        let (tx, ty) = (-ns, nc);
        let [d0, d1] = beams.ends;
        let [p0, p1] = ends;
        // Where beam d meets the line minus where p projects on it, along the line.
        let shift = |d: &Point, p: &Point| {
            let c = d.x * nc + d.y * ns;
            (self.rho * (d.x * tx + d.y * ty) - (p.x * tx + p.y * ty) * c) / c
        };
        let length = (p1.x - p0.x) * tx + (p1.y - p0.y) * ty;
        if !(math::abs(shift(&d0, p0)) + math::abs(shift(&d1, p1)) <= 0.02 * math::abs(length)) {
            return None;
        }
        // Beam i meets the line at range ρ/cos φ_i, φ_i its angle from the normal, at
        // u_i = ρ tan φ_i − τ along it (τ the centroid's position), where cos²β_i = cos²φ_i.
        // With φ_i = φ + jδ (φ the span's middle, j the offsets from it), Σcos 2jδ = n − E
        // and Σsin 2jδ = 0: the sums of cos²φ_i, u_i cos²φ_i and u_i² cos²φ_i follow from
        // cos φ, sin φ and E.
        let (rho, tau) = (self.rho, self.centroid.x * tx + self.centroid.y * ty);
        let (c, a) = (
            beams.mid.x * nc + beams.mid.y * ns,
            beams.mid.x * tx + beams.mid.y * ty,
        );
        let (half_e, dn) = (0.5 * beams.spread, beams.count as f32 - beams.spread);
        // ρ sin φ − τ cos φ: u cos φ at the middle.
        let w = rho * a - tau * c;
        let s_s = half_e + dn * c * c;
        let su_s = dn * c * w - half_e * tau;
        let suu_s = half_e * (rho * rho + tau * tau) + dn * w * w;
        // Σu² of the measured points: the scatter along the line.
        let suu = self.sxx * tx * tx + 2.0 * self.sxy * tx * ty + self.syy * ty * ty;
        Some(self.covariance_from([suu, suu_s, su_s, s_s], tau, sigma_r))
    }

    /// The covariance from Σu², Σu² cos²β, Σu cos²β and Σcos²β (before σ_r²) and `d`, the
    /// centroid's position along the line.
    fn covariance_from(&self, sums: [f32; 4], d: f32, sigma_r: f32) -> LineCovariance {
        let var = sigma_r * sigma_r;
        let [suu, suu_s, su_s, s_s] = sums;
        let (suu_s, su_s, s_s) = (suu_s * var, su_s * var, s_s * var);
        let n = self.n.max(1) as f32;
        let var_alpha = if suu > 0.0 {
            suu_s / (suu * suu)
        } else {
            f32::INFINITY
        };
        let cov_e_a = if suu > 0.0 { -su_s / (n * suu) } else { 0.0 };
        let var_e = s_s / (n * n);
        // Σ var_i (1/n − d u_i / suu)² ≥ 0, summed by parts: when every beam runs along the
        // line (var_i ≈ 0) and the centroid is far out, the parts cancel below zero.
        let var_rho = var_e + d * d * var_alpha + 2.0 * d * cov_e_a;
        LineCovariance {
            var_alpha,
            var_rho: if var_rho < 0.0 { 0.0 } else { var_rho },
            cov_alpha_rho: cov_e_a + d * var_alpha,
        }
    }
}

#[cfg(test)]
#[path = "line_tests.rs"]
mod tests;

#[cfg(test)]
#[path = "line_block_tests.rs"]
mod block_tests;
