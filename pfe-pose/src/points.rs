//! The scans' own points: a compact copy of a scan's ranges ([`RangeScan`]), the check of a
//! pose against them ([`agreement`]) and a point-to-line ICP ([`icp`], Censi 2008) for when
//! the features cannot register a pair.
//!
//! Features alone cannot tell some wrong poses from the right one (a corridor's pillars 0.7 m
//! apart, short lines far away): the scans' points can. Under the right pose the current
//! scan's points lie on what the previous scan saw; under a wrong one many lie where the
//! previous scan saw through (free space), which no static scene allows.

use crate::geom::{eigen_sym3, hypot, inverse_spd3, sin_cos, Cov3, Pose, ZERO3};
use crate::register::{ROTATION_SCALE, UNOBSERVABLE_VARIANCE};

/// A scan's ranges, u16 mm (0: no return), with the bearing of beam 0 and the step, rad: a
/// scan of 361 beams takes 722 bytes. A scan with more than `N` beams keeps every k-th one.
///
/// ```
/// use pfe_pose::points::RangeScan;
/// let mut s = RangeScan::<181>::new();
/// let ranges = [1000.0f32; 361];
/// assert!(s.set(-1.5708, 0.00873, &ranges)); // 361 beams: every other one kept
/// assert_eq!(s.len(), 181);
/// ```
#[derive(Clone, Debug)]
pub struct RangeScan<const N: usize> {
    r: [u16; N],
    n: u16,
    start: f32,
    step: f32,
}

impl<const N: usize> Default for RangeScan<N> {
    fn default() -> Self {
        Self::new()
    }
}

/// Ranges kept, mm: shorter ones are the scanner's own housing or noise.
const MIN_RANGE: f32 = 20.0;

impl<const N: usize> RangeScan<N> {
    /// An empty scan (all zero bytes).
    pub const fn new() -> Self {
        Self {
            r: [0; N],
            n: 0,
            start: 0.0,
            step: 0.0,
        }
    }

    /// Takes `ranges` (mm; NaN, ≤ 20 mm or ≥ 65.5 m: no return) whose beam `i` has bearing
    /// `start + i·step` (rad). False (and empty) when the geometry is not finite or the step
    /// is zero.
    pub fn set(&mut self, start: f32, step: f32, ranges: &[f32]) -> bool {
        self.n = 0;
        if !(start.is_finite() && step.is_finite() && step != 0.0) || N == 0 {
            return false;
        }
        let stride = ranges.len().div_ceil(N).max(1);
        let mut n = 0usize;
        for (slot, r) in self.r.iter_mut().zip(ranges.iter().step_by(stride)) {
            *slot = if *r > MIN_RANGE && *r < 65_535.0 {
                *r as u16
            } else {
                0
            };
            n += 1;
        }
        let Ok(n) = u16::try_from(n) else {
            return false;
        };
        self.n = n;
        self.start = start;
        self.step = step * stride as f32;
        true
    }

    /// Forgets the ranges.
    pub fn clear(&mut self) {
        self.n = 0;
    }

    /// Beams kept.
    pub fn len(&self) -> usize {
        usize::from(self.n)
    }

    /// True when no beam is kept.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    fn ranges(&self) -> &[u16] {
        self.r.get(..self.len()).unwrap_or(&[])
    }

    /// The beam nearest to bearing `b` (rad), if inside the field of view.
    fn beam_of(&self, b: f32) -> Option<usize> {
        let f = (b - self.start) / self.step + 0.5;
        if f >= 0.0 && f < self.n as f32 {
            Some(f as usize)
        } else {
            None
        }
    }

    /// Calls `f(i, [x, y])` for every beam with a return, in beam order, with the scan's
    /// sines and cosines advanced by rotation (one sine and cosine per scan).
    fn for_points(&self, mut f: impl FnMut(usize, [f32; 2])) {
        let (mut s, mut c) = sin_cos(self.start);
        let (ds, dc) = sin_cos(self.step);
        for (i, &r) in self.ranges().iter().enumerate() {
            if r > 0 {
                let r = f32::from(r);
                f(i, [r * c, r * s]);
            }
            let c2 = c * dc - s * ds;
            s = s * dc + c * ds;
            c = c2;
        }
    }
}

/// How a pose's points agree with a scan's ranges (see [`agreement`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Agreement {
    /// Points that lie on what the other scan saw (within the tolerance).
    pub agree: u16,
    /// Points that lie where the other scan saw through: in front of every return of the
    /// beams around their bearing.
    pub conflict: u16,
    /// Points inside the other scan's field of view with a return there to compare with.
    pub tested: u16,
}

impl Agreement {
    /// The points' score: agreeing less [`CONFLICT_WEIGHT`] times conflicting, over the
    /// tested (0 when none was tested).
    pub fn score(&self) -> f32 {
        if self.tested == 0 {
            return 0.0;
        }
        (f32::from(self.agree) - CONFLICT_WEIGHT * f32::from(self.conflict))
            / f32::from(self.tested)
    }

    fn add(self, o: Agreement) -> Agreement {
        Agreement {
            agree: self.agree.saturating_add(o.agree),
            conflict: self.conflict.saturating_add(o.conflict),
            tested: self.tested.saturating_add(o.tested),
        }
    }
}

/// Weight of a conflicting point (one seen where the other scan saw through) against an
/// agreeing one.
pub const CONFLICT_WEIGHT: f32 = 2.0;

/// Tolerance of the agreement at range r: `TOL_MM + TOL_REL·r`, mm (range noise, the
/// reference's own few cm, the beam's width on an oblique surface).
const TOL_MM: f32 = 60.0;
const TOL_REL: f32 = 0.015;

/// The points of `curr` placed by `pose` (the pose of `curr` in the frame of `prev`) against
/// the ranges of `prev`, and the points of `prev` against `curr` (both directions: a scan
/// that sees more than the other is not favoured). A point agrees when its range from the
/// other scan lies within the tolerance of the returns of the three beams around its
/// bearing; it conflicts when it lies in front of all of them by more than the tolerance.
///
/// ```
/// use pfe_pose::points::{agreement, RangeScan};
/// use pfe_pose::Pose;
/// // A wall 2 m ahead, seen from the origin and from 0.5 m closer.
/// let wall = |d: f32| -> Vec<f32> {
///     (0..181).map(|i| d / ((-45.0 + 0.5 * i as f32).to_radians()).cos()).collect()
/// };
/// let (mut a, mut b) = (RangeScan::<181>::new(), RangeScan::<181>::new());
/// a.set(-0.785398, 0.00872665, &wall(2000.0));
/// b.set(-0.785398, 0.00872665, &wall(1500.0));
/// let right = agreement(&a, &b, &Pose::new(500.0, 0.0, 0.0));
/// let wrong = agreement(&a, &b, &Pose::new(0.0, 0.0, 0.0));
/// assert!(right.score() > 0.9 && wrong.score() < 0.0);
/// ```
pub fn agreement<const N: usize>(
    prev: &RangeScan<N>,
    curr: &RangeScan<N>,
    pose: &Pose,
) -> Agreement {
    if !pose.is_finite() {
        return Agreement::default();
    }
    one_way(prev, curr, pose).add(one_way(curr, prev, &pose.inverse()))
}

/// The points of `from` placed by `pose` into the frame of `onto`, against its ranges.
fn one_way<const N: usize>(onto: &RangeScan<N>, from: &RangeScan<N>, pose: &Pose) -> Agreement {
    let mut a = Agreement::default();
    let to = pose.transformer();
    let ranges = onto.ranges();
    from.for_points(|_, p| {
        let q = to(p);
        let rq = hypot(q[0], q[1]);
        let Some(j) = onto.beam_of(libm::atan2f(q[1], q[0])) else {
            return;
        };
        let (mut lo, mut hi) = (u16::MAX, 0u16);
        for k in j.saturating_sub(1)..=j + 1 {
            if let Some(&r) = ranges.get(k).filter(|r| **r > 0) {
                lo = lo.min(r);
                hi = hi.max(r);
            }
        }
        if hi == 0 {
            return;
        }
        let tol = TOL_MM + TOL_REL * rq;
        a.tested = a.tested.saturating_add(1);
        if rq < f32::from(lo) - tol {
            a.conflict = a.conflict.saturating_add(1);
        } else if rq <= f32::from(hi) + tol {
            a.agree = a.agree.saturating_add(1);
        }
    });
    a
}

/// The result of [`icp`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IcpResult {
    /// The pose of the current scan in the previous scan's frame.
    pub pose: Pose,
    /// Its covariance (x mm, y mm, θ rad): the residuals' scatter through `(JᵀJ)⁻¹`, scaled
    /// for the correlation of neighbouring points' errors ([`ICP_CORRELATION`]), with
    /// [`UNOBSERVABLE_VARIANCE`] along a direction the points cannot tell.
    pub cov: Cov3,
    /// A direction the points cannot tell (unit, x mm, y mm, θ·[`ROTATION_SCALE`]).
    pub unobservable: Option<[f32; 3]>,
    /// Correspondences used in the last step.
    pub pairs: u16,
    /// The points' agreement at the answer ([`agreement`]).
    pub agreement: Agreement,
}

/// Points whose errors are taken as one independent measurement in [`icp`]'s covariance:
/// neighbouring beams on one surface share its shape's and the scanner's systematic error.
pub const ICP_CORRELATION: f32 = 16.0;

/// Iterations of [`icp`] at most.
const ICP_ITERATIONS: usize = 30;
/// Fewest correspondences for a step.
const ICP_MIN_PAIRS: usize = 20;
/// Correspondences farther than this are dropped, mm: first wide (the guess may be off by a
/// few decimetres), then CSM's 0.3 m.
const ICP_REACH: [f32; 2] = [1000.0, 300.0];
/// Iterations at the wide reach.
const ICP_WIDE: usize = 6;
/// How far [`icp`] moves its answer along the weakest direction to test it, mm (θ in units
/// of [`ROTATION_SCALE`]).
const ICP_PROBE: f32 = 300.0;
/// The points' score must drop by more than this when moved by [`ICP_PROBE`] one way or the other, or
/// the direction is one the points cannot tell.
const ICP_PROBE_DROP: f32 = 0.05;
/// Directions of translation probed either side of the weakest one, rad.
const ICP_PROBE_SPREAD: f32 = 0.07;
/// Beams either side at most for a surface's direction.
const NORMAL_SPAN: usize = 8;
/// Wanted length of the base of a surface's direction, mm.
const NORMAL_BASE: f32 = 150.0;
/// Bearings searched for the nearest point either side of the projected one, rad.
const ICP_WINDOW: f32 = 0.2;
/// A standard deviation above this (mm; θ in units of [`ROTATION_SCALE`]) is a direction the
/// points cannot tell.
const ICP_DEGENERATE_SIGMA: f32 = 300.0;

/// Point-to-line ICP (Censi, ICRA 2008) of `curr` against `prev` from `guess` (the pose of
/// `curr` in `prev`'s frame): each point of `curr`, placed by the estimate, is paired with the
/// nearest return of `prev` within 0.2 rad of its bearing and the nearer of that
/// return's neighbours (the segment between them), and the pose minimising the squared
/// point-to-line distances is solved by Gauss–Newton; the worst 10 % and those beyond the
/// reach are dropped. `None` when too few points pair or the solution is not finite; the
/// caller judges the answer by its [`Agreement`].
///
/// ```
/// use pfe_pose::points::{icp, RangeScan};
/// use pfe_pose::Pose;
/// // The corner of a room, seen from the origin and from 0.2 m further along x.
/// let room = |dx: f32| -> Vec<f32> {
///     (0..361).map(|i| {
///         let (s, c) = (-90.0f32 + 0.5 * i as f32).to_radians().sin_cos();
///         let mut r = f32::INFINITY;
///         if c > 1e-6 { r = r.min((3000.0 - dx) / c); }
///         if s > 1e-6 { r = r.min(2000.0 / s); }
///         if s < -1e-6 { r = r.min(2500.0 / -s); }
///         r
///     }).collect()
/// };
/// let (mut a, mut b) = (RangeScan::<361>::new(), RangeScan::<361>::new());
/// a.set(-1.5707964, 0.008726646, &room(0.0));
/// b.set(-1.5707964, 0.008726646, &room(200.0));
/// let r = icp(&a, &b, &Pose::new(100.0, 50.0, 0.02)).unwrap();
/// assert!((r.pose.x - 200.0).abs() < 5.0 && r.pose.y.abs() < 5.0 && r.pose.theta.abs() < 2e-3);
/// assert!(r.agreement.score() > 0.9 && r.unobservable.is_none());
/// ```
pub fn icp<const N: usize>(
    prev: &RangeScan<N>,
    curr: &RangeScan<N>,
    guess: &Pose,
) -> Option<IcpResult> {
    if !guess.is_finite() || prev.len() < ICP_MIN_PAIRS || curr.len() < ICP_MIN_PAIRS {
        return None;
    }
    let window = ((ICP_WINDOW / prev.step.abs()) as usize).clamp(2, 64);
    // The previous scan's points (NaN: no return).
    let mut pts = [[f32::NAN; 2]; N];
    prev.for_points(|i, p| {
        if let Some(slot) = pts.get_mut(i) {
            *slot = p;
        }
    });
    let mut pose = *guess;
    let mut last: Option<(Cov3, f32, usize)> = None;
    for it in 0..ICP_ITERATIONS {
        let reach = if it < ICP_WIDE {
            ICP_REACH[0]
        } else {
            ICP_REACH[1]
        };
        // The trimming threshold: the 90th percentile of the paired distances, from a
        // histogram of 64 bins over the reach.
        let mut hist = [0u16; 64];
        let mut total = 0usize;
        pairs(prev, &pts, curr, &pose, window, reach, |_, _, e| {
            let bin = ((e.abs() / reach) * 64.0) as usize;
            if let Some(h) = hist.get_mut(bin.min(63)) {
                *h = h.saturating_add(1);
                total += 1;
            }
        });
        if total < ICP_MIN_PAIRS {
            return None;
        }
        let keep = total - total / 10;
        let mut cut = reach;
        let mut acc = 0usize;
        for (b, &h) in hist.iter().enumerate() {
            acc += usize::from(h);
            if acc >= keep {
                cut = reach * (b + 1) as f32 / 64.0;
                break;
            }
        }
        let mut h = ZERO3;
        let mut g = [0.0f32; 3];
        let mut sse = 0.0f32;
        let mut m = 0usize;
        pairs(prev, &pts, curr, &pose, window, reach, |n, j, e| {
            if e.abs() > cut {
                return;
            }
            // J scaled: θ in units of ROTATION_SCALE mm.
            let js = [n[0], n[1], j / ROTATION_SCALE];
            for a in 0..3 {
                for b in 0..3 {
                    h[a][b] += js[a] * js[b];
                }
                g[a] += js[a] * e;
            }
            sse += e * e;
            m += 1;
        });
        if m < ICP_MIN_PAIRS {
            return None;
        }
        let mut damped = h;
        for (k, row) in damped.iter_mut().enumerate() {
            if let Some(d) = row.get_mut(k) {
                *d += 1e-3;
            }
        }
        let hi = inverse_spd3(&damped)?;
        let mut dx = [0.0f32; 3];
        for a in 0..3 {
            dx[a] = -(hi[a][0] * g[0] + hi[a][1] * g[1] + hi[a][2] * g[2]);
        }
        pose = Pose::new(
            pose.x + dx[0],
            pose.y + dx[1],
            crate::geom::wrap(pose.theta + dx[2] / ROTATION_SCALE),
        );
        if !pose.is_finite() {
            return None;
        }
        last = Some((h, sse, m));
        if it >= ICP_WIDE && hypot(dx[0], dx[1]) < 0.1 && dx[2].abs() < 0.02 {
            break;
        }
    }
    let (h, sse, m) = last?;
    let mut unobservable = None;
    let here = agreement(prev, curr, &pose);
    // Covariance: σ² (JᵀJ)⁻¹ with σ² the residuals' scatter, times the correlation of
    // neighbouring points. A direction of translation along which moving the answer by
    // ICP_PROBE (either way) leaves the points agreeing about as well is one the points cannot
    // tell (a corridor's plain walls): the normals' noise alone would make it look determined
    // in JᵀJ, so it is found by probing, and its variance is unobservable.
    let sigma2 = (sse / (m.saturating_sub(3).max(1)) as f32).max(100.0) * ICP_CORRELATION;
    let least = here.score() - ICP_PROBE_DROP;
    let mut flat: Option<([f32; 3], f32)> = None;
    // The weakest direction of translation (θ eliminated: the Schur complement of JᵀJ), and
    // either side of it by ICP_PROBE_SPREAD.
    let hth = h[2][2].max(1e-12);
    let s2 = [
        h[0][0] - h[0][2] * h[2][0] / hth,
        h[0][1] - h[0][2] * h[2][1] / hth,
        h[1][1] - h[1][2] * h[2][1] / hth,
    ];
    let weakest = 0.5 * libm::atan2f(-2.0 * s2[1], s2[2] - s2[0]);
    for k in [0.0f32, -1.0, 1.0] {
        let (sn, cs) = sin_cos(weakest + k * ICP_PROBE_SPREAD);
        let probe = |sign: f32| {
            let d = sign * ICP_PROBE;
            agreement(
                prev,
                curr,
                &Pose::new(pose.x + d * cs, pose.y + d * sn, pose.theta),
            )
            .score()
        };
        let kept = probe(1.0).min(probe(-1.0));
        if kept > least && flat.is_none_or(|(_, b)| kept > b) {
            flat = Some(([cs, sn, 0.0], kept));
        }
    }
    let cov_s = match flat {
        Some((d, _)) => {
            unobservable = Some(d);
            // JᵀJ on the plane across `d` (spanned by e1 = (−d_y, d_x, 0) and e2 = θ), its
            // inverse there, and the unobservable variance along `d`.
            let e = [[-d[1], d[0], 0.0], [0.0, 0.0, 1.0]];
            let mut h2 = [[0.0f32; 2]; 2];
            for i in 0..2 {
                for j in 0..2 {
                    for a in 0..3 {
                        for b in 0..3 {
                            h2[i][j] += e[i][a] * h[a][b] * e[j][b];
                        }
                    }
                }
            }
            let det = h2[0][0] * h2[1][1] - h2[0][1] * h2[1][0];
            if !(det > 0.0) {
                return None;
            }
            let inv2 = [
                [h2[1][1] / det, -h2[0][1] / det],
                [-h2[1][0] / det, h2[0][0] / det],
            ];
            let mut c = ZERO3;
            for a in 0..3 {
                for b in 0..3 {
                    c[a][b] = UNOBSERVABLE_VARIANCE * d[a] * d[b];
                    for i in 0..2 {
                        for j in 0..2 {
                            c[a][b] += sigma2 * e[i][a] * inv2[i][j] * e[j][b];
                        }
                    }
                }
            }
            c
        }
        None => {
            let (vals, vecs) = eigen_sym3(&h);
            let mut c = ZERO3;
            for (k, (&l, v)) in vals.iter().zip(&vecs).enumerate() {
                let var = if l > 0.0 { sigma2 / l } else { f32::INFINITY };
                let var = if var.is_finite() && var < ICP_DEGENERATE_SIGMA * ICP_DEGENERATE_SIGMA {
                    var
                } else {
                    if k == 0 {
                        unobservable = Some(*v);
                    }
                    UNOBSERVABLE_VARIANCE
                };
                for a in 0..3 {
                    for b in 0..3 {
                        c[a][b] += var * v[a] * v[b];
                    }
                }
            }
            c
        }
    };
    let mut cov = cov_s;
    for a in 0..3 {
        cov[a][2] /= ROTATION_SCALE;
        cov[2][a] /= ROTATION_SCALE;
    }
    if !cov.iter().flatten().all(|v| v.is_finite()) {
        return None;
    }
    Some(IcpResult {
        pose,
        cov,
        unobservable,
        pairs: u16::try_from(m).unwrap_or(u16::MAX),
        agreement: here,
    })
}

/// Calls `f(normal, dθ-jacobian, signed distance)` for each point of `curr` placed by `pose`
/// that pairs with a segment of `prev` within `reach`.
fn pairs<const N: usize>(
    prev: &RangeScan<N>,
    pts: &[[f32; 2]],
    curr: &RangeScan<N>,
    pose: &Pose,
    window: usize,
    reach: f32,
    mut f: impl FnMut([f32; 2], f32, f32),
) {
    let to = pose.transformer();
    let (s, c) = sin_cos(pose.theta);
    let point = |k: usize| -> Option<[f32; 2]> { pts.get(k).copied().filter(|a| !a[0].is_nan()) };
    curr.for_points(|_, p| {
        let q = to(p);
        let Some(j0) = prev.beam_of(libm::atan2f(q[1], q[0])) else {
            return;
        };
        let mut best: Option<(usize, [f32; 2], f32)> = None;
        for k in j0.saturating_sub(window)..=(j0 + window).min(prev.len().saturating_sub(1)) {
            if let Some(a) = point(k) {
                let d2 = (q[0] - a[0]) * (q[0] - a[0]) + (q[1] - a[1]) * (q[1] - a[1]);
                if best.is_none_or(|(_, _, b)| d2 < b) {
                    best = Some((k, a, d2));
                }
            }
        }
        let Some((k, a, d2)) = best else { return };
        if !(d2 < reach * reach) {
            return;
        }
        // The surface's direction at `a`: from the returns either side of it, w beams away,
        // w growing until they are NORMAL_BASE apart (a normal from two neighbours alone
        // takes the range noise as tilt, which would make a corridor's length look
        // determined); the surface ends where two returns jump apart.
        let same = |x: &[f32; 2], y: &[f32; 2], w: usize| {
            hypot(x[0] - y[0], x[1] - y[1]) < (300.0 + 0.05 * hypot(a[0], a[1])) * w as f32
        };
        let mut span: Option<([f32; 2], [f32; 2])> = None;
        for w in 1..=NORMAL_SPAN {
            let (Some(l), Some(r)) = (k.checked_sub(w).and_then(point), point(k + w)) else {
                break;
            };
            if !same(&l, &r, 2 * w) {
                break;
            }
            span = Some((l, r));
            if hypot(r[0] - l[0], r[1] - l[1]) >= NORMAL_BASE {
                break;
            }
        }
        if span.is_none() {
            // One side only: the nearer neighbour on the same surface.
            let nb = [k.checked_sub(1).and_then(point), point(k + 1)];
            span = nb
                .iter()
                .flatten()
                .filter(|b| same(b, &a, 1))
                .min_by(|x, y| {
                    hypot(q[0] - x[0], q[1] - x[1]).total_cmp(&hypot(q[0] - y[0], q[1] - y[1]))
                })
                .map(|b| (a, *b));
        }
        let n = match span {
            Some((l, r)) => {
                let t = [r[0] - l[0], r[1] - l[1]];
                let len = hypot(t[0], t[1]);
                if !(len > 1e-3) {
                    return;
                }
                [-t[1] / len, t[0] / len]
            }
            None => {
                // No neighbour on the same surface: point to point along the offset.
                let l = hypot(q[0] - a[0], q[1] - a[1]);
                if !(l > 1e-3) {
                    return;
                }
                [(q[0] - a[0]) / l, (q[1] - a[1]) / l]
            }
        };
        let e = n[0] * (q[0] - a[0]) + n[1] * (q[1] - a[1]);
        // d q / d θ = (−(R p)_y, (R p)_x).
        let rp = [c * p[0] - s * p[1], s * p[0] + c * p[1]];
        let jt = n[0] * -rp[1] + n[1] * rp[0];
        if e.is_finite() && jt.is_finite() {
            f(n, jt, e);
        }
    });
}

/// [`crate::register_with`] verified and completed by the scans' points: among the refined
/// hypotheses the one whose points agree best wins when the features' winner's agree clearly
/// less ([`crate::Config::verify_margin`]); when the features do not register the pair, or
/// their answer's points agree less than [`crate::Config::verify_accept`], a point-to-line
/// ICP ([`icp`]) from that answer, from `guess` (the last motion, say) and from no motion is
/// tried, and its best answer is taken if its points agree at least that well (and better
/// than the features' answer). `prev_pts` and `curr_pts` are the two scans' ranges; empty
/// ones give [`crate::register_with`]'s answer.
///
/// ```
/// use pfe_pose::points::{register_scans, RangeScan};
/// use pfe_pose::{Config, Pose};
/// // A room seen from its centre and 0.3 m further on: no features given, the points suffice.
/// let room = |dx: f32| -> Vec<f32> {
///     (0..361).map(|i| {
///         let (s, c) = (-90.0f32 + 0.5 * i as f32).to_radians().sin_cos();
///         let mut r = f32::INFINITY;
///         if c > 1e-6 { r = r.min((3000.0 - dx) / c); }
///         if s > 1e-6 { r = r.min(2000.0 / s); }
///         if s < -1e-6 { r = r.min(2500.0 / -s); }
///         r
///     }).collect()
/// };
/// let (mut a, mut b) = (RangeScan::<361>::new(), RangeScan::<361>::new());
/// a.set(-1.5707964, 0.008726646, &room(0.0));
/// b.set(-1.5707964, 0.008726646, &room(300.0));
/// let reg = register_scans(&[], &a, &[], &b, Some(Pose::new(250.0, 0.0, 0.0)), &Config::default());
/// assert!(reg.is_registered() && (reg.rel.x - 300.0).abs() < 5.0);
/// ```
pub fn register_scans<const N: usize>(
    prev: &[crate::Observation],
    prev_pts: &RangeScan<N>,
    curr: &[crate::Observation],
    curr_pts: &RangeScan<N>,
    guess: Option<Pose>,
    cfg: &crate::Config,
) -> crate::Registration {
    let p = crate::set::Set::from_obs(prev.iter().copied(), cfg);
    let c = crate::set::Set::from_obs(curr.iter().copied(), cfg);
    let mut assoc = crate::register::Assoc::new();
    let verify = |pose: &Pose| agreement(prev_pts, curr_pts, pose).score();
    let points = !prev_pts.is_empty() && !curr_pts.is_empty();
    let mut r = crate::register::register_sets_verified::<{ crate::register::VERIFIED }>(
        &p,
        &c,
        None,
        cfg,
        &mut assoc,
        true,
        points.then_some(&verify as &dyn Fn(&Pose) -> f32),
    );
    r.dropped = p.dropped.saturating_add(c.dropped);
    r.invalid = p.invalid.saturating_add(c.invalid);
    if points {
        complete(r, prev_pts, curr_pts, guess, cfg)
    } else {
        r
    }
}

/// The registration `reg` of two scans kept when its points agree well enough, else the best
/// ICP answer from it, from `guess` and from no motion when that agrees well enough and
/// better (see [`register_scans`]).
pub(crate) fn complete<const N: usize>(
    reg: crate::Registration,
    prev_pts: &RangeScan<N>,
    curr_pts: &RangeScan<N>,
    guess: Option<Pose>,
    cfg: &crate::Config,
) -> crate::Registration {
    let reg = complete_from(reg, prev_pts, curr_pts, guess, cfg);
    if reg.is_registered() {
        polish(search_along(reg, prev_pts, curr_pts), prev_pts, curr_pts)
    } else {
        reg
    }
}

/// The ICP may move an "ok" answer of the features at most this far to polish it, mm (θ in
/// units of [`ROTATION_SCALE`]).
const POLISH_REACH: f32 = 150.0;

/// An "ok" answer of the features refined by [`icp`] on the points (the features' fits leave
/// a few cm the raw points resolve), taken when the points determine every direction, agree at
/// least as well and the ICP moved it less than [`POLISH_REACH`]; the covariance stays the
/// features' (the ICP's own is no better calibrated).
fn polish<const N: usize>(
    reg: crate::Registration,
    prev_pts: &RangeScan<N>,
    curr_pts: &RangeScan<N>,
) -> crate::Registration {
    if !matches!(reg.status, crate::Status::Ok) || reg.matches == (0, 0) {
        return reg;
    }
    let own = agreement(prev_pts, curr_pts, &reg.rel).score();
    let Some(r) = icp(prev_pts, curr_pts, &reg.rel) else {
        return reg;
    };
    let d = [
        r.pose.x - reg.rel.x,
        r.pose.y - reg.rel.y,
        crate::geom::wrap(r.pose.theta - reg.rel.theta) * ROTATION_SCALE,
    ];
    let moved = crate::geom::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if r.unobservable.is_none() && r.agreement.score() >= own && moved < POLISH_REACH {
        crate::Registration { rel: r.pose, ..reg }
    } else {
        reg
    }
}

/// Offsets tried either side of an answer along its least determined direction (3 m).
const SEARCH_OFFSETS: usize = 60;
/// Their spacing, mm (below the agreement's tolerance).
const SEARCH_STEP: f32 = 50.0;
/// An answer found along the least determined direction replaces `reg` when its points agree
/// this much better (or when `reg` is degenerate and the points determine every direction).
const SEARCH_MARGIN: f32 = 0.03;
/// Local maxima of the agreement along the direction refined by the ICP, best first.
const SEARCH_STARTS: usize = 2;
/// The best local maximum must agree this much better than any other at least 0.3 m from it,
/// or the direction stays ambiguous (periodic pillars, doors along a corridor).
const SEARCH_DISTINCT: f32 = 0.05;
/// A degenerate answer becomes "ok" only when the search's agrees at least this well.
const SEARCH_RESOLVE: f32 = 0.9;

/// `reg` (registered) checked along the direction its covariance determines least (a
/// corridor's length, periodic pillars): the points' agreement at offsets of up to
/// [`SEARCH_OFFSETS`] × [`SEARCH_STEP`] either way, the best local maxima refined by [`icp`]; the best ICP answer
/// replaces `reg` when its points agree clearly better, or, for a degenerate `reg`, when it
/// determines every direction and agrees at least as well.
fn search_along<const N: usize>(
    reg: crate::Registration,
    prev_pts: &RangeScan<N>,
    curr_pts: &RangeScan<N>,
) -> crate::Registration {
    let c = &reg.cov;
    let axis = 0.5 * libm::atan2f(2.0 * c[0][1], c[0][0] - c[1][1]);
    if !axis.is_finite() {
        return reg;
    }
    let (sn, cs) = sin_cos(axis);
    let own = agreement(prev_pts, curr_pts, &reg.rel).score();
    let at = |k: i32| {
        let d = k as f32 * SEARCH_STEP;
        Pose::new(reg.rel.x + d * cs, reg.rel.y + d * sn, reg.rel.theta)
    };
    let n = SEARCH_OFFSETS as i32;
    let mut scores = [f32::NEG_INFINITY; 2 * SEARCH_OFFSETS + 1];
    for (k, slot) in (-n..=n).zip(scores.iter_mut()) {
        *slot = agreement(prev_pts, curr_pts, &at(k)).score();
    }
    // The best local maxima, at least 0.3 m from each other.
    let peak = |i: usize| {
        let s = scores.get(i).copied().unwrap_or(f32::NEG_INFINITY);
        let left = i.checked_sub(1).and_then(|j| scores.get(j)).copied();
        let right = scores.get(i + 1).copied();
        s.is_finite() && left.is_none_or(|l| l <= s) && right.is_none_or(|r| r < s)
    };
    let mut starts = [None::<(i32, f32)>; SEARCH_STARTS];
    for slot in 0..SEARCH_STARTS {
        let mut top: Option<(i32, f32)> = None;
        for (i, &s) in scores.iter().enumerate() {
            let k = i as i32 - n;
            let taken = starts
                .iter()
                .flatten()
                .any(|(j, _)| (j - k).unsigned_abs() as f32 * SEARCH_STEP < 300.0);
            if peak(i) && !taken && top.is_none_or(|(_, b)| s > b) {
                top = Some((k, s));
            }
        }
        if let Some(t) = starts.get_mut(slot) {
            *t = top;
        }
    }
    let distinct = match starts {
        [Some((_, a)), Some((_, b))] => a - b >= SEARCH_DISTINCT,
        _ => true,
    };
    if !distinct {
        return reg;
    }
    let degenerate = matches!(reg.status, crate::Status::Degenerate { .. });
    let mut best: Option<(IcpResult, f32)> = None;
    for (k, _) in starts.iter().flatten() {
        if let Some(r) = icp(prev_pts, curr_pts, &at(*k)) {
            let s = r.agreement.score();
            if r.unobservable.is_none() && best.as_ref().is_none_or(|(_, b)| s > *b) {
                best = Some((r, s));
            }
        }
    }
    match best {
        Some((r, s))
            if s > own + SEARCH_MARGIN
                || (degenerate && s >= own - RESOLVE_SLACK && s >= SEARCH_RESOLVE) =>
        {
            crate::Registration {
                rel: r.pose,
                cov: r.cov,
                status: crate::Status::Ok,
                matches: (0, 0),
                chi2: 0.0,
                ..reg
            }
        }
        _ => reg,
    }
}

/// [`complete`] before the search along the answer's least determined direction.
fn complete_from<const N: usize>(
    reg: crate::Registration,
    prev_pts: &RangeScan<N>,
    curr_pts: &RangeScan<N>,
    guess: Option<Pose>,
    cfg: &crate::Config,
) -> crate::Registration {
    let own = if reg.is_registered() {
        agreement(prev_pts, curr_pts, &reg.rel).score()
    } else {
        f32::NEG_INFINITY
    };
    if own >= cfg.verify_keep {
        if let (crate::Status::Degenerate { direction }, true) = (reg.status, cfg.points_resolve) {
            // What the features cannot tell the points may: the ICP from the features'
            // answer, taken when it determines every direction, agrees as well and moved
            // little across the features' unobservable direction.
            if let Some(r) = icp(prev_pts, curr_pts, &reg.rel) {
                let d = [
                    r.pose.x - reg.rel.x,
                    r.pose.y - reg.rel.y,
                    crate::geom::wrap(r.pose.theta - reg.rel.theta) * ROTATION_SCALE,
                ];
                let along = d[0] * direction[0] + d[1] * direction[1] + d[2] * direction[2];
                let across = [
                    d[0] - along * direction[0],
                    d[1] - along * direction[1],
                    d[2] - along * direction[2],
                ];
                let off = crate::geom::sqrt(
                    across[0] * across[0] + across[1] * across[1] + across[2] * across[2],
                );
                if r.unobservable.is_none()
                    && r.agreement.score() >= own - RESOLVE_SLACK
                    && off < RESOLVE_ACROSS
                {
                    return crate::Registration {
                        rel: r.pose,
                        cov: r.cov,
                        status: crate::Status::Ok,
                        ..reg
                    };
                }
            }
        }
        return reg;
    }
    let starts = [
        reg.is_registered().then_some(reg.rel),
        guess.filter(Pose::is_finite),
        Some(Pose::IDENTITY),
    ];
    let mut best: Option<(IcpResult, f32)> = None;
    for start in starts.iter().flatten() {
        if let Some(r) = icp(prev_pts, curr_pts, start) {
            let s = r.agreement.score();
            // The earlier starts (the features' answer, then the guess) unless a later one's
            // points agree clearly better: along a direction the points cannot tell the
            // answer stays near its start.
            if best.as_ref().is_none_or(|(_, b)| s > *b + 0.02) {
                best = Some((r, s));
            }
        }
    }
    match best {
        Some((r, s)) if s >= cfg.verify_accept && s > own + cfg.verify_margin => {
            crate::Registration {
                rel: r.pose,
                cov: r.cov,
                status: match r.unobservable {
                    Some(direction) => crate::Status::Degenerate { direction },
                    None => crate::Status::Ok,
                },
                matches: (0, 0),
                chi2: 0.0,
                ..reg
            }
        }
        _ => reg,
    }
}

/// A key scan refines a pose when their points agree at least this well after the ICP.
const KEY_AGREE: f32 = 0.9;
/// ...and the ICP moved the pose less than this, mm (θ in units of [`ROTATION_SCALE`]).
const KEY_REACH: f32 = 80.0;

/// `pose` (of the scan `curr`, in the odometry frame) refined by [`icp`] against the key scan
/// `key` at `key_pose`: registering against one key scan for many scans keeps their errors from
/// adding up as chained pairs do. `None` (the caller then takes `curr` as the new key) when the
/// points do not determine every direction, agree less than [`KEY_AGREE`] or the ICP moved
/// the pose [`KEY_REACH`] or more.
pub fn refine_on_key<const N: usize>(
    key: &RangeScan<N>,
    key_pose: &Pose,
    curr: &RangeScan<N>,
    pose: &Pose,
) -> Option<Pose> {
    let rel = key_pose.inverse().compose(pose);
    let r = icp(key, curr, &rel)?;
    let d = [
        r.pose.x - rel.x,
        r.pose.y - rel.y,
        crate::geom::wrap(r.pose.theta - rel.theta) * ROTATION_SCALE,
    ];
    let moved = crate::geom::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    let out = key_pose.compose(&r.pose);
    (r.unobservable.is_none()
        && r.agreement.score() >= KEY_AGREE
        && moved < KEY_REACH
        && out.is_finite())
    .then_some(out)
}

/// A points' answer may agree this much less than the features' degenerate one and still
/// resolve its direction.
const RESOLVE_SLACK: f32 = 0.02;
/// ...and move at most this far off the features' unobservable direction (mm, θ in units of
/// [`ROTATION_SCALE`]).
const RESOLVE_ACROSS: f32 = 100.0;

/// Beams kept of a scan by `pfe odometry`, the pose benchmark and the firmware: an LMS200's
/// 180° at 0.5° (361); a scan of more beams keeps every k-th one.
pub const SCAN_BEAMS: usize = 361;
