//! Prediction (paper §3.1–3.2): the least-squares line through the `Np` preceding points
//! (Line 1) meets the test point's beam (Line 2) at the prediction point; the test point's
//! distance from it is the prediction error `D`. No trigonometry: the line's direction is the
//! principal axis of the window's centred moments (one square root).

use crate::fit::line;
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
    /// ∝ sin ϕ (the beam direction times Line 1's normal, scaled).
    dn: f32,
    /// ∝ cos ϕ, with the same scale as `dn`.
    dt: f32,
    /// Variance of `error` in units of σ_r² for pure range noise:
    /// `1 + (1/n + u²/S_uu) · sin²ϕ̄ / sin²ϕ`, u the prediction point's position along Line 1
    /// from the window's centroid, `S_uu` the window's spread along Line 1, ϕ̄ the incidence of
    /// Line 1 at the window's last point (its points' noise across Line 1 is σ_r sin ϕ̄).
    pub var_factor: f32,
}

impl Prediction {
    /// The prediction of a beam that runs along Line 1: says nothing (infinite error).
    const fn along(dn: f32, dt: f32) -> Self {
        Self {
            error: f32::INFINITY,
            signed: f32::INFINITY,
            dn,
            dt,
            var_factor: f32::INFINITY,
        }
    }

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

/// Line 1 of a prediction: the least-squares line of a window of points (its principal axis:
/// one square root, no trigonometry), fitted once and able to predict any beam. The extractor
/// reuses one window's line for the next few beams while they fit it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WindowLine {
    /// Direction of the line, scaled so that its larger component is ±1 (|t|² = `t2` in
    /// [1, 2]: no square root to normalise it); the normal is `(−ty, tx)`, of the same length.
    tx: f32,
    ty: f32,
    /// 10⁻¹² |t|²: a beam with (d·n)² below this runs along the line.
    parallel: f32,
    /// The centroid's coordinates along the normal and along the line (times |t|).
    cn: f32,
    ct: f32,
    /// 1 / number of points.
    inv_n: f32,
    /// 1 / (|t|² Σu²), Σu² the window's spread along the line.
    inv_t2suu: f32,
    /// The lever `1/n + u²/Σu²` of the beam right after the window times `t2_sin2_last`, or
    /// NaN before [`Self::capped`] (then [`Self::accepts`] accepts nothing).
    lever_sin2: f32,
    /// |t|² sin²ϕ̄, ϕ̄ the incidence of the line at the window's last point, seen from the
    /// origin given to [`WindowLine::fit`] (sin²ϕ̄ = 1 when that point is the origin).
    t2_sin2_last: f32,
    /// The window's last point along the line from the centroid (times |t|), or NaN before
    /// [`Self::capped`].
    tail: f32,
}

impl WindowLine {
    /// The line of `window` (at least 2 points), its last point seen from `origin`. `None`
    /// when the window does not define a line (fewer than 2 points, all equal, not finite).
    pub fn fit(window: &[Point], origin: Point) -> Option<Self> {
        let (first, last) = (window.first()?, window.last()?);
        let n = window.len();
        if n < 2 {
            return None;
        }
        let inv_n = 1.0 / n as f32;
        let (c, suu, tx, ty) = if n == 2 {
            // The line through two points (a new segment's first window): no moments.
            let (dx, dy) = (last.x - first.x, last.y - first.y);
            let c = Point::new(first.x + 0.5 * dx, first.y + 0.5 * dy);
            (c, 0.5 * (dx * dx + dy * dy), dx, dy)
        } else {
            // Moments relative to the first point (the window is small: no cancellation),
            // whose own terms are zeros: the sums start from the second.
            let rest = window.get(1..).unwrap_or_default();
            let ((mx, my), [sxx, syy, sxy]) = line::centre(line::sums_about(rest, first), inv_n);
            // Principal axis (tx, ty) and the spread along it.
            let (suu, tx, ty) = line::major_axis(sxx, syy, sxy);
            (Point::new(first.x + mx, first.y + my), suu, tx, ty)
        };
        let big = if math::abs(tx) >= math::abs(ty) {
            math::abs(tx)
        } else {
            math::abs(ty)
        };
        if !(big > 0.0) || !math::finite(big) || !(suu > 0.0) {
            return None;
        }
        let inv_big = 1.0 / big;
        let (tx, ty) = (tx * inv_big, ty * inv_big);
        let t2 = tx * tx + ty * ty;
        // Incidence at the last point: |t|² sin²ϕ̄ = (l·n)² / |l|².
        let (lx, ly) = (last.x - origin.x, last.y - origin.y);
        let (ln, l2) = (ty * lx - tx * ly, lx * lx + ly * ly);
        Some(Self {
            tx,
            ty,
            parallel: 1e-12 * t2,
            cn: tx * c.y - ty * c.x,
            ct: tx * c.x + ty * c.y,
            inv_n,
            inv_t2suu: 1.0 / (t2 * suu),
            lever_sin2: f32::NAN,
            tail: f32::NAN,
            t2_sin2_last: if l2 > 0.0 { ln * ln / l2 } else { t2 },
        })
    }

    /// The same line, ready for [`Self::accepts`]: every beam tested as strictly as the one
    /// right after its window (`first`, `last` and `n`: the window's first and last point and
    /// its size), assuming evenly spaced points.
    #[inline]
    pub(crate) fn capped(mut self, first: &Point, last: &Point, n: usize) -> Self {
        let u_first = first.x * self.tx + first.y * self.ty - self.ct;
        let u_last = last.x * self.tx + last.y * self.ty - self.ct;
        let u_next = u_last + (u_last - u_first) / n.saturating_sub(1).max(1) as f32;
        self.lever_sin2 = (self.inv_n + u_next * u_next * self.inv_t2suu) * self.t2_sin2_last;
        self.tail = u_last;
        self
    }

    /// [`Self::accepts`] for the point `(x, y)` after the point `prev` (both relative to the
    /// scanner), with the lever a window like this line's, ending at `prev`, gives it: the
    /// point's own step from `prev` instead of the window's mean step. For points not evenly
    /// spaced (interleaved sweeps de-skewed: a short and a long step in turn), where the mean
    /// step tests the point after a long one far more strictly than a fresh window would.
    #[inline]
    pub(crate) fn accepts_after(
        &self,
        prev: &Point,
        (x, y): (f32, f32),
        r: f32,
        k_sigma2: f32,
        floor: f32,
    ) -> bool {
        let u_next = self.tail + (x - prev.x) * self.tx + (y - prev.y) * self.ty;
        let lever_sin2 = (self.inv_n + u_next * u_next * self.inv_t2suu) * self.t2_sin2_last;
        Self {
            lever_sin2,
            ..*self
        }
        .accepts(x, y, r, k_sigma2, floor)
    }

    /// [`Self::accepts_after`] without a branch (its tests joined by `&` and `|`): the same
    /// answer, for loops meant to vectorise.
    #[inline(always)]
    pub(crate) fn accepts_after_lanes(
        &self,
        prev: &Point,
        (x, y): (f32, f32),
        r: f32,
        k_sigma2: f32,
        floor: f32,
    ) -> bool {
        let u_next = self.tail + (x - prev.x) * self.tx + (y - prev.y) * self.ty;
        let lever_sin2 = (self.inv_n + u_next * u_next * self.inv_t2suu) * self.t2_sin2_last;
        // `test::<true>` with that lever.
        let q = self.tx * y - self.ty * x;
        let e = math::abs(r * (q - self.cn)) - floor * math::abs(q);
        let within = e * e <= k_sigma2 * (q * q + lever_sin2 * (r * r));
        (self.cn * q > 0.0) & ((e <= 0.0) | within)
    }

    /// The same line in the frame of a scanner at `origin` (the frame of the scanner at (0, 0)
    /// moved by `origin`, not turned): [`Self::accepts`] then tests a point given relative to
    /// `origin`, as a de-skewed beam's point is seen from its own pose.
    #[inline]
    pub(crate) fn seen_from(mut self, origin: Point) -> Self {
        self.cn -= self.tx * origin.y - self.ty * origin.x;
        self.ct -= self.tx * origin.x + self.ty * origin.y;
        self
    }

    /// Predicts the point at range `r` (mm) along the beam from `origin` whose direction times
    /// `r` is `(bx, by)` (for a measured point `P`: `P − origin`). One division.
    pub fn predict(&self, origin: Point, bx: f32, by: f32, r: f32) -> Prediction {
        let (nx, ny) = (-self.ty, self.tx);
        // q = r (d·n), bt = r (d·t), d the unit beam direction.
        let q = bx * nx + by * ny;
        let bt = bx * self.tx + by * self.ty;
        if !(q * q >= self.parallel * r * r) {
            // Line 1 runs along the beam (or the input is not finite).
            return Prediction::along(q, bt);
        }
        let iq = 1.0 / q;
        // w = centroid − origin.
        let wn = self.cn - (origin.x * nx + origin.y * ny);
        let wt = self.ct - (origin.x * self.tx + origin.y * self.ty);
        // Line 1 meets the beam at t = (w·n)/(d·n).
        let t_over_r = wn * iq;
        let t = t_over_r * r;
        let (error, signed) = if t > 0.0 && math::finite(t) {
            (math::abs(r - t), r - t)
        } else {
            (f32::INFINITY, f32::INFINITY)
        };
        // The prediction point's position along Line 1 from the centroid.
        let ut = bt * t_over_r - wt;
        let lever = self.inv_n + ut * ut * self.inv_t2suu;
        // sin²ϕ̄ / sin²ϕ, |t| sin ϕ = d·n = q / r.
        let ratio2 = self.t2_sin2_last * (r * iq) * (r * iq);
        Prediction {
            error,
            signed,
            dn: q,
            dt: bt,
            var_factor: 1.0 + lever * ratio2,
        }
    }
}

impl WindowLine {
    /// `!predict((0, 0), x, y, r).exceeds(k, σ_r, floor)` for the point `(x, y)` at range `r`
    /// from a scanner at the origin, with `k_sigma2 = (k σ_r)²`, and the lever of the beam
    /// right after the window ([`Self::capped`]): the extractor's test for most points, kept
    /// to its arithmetic.
    #[inline]
    pub(crate) fn accepts(&self, x: f32, y: f32, r: f32, k_sigma2: f32, floor: f32) -> bool {
        self.test::<true>(x, y, r, k_sigma2, floor)
    }

    /// [`Self::accepts`] without its test of `e ≤ 0`: the same answer when
    /// `floor² ≤ 0.999 k_sigma2` ([`Self::FLOOR2_WITHIN`]), where `e ≥ −floor·|q|` makes
    /// `e² ≤ k_sigma2·q²` hold anyway (the factor covers the rounding). The fast path's test.
    #[inline]
    pub(crate) fn accepts_within(&self, x: f32, y: f32, r: f32, k_sigma2: f32, floor: f32) -> bool {
        self.test::<false>(x, y, r, k_sigma2, floor)
    }

    /// The acceptance test, with (`WITHIN_FLOOR`) or without the early answer for points
    /// within the floor of the line.
    #[inline(always)]
    fn test<const WITHIN_FLOOR: bool>(
        &self,
        x: f32,
        y: f32,
        r: f32,
        k_sigma2: f32,
        floor: f32,
    ) -> bool {
        // q = r (d·n), d the unit beam direction: Line 1 meets the beam at t = r·cn/q, in
        // front of the scanner when cn·q > 0 (false for q = 0 and NaN).
        let q = self.tx * y - self.ty * x;
        if !(self.cn * q > 0.0) {
            return false;
        }
        // (|r − t| − floor)·|q|, without a division: |r − t|·|q| = |r (q − cn)|.
        let e = math::abs(r * (q - self.cn)) - floor * math::abs(q);
        if WITHIN_FLOOR && e <= 0.0 {
            return true;
        }
        // e² ≤ (k σ_r)² (1 + lever (r/q)²), times q². The lever of the beam right after the
        // window, for every beam: a line kept for a few more beams tests them as strictly as
        // a fresh one would (the lever grows with the distance from the window). A beam along
        // the line (q → 0) is accepted only when the line runs through the scanner, within the
        // noise: then the point is on it.
        e * e <= k_sigma2 * (q * q + self.lever_sin2 * (r * r))
    }

    /// See [`Self::accepts_within`].
    pub(crate) const FLOOR2_WITHIN: f32 = 0.999;
}

/// Predicts the point at range `r` (mm, from `origin`) along the unit beam direction
/// `(dx, dy)` from the `window` points (at least 2). `None` when the window does not define a
/// line (fewer than 2 points, all equal, or not finite).
pub fn predict_beam(
    window: &[Point],
    origin: Point,
    dx: f32,
    dy: f32,
    r: f32,
) -> Option<Prediction> {
    let line = WindowLine::fit(window, origin)?;
    Some(line.predict(origin, dx * r, dy * r, r))
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

#[cfg(test)]
mod tests {
    use super::*;

    /// `accepts` (no division) decides as the prediction does, with the capped lever: over
    /// lines at every angle and distance, beams across the window's continuation, and test
    /// ranges from well inside to well outside the threshold (cases within 0.1 % of it are
    /// left out: the two forms round differently).
    #[test]
    fn accepts_matches_the_prediction() -> Result<(), &'static str> {
        let (ks2, floor) = (20.0f32 * 20.0, 3.0f32);
        let (mut agreed, mut accepted, mut within) = (0usize, 0usize, 0usize);
        for ia in 0..24 {
            let alpha = -3.1 + 0.26 * ia as f32;
            for rho in [150.0f32, 800.0, 2500.0, 7000.0] {
                let (c, s) = (math::sin_cos(alpha).1, math::sin_cos(alpha).0);
                // Ten points of the line x cos α + y sin α = ρ, 0.5° apart, with a wiggle.
                let window: heapless::Vec<Point, 10> = (0..10)
                    .map(|i| {
                        let u = (i as f32 - 4.5) * rho * 0.0087;
                        let d = if i % 2 == 0 { 2.0 } else { -2.0 };
                        Point::new((rho + d) * c - u * s, (rho + d) * s + u * c)
                    })
                    .collect();
                let (first, last) = (
                    window.first().ok_or("empty")?,
                    window.last().ok_or("empty")?,
                );
                let line = WindowLine::fit(&window, Point::new(0.0, 0.0))
                    .ok_or("fit")?
                    .capped(first, last, window.len());
                for ib in -6..=6 {
                    let b = last.y.atan2(last.x) + 0.0087 * ib as f32;
                    let (bs, bc) = math::sin_cos(b);
                    // Where Line 1 meets this beam, and the threshold there.
                    let r0 = rho / (bc * c + bs * s).max(0.05);
                    let p0 = line.predict(Point::new(0.0, 0.0), r0 * bc, r0 * bs, r0);
                    let t = r0 - p0.signed;
                    let ti = f64::from(r0) / f64::from(p0.dn);
                    let bound0 =
                        (f64::from(ks2) * (1.0 + f64::from(line.lever_sin2) * ti * ti)).sqrt();
                    // Within the floor of Line 1 (`e ≤ 0`): accepted by both forms.
                    for d in [-2.9f32, -1.0, 0.0, 1.5, 2.9] {
                        let r = t + d;
                        if t.is_finite() && r > 0.0 {
                            let (x, y) = (r * bc, r * bs);
                            assert!(line.accepts(x, y, r, ks2, floor), "α {alpha} ρ {rho} {d}");
                            assert!(line.accepts_within(x, y, r, ks2, floor), "α {alpha} {d}");
                            within += 1;
                        }
                    }
                    for m in [
                        -3.0f32, -1.1, -1.01, -0.99, -0.5, 0.0, 0.5, 0.99, 1.01, 1.1, 3.0,
                    ] {
                        let off = (floor + m.abs() * bound0 as f32).copysign(m);
                        let r = if t.is_finite() { t + off } else { r0 };
                        if !(r > 0.0) {
                            continue;
                        }
                        let (x, y) = (r * bc, r * bs);
                        // The fast path's form agrees everywhere, thresholds or not.
                        assert_eq!(
                            line.accepts_within(x, y, r, ks2, floor),
                            line.accepts(x, y, r, ks2, floor),
                            "α {alpha} ρ {rho} beam {ib} m {m}"
                        );
                        let p = line.predict(Point::new(0.0, 0.0), x, y, r);
                        let reference = if !p.error.is_finite() {
                            Some(false)
                        } else {
                            let e = f64::from(p.error) - f64::from(floor);
                            let ri = f64::from(r) / f64::from(p.dn);
                            let bound =
                                f64::from(ks2) * (1.0 + f64::from(line.lever_sin2) * ri * ri);
                            let margin = (e.max(0.0) * e.max(0.0) - bound) / bound;
                            (e <= 0.0 || margin.abs() > 1e-3).then_some(e <= 0.0 || margin <= 0.0)
                        };
                        if let Some(want) = reference {
                            assert_eq!(
                                line.accepts(x, y, r, ks2, floor),
                                want,
                                "α {alpha} ρ {rho} beam {ib} m {m}"
                            );
                            agreed += 1;
                            accepted += usize::from(want);
                        }
                    }
                }
            }
        }
        // Both outcomes were exercised.
        assert!(
            agreed > 5000 && accepted > 1000 && agreed - accepted > 1000 && within > 1000,
            "{agreed} {accepted} {within}"
        );
        Ok(())
    }

    /// `WindowLine::fit` as it was, its sums from the window's first point on.
    fn fit_as_it_was(window: &[Point], origin: Point) -> Option<WindowLine> {
        let (first, last) = (window.first()?, window.last()?);
        let n = window.len();
        if n < 2 {
            return None;
        }
        let inv_n = 1.0 / n as f32;
        let (c, suu, tx, ty) = if n == 2 {
            let (dx, dy) = (last.x - first.x, last.y - first.y);
            let c = Point::new(first.x + 0.5 * dx, first.y + 0.5 * dy);
            (c, 0.5 * (dx * dx + dy * dy), dx, dy)
        } else {
            let ((mx, my), [sxx, syy, sxy]) = line::centre(line::sums_about(window, first), inv_n);
            let (suu, tx, ty) = line::major_axis(sxx, syy, sxy);
            (Point::new(first.x + mx, first.y + my), suu, tx, ty)
        };
        let big = if math::abs(tx) >= math::abs(ty) {
            math::abs(tx)
        } else {
            math::abs(ty)
        };
        if !(big > 0.0) || !math::finite(big) || !(suu > 0.0) {
            return None;
        }
        let inv_big = 1.0 / big;
        let (tx, ty) = (tx * inv_big, ty * inv_big);
        let t2 = tx * tx + ty * ty;
        let (lx, ly) = (last.x - origin.x, last.y - origin.y);
        let (ln, l2) = (ty * lx - tx * ly, lx * lx + ly * ly);
        Some(WindowLine {
            tx,
            ty,
            parallel: 1e-12 * t2,
            cn: tx * c.y - ty * c.x,
            ct: tx * c.x + ty * c.y,
            inv_n,
            inv_t2suu: 1.0 / (t2 * suu),
            lever_sin2: f32::NAN,
            tail: f32::NAN,
            t2_sin2_last: if l2 > 0.0 { ln * ln / l2 } else { t2 },
        })
    }

    /// A line's fields as bits (NaN fields compare equal).
    fn line_bits(l: &WindowLine) -> [u32; 11] {
        [
            l.tx,
            l.ty,
            l.parallel,
            l.cn,
            l.ct,
            l.inv_n,
            l.inv_t2suu,
            l.lever_sin2,
            l.t2_sin2_last,
            l.tail,
            0.0,
        ]
        .map(f32::to_bits)
    }

    /// The fit's sums from the window's second point (the first one's terms are zeros) give
    /// the line of the sums from its first, bit for bit: random windows of 2 to 24 points
    /// along walls and in clutter, near and far, some with a NaN or an infinite point (first
    /// among them), all equal points, seen from the origin or off it.
    #[test]
    fn the_window_line_skips_its_first_points_zero_terms() {
        let mut seed = 3u32;
        let mut u = move || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as f32 / (1u32 << 24) as f32
        };
        let (mut lines, mut none) = (0usize, 0usize);
        for t in 0..20_000usize {
            let n = 2 + t % 23;
            let (x0, y0) = (8000.0 * u() - 4000.0, 8000.0 * u() - 4000.0);
            let (dx, dy, noise) = (40.0 * u() - 20.0, 40.0 * u() - 20.0, 10.0 * u());
            let mut window: heapless::Vec<Point, 24> = (0..n)
                .map(|i| {
                    let i = i as f32;
                    Point::new(
                        x0 + dx * i + noise * (u() - 0.5),
                        y0 + dy * i + noise * (u() - 0.5),
                    )
                })
                .collect();
            let odd = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY];
            let at = (t / 7) % n;
            match t % 11 {
                0 => window[at].x = odd[t % 3],
                1 => window[at].y = odd[t % 3],
                2 => window[0].x = odd[t % 3],
                3 => window.iter_mut().for_each(|p| *p = Point::new(x0, y0)),
                _ => {}
            }
            let origin = match t % 2 {
                0 => Point::new(0.0, 0.0),
                _ => Point::new(50.0 * u(), 50.0 * u()),
            };
            let (new, old) = (
                WindowLine::fit(&window, origin),
                fit_as_it_was(&window, origin),
            );
            assert_eq!(
                new.map(|l| line_bits(&l)),
                old.map(|l| line_bits(&l)),
                "{t}"
            );
            lines += usize::from(old.is_some());
            none += usize::from(old.is_none());
        }
        assert!(lines > 10_000 && none > 5_000, "{lines} {none}");
    }

    /// Ten points of the wall x = 2000 mm seen from `o` (17.5 mm apart, ±1 mm wiggle), and
    /// their line fitted from `o`, capped.
    fn wall_from(o: Point) -> Result<(WindowLine, Point), &'static str> {
        let window: heapless::Vec<Point, 10> = (0..10)
            .map(|i| {
                let d = if i % 2 == 0 { 1.0 } else { -1.0 };
                Point::new(o.x + 2000.0 + d, o.y + 17.5 * i as f32)
            })
            .collect();
        let (first, last) = (
            window.first().ok_or("empty")?,
            window.last().ok_or("empty")?,
        );
        let line = WindowLine::fit(&window, o).ok_or("fit")?;
        Ok((line.capped(first, last, window.len()), *last))
    }

    /// The point of the beam from the scanner through (2000, y) at `off` mm past the wall.
    fn beyond(y: f32, off: f32) -> (f32, f32, f32) {
        let r = math::hypot(2000.0, y);
        let k = (r + off) / r;
        (2000.0 * k, y * k, r + off)
    }

    /// A line fitted from a scanner at `o`, `seen_from(o)`, tests points given relative to `o`:
    /// the wall's next points are accepted and 60 mm behind it rejected; without it, the same
    /// relative points lie 40 mm off a line that is 2040 mm away and are rejected.
    #[test]
    fn a_line_seen_from_its_scanner_tests_points_relative_to_it() -> Result<(), &'static str> {
        let (ks2, floor) = (15.0f32 * 15.0, 0.0);
        let o = Point::new(40.0, -25.0);
        let (line, _) = wall_from(o)?;
        let seen = line.seen_from(o);
        for y in [175.0f32, 192.5, 210.0] {
            let (x, yy, r) = beyond(y, 0.0);
            assert!(seen.accepts(x, yy, r, ks2, floor), "{y}");
            assert!(!line.accepts(x, yy, r, ks2, floor), "{y}");
            let (x, yy, r) = beyond(y, 60.0);
            assert!(!seen.accepts(x, yy, r, ks2, floor), "{y}");
        }
        // Seen from where it was fitted, nothing moves.
        let (line0, _) = wall_from(Point::new(0.0, 0.0))?;
        assert_eq!(line0.seen_from(Point::new(0.0, 0.0)), line0);
        Ok(())
    }

    /// `seen_from(o)` is the same line in the frame moved by `o`, along the line as across it:
    /// its prediction for a beam from the new frame's origin (the window's centroid carried
    /// into that frame sets the lever, `1/n + u²/Σu²`) is that of the line fitted to the window
    /// given relative to `o`, and that of the line itself for the beam from `o`. Beams to the
    /// wall 175 to 400 mm along it, and 60 mm behind it.
    #[test]
    fn a_line_seen_from_its_scanner_predicts_as_one_fitted_there() -> Result<(), &'static str> {
        let o = Point::new(40.0, -25.0);
        let window: heapless::Vec<Point, 10> = (0..10)
            .map(|i| {
                let d = if i % 2 == 0 { 1.0 } else { -1.0 };
                Point::new(2000.0 + d, 17.5 * i as f32)
            })
            .collect();
        let moved: heapless::Vec<Point, 10> = window
            .iter()
            .map(|p| Point::new(p.x + o.x, p.y + o.y))
            .collect();
        let line = WindowLine::fit(&moved, o).ok_or("fit")?;
        let there = WindowLine::fit(&window, Point::new(0.0, 0.0)).ok_or("fit")?;
        let seen = line.seen_from(o);
        let close = |a: f32, b: f32| (a - b).abs() <= 1e-3 * (1.0 + b.abs());
        for y in [175.0f32, 250.0, 400.0] {
            for off in [0.0f32, 60.0] {
                let (bx, by, r) = beyond(y, off);
                let got = seen.predict(Point::new(0.0, 0.0), bx, by, r);
                for want in [
                    there.predict(Point::new(0.0, 0.0), bx, by, r),
                    line.predict(o, bx, by, r),
                ] {
                    assert!(
                        close(got.var_factor, want.var_factor) && close(got.signed, want.signed),
                        "{y} {off}: {got:?} against {want:?}"
                    );
                }
            }
        }
        Ok(())
    }

    /// `accepts_after` a point one mean step past the window's last point tests as `accepts`
    /// (the capped lever: the same bound); a point five mean steps past it gets its own larger
    /// lever: a point off the wall by between the two bounds is accepted after that long step,
    /// rejected by `accepts` and after a mean step.
    #[test]
    fn a_point_after_a_long_step_gets_its_own_lever() -> Result<(), &'static str> {
        let (ks2, floor) = (15.0f32 * 15.0, 0.0);
        let (line, last) = wall_from(Point::new(0.0, 0.0))?;
        // The bound |r − t| ≤ k σ √(1 + lever (r/q)²) at the wall point 1 and 5 steps on.
        let bound = |steps: f32| {
            let y = last.y + 17.5 * steps;
            let u = line.tail + 17.5 * steps * line.ty;
            let lever = line.inv_n + u * u * line.inv_t2suu;
            let (r, q) = (math::hypot(2000.0, y), 2000.0 * line.ty);
            let ratio2 = line.t2_sin2_last * (r / q) * (r / q);
            (y, 15.0 * math::sqrt(1.0 + lever * ratio2))
        };
        let (y1, b1) = bound(1.0);
        let (y5, b5) = bound(5.0);
        assert!(b5 > 1.2 * b1, "{b1} {b5}");
        let between = 0.5 * (b1 + b5);
        // One mean step on: both forms agree, inside and outside the bound.
        for (off, want) in [(0.5 * b1, true), (1.5 * b1, false), (between, false)] {
            let (x, y, r) = beyond(y1, off);
            assert_eq!(line.accepts(x, y, r, ks2, floor), want, "{off}");
            assert_eq!(
                line.accepts_after(&last, (x, y), r, ks2, floor),
                want,
                "{off}"
            );
        }
        // A step of five from the window's last point.
        let prev = last;
        let (x, y, r) = beyond(y5, between);
        assert!(!line.accepts(x, y, r, ks2, floor));
        assert!(line.accepts_after(&prev, (x, y), r, ks2, floor));
        let (x, y, r) = beyond(y5, 1.2 * b5);
        assert!(!line.accepts_after(&prev, (x, y), r, ks2, floor));
        Ok(())
    }
}
