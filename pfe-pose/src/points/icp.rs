//! [`icp`]: point-to-line ICP (Censi 2008) of one scan's points against another's.

use super::{agreement, Agreement, RangeScan};
use crate::geom::{eigen_sym3, hypot, inverse_spd3, sin_cos, Cov3, Pose, ZERO3};
use crate::register::{ROTATION_SCALE, UNOBSERVABLE_VARIANCE};

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
