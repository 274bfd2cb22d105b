//! Adaptive curvature function (ACF) of P. Núñez, R. Vázquez-Martín, J. C. del Toro,
//! A. Bandera, F. Sandoval, "Natural landmark extraction for mobile robot navigation based on
//! an adaptive curvature estimation", *Robotics and Autonomous Systems* 56 (2008) 247–264 —
//! the method the PFE paper compares itself with — after the adaptive breakpoint detector
//! ([`Abd`], Borges & Aldon 2004), as in that comparison.
//!
//! Inside each ABD segment, for every point P_i:
//! 1. **Adaptive window.** k_f(i) is grown from `k_min` while the contour from P_i to
//!    P_{i+k_f} stays nearly straight: `d(P_i, P_{i+k}) + U_k > L(i, i+k)`, `d` the Euclidean
//!    distance and `L` the length of the polyline through the points (the published criterion
//!    `d_E > L − U_k`; the authors' public implementation reads it the same way). It stops at
//!    the first `k` that fails, at `k_max`, or at the segment's end. k_b(i) likewise backwards.
//!    `k_min` is imposed even where the test fails (as the authors' `KMin`).
//! 2. **Local angle.** With `f = P_{i+k_f} − P_i` and `b = P_{i−k_b} − P_i`, the turning
//!    angle `τ_i = π − ∠(f, b)`, signed (left turn positive). This is the angle of the
//!    paper's forward and backward vectors, measured from the straight line (0 on a line;
//!    the paper's Rosenfeld–Johnston form `(1 + cos∠(f, b))/2` is a monotone function of it).
//!    The segment's two end points, which lack one of the vectors, take their neighbour's
//!    value.
//! 3. **Smoothing.** τ is smoothed with a 5-tap binomial (Gaussian, σ = 1 sample) kernel,
//!    renormalised at the segment's ends.
//! 4. **Corners** are local maxima of |τ| of at least `u_c`. *Interpretation (documented
//!    deviation)*: a peak must also be a peak of curvature, `κ_i = 2|τ_i| / (|f| + |b|)`
//!    (smoothed likewise): at least twice κ at both ends of its own window. Otherwise the
//!    plateau of constant curvature along an arc — where |τ| grows with the window and may
//!    exceed `u_c` on small pillars — would be cut where the window is largest. Corners split
//!    the segment after the corner point.
//! 5. **Curve or line.** Between corners, a point is *curved* when its window stays between
//!    the corners and `|τ_i|` (smoothed) exceeds
//!    `k_curved` times its noise standard deviation
//!    `σ_τ = σ_r √(1/|f|² + 1/|b|² + (1/|f| + 1/|b|)²)` (first-order propagation of σ_r across
//!    the three points), else *straight*. Runs shorter than 4 points join the run before them
//!    (or after, at the start). A curved run whose τ keeps one sign on at least 80 % of its
//!    points is a curve segment (constant non-zero curvature), else a line segment (the paper:
//!    lines where the curvature is near zero, curves where it is constant and non-zero). A
//!    curve whose fitted radius exceeds `max_radius` is typed as a line; consecutive line runs
//!    (no corner between them) are one line.
//! 6. **Fits**: lines by pfe-core's least squares, curves by pfe-core's circle fit (Hyper,
//!    refined), both with range-noise covariances; a boundary point between two lines goes to
//!    the closer line.
//!
//! Parameters (the paper's numeric values are not available to us; these are ours):
//! `k_min = 3`, `k_max = 15` beams; `U_k = u_k_sigma · σ_r` with `u_k_sigma = 6` (the path of
//! a noisy straight wall is longer than its chord by about σ_r²/spacing per step, so U_k must
//! scale with the noise for windows to grow on walls; 30 mm lets a 90° corner shrink the
//! windows to about 50 mm legs); `u_c = 0.4` rad (≈ 23°); `k_curved = 3`;
//! `max_radius = 2000` mm; σ_r = 5 mm.
//!
//! Cost: O(n · k_max) for the windows (each point grows its own window, as the method is
//! defined), plus one smoothing pass and the fits — more work per point than PFE.

use super::{abd::Abd, circle_fit, extract_segments, slice, Model, Piece, MIN_POINTS};
use crate::methods::{Extraction, Method};
use pfe_core::{Point, ScanGeometry};

/// The adaptive-curvature-function extractor with ABD.
///
/// ```
/// use pfe_eval::methods::baselines::Acf;
/// use pfe_eval::methods::Method;
/// use pfe_core::ScanGeometry;
/// let g = ScanGeometry::LMS200_180_050;
/// // A wall 2 m ahead over ±45°: one line.
/// let r: Vec<f32> = (0..361)
///     .map(|i| {
///         let b = g.bearing(i);
///         if b.abs() < 0.785 { 2000.0 / b.cos() } else { f32::NAN }
///     })
///     .collect();
/// let out = Acf::new().extract(&g, &r);
/// assert_eq!(out.features.len(), 1);
/// assert!(out.features[0].is_line());
/// ```
#[derive(Clone, Debug)]
pub struct Acf {
    /// Breakpoint detector.
    pub abd: Abd,
    /// Smallest window, beams.
    pub k_min: usize,
    /// Largest window, beams.
    pub k_max: usize,
    /// U_k in units of σ_r.
    pub u_k_sigma: f32,
    /// Corner threshold on the smoothed turning angle, rad.
    pub u_c: f32,
    /// Curved-point threshold, in standard deviations of the turning angle.
    pub k_curved: f32,
    /// Largest radius accepted as a circle, mm.
    pub max_radius: f32,
}

impl Default for Acf {
    fn default() -> Self {
        Self::new()
    }
}

/// Per-point results of the curvature estimation inside one segment.
struct Curvature {
    kf: Vec<usize>,
    kb: Vec<usize>,
    /// Smoothed signed turning angle, rad.
    tau: Vec<f32>,
    /// Smoothed |curvature| τ / mean window chord, 1/mm.
    kappa: Vec<f32>,
    /// Noise standard deviation of the raw turning angle, rad.
    sigma_tau: Vec<f32>,
}

impl Acf {
    /// The documented defaults (σ_r = 5 mm).
    pub fn new() -> Self {
        Self {
            abd: Abd::default(),
            k_min: 3,
            k_max: 15,
            u_k_sigma: 6.0,
            u_c: 0.4,
            k_curved: 3.0,
            max_radius: 2000.0,
        }
    }

    /// The same method for a scanner with range noise `sigma_r` mm.
    pub fn with_sigma_r(mut self, sigma_r: f32) -> Self {
        self.abd.sigma_r = sigma_r;
        self
    }

    /// Steps 1–3 on the points of one segment.
    fn curvature(&self, seg: &[Point]) -> Curvature {
        let n = seg.len();
        let u_k = self.u_k_sigma * self.abd.sigma();
        let k_max = self.k_max.max(1);
        let k_min = self.k_min.clamp(1, k_max);
        // Cumulative polyline length: path(i, j) = cum[j] − cum[i].
        let mut cum = Vec::with_capacity(n);
        let mut acc = 0.0f32;
        let mut prev: Option<&Point> = None;
        for p in seg {
            if let Some(q) = prev {
                acc += p.distance(q);
            }
            cum.push(acc);
            prev = Some(p);
        }
        let path = |i: usize, j: usize| {
            let (a, b) = (i.min(j), i.max(j));
            cum.get(b).copied().unwrap_or(0.0) - cum.get(a).copied().unwrap_or(0.0)
        };
        let chord = |i: usize, j: usize| match (seg.get(i), seg.get(j)) {
            (Some(a), Some(b)) => a.distance(b),
            _ => 0.0,
        };
        let straight = |i: usize, j: usize| chord(i, j) + u_k > path(i, j);
        let mut kf = vec![0usize; n];
        let mut kb = vec![0usize; n];
        for i in 0..n {
            let room_f = n - 1 - i;
            let mut k = k_min.min(room_f);
            while k < k_max && k < room_f && straight(i, i + k + 1) {
                k += 1;
            }
            if let Some(v) = kf.get_mut(i) {
                *v = k;
            }
            let room_b = i;
            let mut k = k_min.min(room_b);
            while k < k_max && k < room_b && straight(i, i - k - 1) {
                k += 1;
            }
            if let Some(v) = kb.get_mut(i) {
                *v = k;
            }
        }
        let sr = self.abd.sigma();
        let mut raw = vec![0.0f32; n];
        let mut raw_kappa = vec![0.0f32; n];
        let mut sigma_tau = vec![f32::INFINITY; n];
        for i in 0..n {
            let (f, b) = (
                kf.get(i).copied().unwrap_or(0),
                kb.get(i).copied().unwrap_or(0),
            );
            if f == 0 || b == 0 {
                continue;
            }
            let (Some(p), Some(pf), Some(pb)) = (seg.get(i), seg.get(i + f), seg.get(i - b)) else {
                continue;
            };
            let (fx, fy) = (pf.x - p.x, pf.y - p.y);
            // Incoming direction −b = P_i − P_{i−k_b}.
            let (ix, iy) = (p.x - pb.x, p.y - pb.y);
            let t = (ix * fy - iy * fx).atan2(ix * fx + iy * fy);
            let (lf, lb) = (fx.hypot(fy), ix.hypot(iy));
            if t.is_finite() && lf > 0.0 && lb > 0.0 {
                if let Some(v) = raw.get_mut(i) {
                    *v = t;
                }
                if let Some(v) = raw_kappa.get_mut(i) {
                    *v = 2.0 * t.abs() / (lf + lb);
                }
                let (a, c) = (1.0 / lf, 1.0 / lb);
                if let Some(v) = sigma_tau.get_mut(i) {
                    *v = sr * (a * a + c * c + (a + c) * (a + c)).sqrt();
                }
            }
        }
        // The end points have no backward (forward) vector: they take their neighbour's value.
        for v in [&mut raw, &mut raw_kappa, &mut sigma_tau] {
            if n >= 3 {
                let (second, before_last) = (v.get(1).copied(), v.get(n - 2).copied());
                if let (Some(a), Some(b)) = (second, before_last) {
                    if let Some(x) = v.first_mut() {
                        *x = a;
                    }
                    if let Some(x) = v.last_mut() {
                        *x = b;
                    }
                }
            }
        }
        let tau = smooth(&raw);
        let kappa = smooth(&raw_kappa);
        Curvature {
            kf,
            kb,
            tau,
            kappa,
            sigma_tau,
        }
    }

    /// Step 4: corner indices (local to the segment), increasing.
    fn corners(&self, c: &Curvature) -> Vec<usize> {
        let n = c.tau.len();
        let at = |i: usize| c.tau.get(i).map_or(0.0, |v| v.abs());
        let k_at = |i: usize| c.kappa.get(i).copied().unwrap_or(0.0);
        (1..n.saturating_sub(1))
            .filter(|&i| {
                let v = at(i);
                let (b, f) = (
                    i.saturating_sub(c.kb.get(i).copied().unwrap_or(0)),
                    i + c.kf.get(i).copied().unwrap_or(0),
                );
                v >= self.u_c
                    && v >= at(i - 1)
                    && v > at(i + 1)
                    && k_at(i) >= 2.0 * k_at(b).max(k_at(f))
            })
            .collect()
    }

    /// Step 5: pieces (global indices) of the part `a..=b` (local indices) between corners.
    fn type_runs(
        &self,
        seg: &[Point],
        c: &Curvature,
        a: usize,
        b: usize,
        offset: usize,
        out: &mut Vec<Piece>,
    ) {
        let curved = |i: usize| {
            let inside = i >= a + c.kb.get(i).copied().unwrap_or(0)
                && i + c.kf.get(i).copied().unwrap_or(0) <= b;
            if !inside {
                // The window reaches over a corner: its angle says nothing about this part.
                return false;
            }
            let t = c.tau.get(i).copied().unwrap_or(0.0).abs();
            let s = c.sigma_tau.get(i).copied().unwrap_or(f32::INFINITY);
            t > self.k_curved * s
        };
        // Runs of equal label: (first, last, curved).
        let mut runs: Vec<(usize, usize, bool)> = Vec::new();
        for i in a..=b {
            let l = curved(i);
            match runs.last_mut() {
                Some(r) if r.2 == l => r.1 = i,
                _ => runs.push((i, i, l)),
            }
        }
        // Short runs join a neighbour.
        let mut merged: Vec<(usize, usize, bool)> = Vec::new();
        for r in runs {
            match merged.last_mut() {
                Some(m) if r.1 + 1 - r.0 < MIN_POINTS => m.1 = r.1,
                Some(m) if m.1 + 1 - m.0 < MIN_POINTS => {
                    m.1 = r.1;
                    m.2 = r.2;
                }
                Some(m) if m.2 == r.2 => m.1 = r.1,
                _ => merged.push(r),
            }
        }
        for (f, l, is_curved) in merged {
            let mut model = Model::Line;
            if is_curved && l + 1 - f >= MIN_POINTS.max(5) {
                let taus = c.tau.get(f..=l).unwrap_or(&[]);
                let pos = taus.iter().filter(|t| **t > 0.0).count();
                let neg = taus.len() - pos;
                if pos.max(neg) * 5 >= taus.len() * 4 {
                    let pts = slice(seg, f, l);
                    if circle_fit(pts).is_some_and(|k| k.radius <= self.max_radius) {
                        model = Model::Circle;
                    }
                }
            }
            match out.last_mut() {
                // No corner between two line runs: they are one line.
                Some(p)
                    if p.model == Model::Line
                        && model == Model::Line
                        && p.last + 1 == f + offset
                        && p.first >= a + offset =>
                {
                    p.last = l + offset;
                }
                _ => out.push(Piece {
                    first: f + offset,
                    last: l + offset,
                    model,
                }),
            }
        }
    }
}

impl Method for Acf {
    fn name(&self) -> &str {
        "acf"
    }

    fn extract(&mut self, geometry: &ScanGeometry, ranges_mm: &[f32]) -> Extraction {
        extract_segments(&self.abd, geometry, ranges_mm, |pts, s, e, pieces| {
            let seg = slice(pts, s, e);
            if seg.len() < MIN_POINTS {
                pieces.push(Piece {
                    first: s,
                    last: e,
                    model: Model::Line,
                });
            } else {
                let c = self.curvature(seg);
                let mut a = 0usize;
                for k in self.corners(&c) {
                    self.type_runs(seg, &c, a, k, s, pieces);
                    a = k + 1;
                }
                self.type_runs(seg, &c, a, seg.len() - 1, s, pieces);
            }
        })
    }
}

/// 5-tap binomial smoothing (Gaussian, σ = 1 sample), renormalised at the ends.
fn smooth(v: &[f32]) -> Vec<f32> {
    const W: [f32; 5] = [1.0, 4.0, 6.0, 4.0, 1.0];
    (0..v.len())
        .map(|i| {
            let (mut s, mut w) = (0.0f32, 0.0f32);
            for (o, wk) in W.iter().enumerate() {
                if let Some(x) = (i + o).checked_sub(2).and_then(|j| v.get(j)) {
                    s += wk * x;
                    w += wk;
                }
            }
            if w > 0.0 {
                s / w
            } else {
                0.0
            }
        })
        .collect()
}
