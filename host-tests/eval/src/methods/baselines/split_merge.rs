//! Split-and-merge (iterative end-point fit, IEPF) inside the segments of the adaptive
//! breakpoint detector: the classic two-pass line extractor (see e.g. V. Nguyen, A. Martinelli,
//! N. Tomatis, R. Siegwart, "A comparison of line extraction algorithms using 2D laser
//! rangefinder for indoor mobile robotics", IROS 2005; Borges & Aldon 2004).
//!
//! For each ABD segment (see [`Abd`]):
//! 1. **Split** (recursive, on an explicit stack): take the chord between the segment's end
//!    points; if the largest distance of a point from it is at most
//!    `d_split = k_sigma · σ_r + length_fraction · |chord|`, the segment is a line. Otherwise,
//!    if it has at least `min_circle_points` points and pfe-core's circle fit (Hyper, refined)
//!    has a radius ≤ `max_radius` and every point within `d_split` of the circle, it is a circle
//!    (this is the circle test that lets the baseline output arcs: "the line is poor but the
//!    circle is good"). Otherwise split it after the farthest point.
//! 2. **Merge**: adjacent line pieces of the same ABD segment whose union has every point
//!    within `d_split` of its least-squares line are merged, until nothing changes.
//! 3. **Boundary**: the last point of a line piece moves to the next line piece when it is
//!    closer to that line (and vice versa), so a corner point goes to the better line.
//!
//! Pieces of at least 4 points become features, fitted by pfe-core ([`pfe_core::fit_line`],
//! [`pfe_core::fit_circle`]) with range-noise covariances.
//!
//! Defaults: `k_sigma = 4` (the largest of a few hundred Gaussian residuals is ≈ 3.3 σ, and the
//! chord's own end points are noisy), `length_fraction = 0.005` (5 mm a metre: allowance for
//! small systematic range errors along long walls), `min_circle_points = 6`,
//! `max_radius = 2000 mm` (as pfe-core's default typing), σ_r = 5 mm.

use super::{
    abd::Abd, circle_fit, circle_max_residual, extract_segments, line_max_residual, slice, Model,
    Piece,
};
use crate::methods::{Extraction, Method};
use pfe_core::{fit_line, Point, ScanGeometry};

/// Split-and-merge with ABD and a circle test.
///
/// ```
/// use pfe_eval::methods::baselines::SplitMerge;
/// use pfe_eval::methods::Method;
/// use pfe_core::{Feature, ScanGeometry};
/// let g = ScanGeometry::LMS200_180_050;
/// // A wall 2 m ahead, perpendicular to the x axis, seen over ±45°.
/// let r: Vec<f32> = (0..361)
///     .map(|i| {
///         let b = g.bearing(i);
///         if b.abs() < 0.785 { 2000.0 / b.cos() } else { f32::NAN }
///     })
///     .collect();
/// let out = SplitMerge::new().extract(&g, &r);
/// assert_eq!(out.features.len(), 1);
/// let Feature::Line(l) = out.features[0] else { panic!("not a line") };
/// assert!((l.rho - 2000.0).abs() < 1.0 && l.alpha.abs() < 1e-3);
/// ```
#[derive(Clone, Debug)]
pub struct SplitMerge {
    /// Breakpoint detector.
    pub abd: Abd,
    /// Split threshold, in units of σ_r.
    pub k_sigma: f32,
    /// Split threshold growth with the chord length (dimensionless).
    pub length_fraction: f32,
    /// Fewest points for the circle test.
    pub min_circle_points: usize,
    /// Largest radius accepted as a circle, mm.
    pub max_radius: f32,
}

impl Default for SplitMerge {
    fn default() -> Self {
        Self::new()
    }
}

impl SplitMerge {
    /// The documented defaults (σ_r = 5 mm).
    pub fn new() -> Self {
        Self {
            abd: Abd::default(),
            k_sigma: 4.0,
            length_fraction: 0.005,
            min_circle_points: 6,
            max_radius: 2000.0,
        }
    }

    /// The same method for a scanner with range noise `sigma_r` mm.
    pub fn with_sigma_r(mut self, sigma_r: f32) -> Self {
        self.abd.sigma_r = sigma_r;
        self
    }

    fn d_split(&self, a: &Point, b: &Point) -> f32 {
        let frac = if self.length_fraction.is_finite() {
            self.length_fraction.max(0.0)
        } else {
            0.0
        };
        self.k_sigma * self.abd.sigma() + frac * a.distance(b)
    }

    /// Splits segment `s..=e` of `pts` into pieces, appended in scan order.
    fn split(&self, pts: &[Point], s: usize, e: usize, out: &mut Vec<Piece>) {
        let mut stack = vec![(s, e)];
        while let Some((a, b)) = stack.pop() {
            let piece = |model| Piece {
                first: a,
                last: b,
                model,
            };
            let (Some(pa), Some(pb)) = (pts.get(a), pts.get(b)) else {
                continue;
            };
            if b < a + 2 {
                out.push(piece(Model::Line));
                continue;
            }
            let (k, dmax) = farthest_from_chord(pts, a, b);
            let thr = self.d_split(pa, pb);
            if dmax <= thr {
                out.push(piece(Model::Line));
                continue;
            }
            if b + 1 - a >= self.min_circle_points.max(3) {
                let seg = slice(pts, a, b);
                if let Some(c) = circle_fit(seg) {
                    if c.radius <= self.max_radius && circle_max_residual(seg, &c) <= thr {
                        out.push(piece(Model::Circle));
                        continue;
                    }
                }
            }
            // Split after the farthest point (it is strictly inside, so both halves are
            // non-empty); the right half first on the stack so the left one comes out first.
            let k = k.clamp(a, b - 1);
            stack.push((k + 1, b));
            stack.push((a, k));
        }
    }

    /// Merges adjacent collinear line pieces (all pieces of one ABD segment).
    fn merge(&self, pts: &[Point], pieces: &mut Vec<Piece>) {
        let mut changed = true;
        while changed {
            changed = false;
            let mut i = 0;
            while i + 1 < pieces.len() {
                let (Some(l), Some(r)) = (pieces.get(i).copied(), pieces.get(i + 1).copied())
                else {
                    break;
                };
                if l.model == Model::Line
                    && r.model == Model::Line
                    && self.collinear(pts, l.first, r.last)
                {
                    if let Some(p) = pieces.get_mut(i) {
                        p.last = r.last;
                    }
                    pieces.remove(i + 1);
                    changed = true;
                } else {
                    i += 1;
                }
            }
        }
    }

    fn collinear(&self, pts: &[Point], a: usize, b: usize) -> bool {
        let seg = slice(pts, a, b);
        let (Some(pa), Some(pb)) = (seg.first(), seg.last()) else {
            return false;
        };
        match fit_line(seg) {
            Ok(l) => line_max_residual(seg, &l) <= self.d_split(pa, pb),
            Err(_) => false,
        }
    }
}

/// Index strictly inside `a..b` farthest from the chord P_a P_b, and that distance
/// (`(a, 0)` when there is no interior point). A degenerate chord uses the distance to P_a.
pub(crate) fn farthest_from_chord(pts: &[Point], a: usize, b: usize) -> (usize, f32) {
    let (Some(pa), Some(pb)) = (pts.get(a), pts.get(b)) else {
        return (a, 0.0);
    };
    let (dx, dy) = (pb.x - pa.x, pb.y - pa.y);
    let len = (dx * dx + dy * dy).sqrt();
    let mut best = (a, 0.0f32);
    for (k, p) in pts.iter().enumerate().take(b).skip(a + 1) {
        let d = if len > 0.0 {
            ((p.x - pa.x) * dy - (p.y - pa.y) * dx).abs() / len
        } else {
            p.distance(pa)
        };
        if d > best.1 || d.is_nan() {
            best = (k, if d.is_nan() { f32::INFINITY } else { d });
        }
    }
    best
}

impl Method for SplitMerge {
    fn name(&self) -> &str {
        "split-merge"
    }

    fn extract(&mut self, geometry: &ScanGeometry, ranges_mm: &[f32]) -> Extraction {
        extract_segments(&self.abd, geometry, ranges_mm, |pts, s, e, pieces| {
            self.split(pts, s, e, pieces);
            self.merge(pts, pieces);
        })
    }
}
