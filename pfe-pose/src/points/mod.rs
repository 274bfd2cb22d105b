//! The scans' own points: a compact copy of a scan's ranges ([`RangeScan`]), the check of a
//! pose against them ([`agreement`]) and a point-to-line ICP ([`icp()`], Censi 2008) for when
//! the features cannot register a pair.
//!
//! Features alone cannot tell some wrong poses from the right one (a corridor's pillars 0.7 m
//! apart, short lines far away): the scans' points can. Under the right pose the current
//! scan's points lie on what the previous scan saw; under a wrong one many lie where the
//! previous scan saw through (free space), which no static scene allows.

mod icp;
mod recover;
mod search;

pub use icp::{icp, IcpResult, ICP_CORRELATION};
pub use recover::{bridge, recheck, RECHECK_BELOW};
pub use search::{back_to_key, refine_on_key};

use crate::geom::{hypot, sin_cos, Pose};
use crate::register::ROTATION_SCALE;
use search::{polish, search_along};

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

/// [`crate::register_with`] verified and completed by the scans' points: among the refined
/// hypotheses the one whose points agree best wins when the features' winner's agree clearly
/// less ([`crate::Config::verify_margin`]); when the features do not register the pair, or
/// their answer's points agree less than [`crate::Config::verify_keep`], a point-to-line
/// ICP ([`icp()`]) from that answer, from `guess` (the last motion, say) and from no motion is
/// tried, and its best answer is taken if its points agree at least
/// [`crate::Config::verify_accept`] and better than the features' answer by
/// [`crate::Config::verify_margin`]. An answer whose points then still agree less than
/// [`crate::Config::verify_accept`] (or none) is looked at again over the whole circle of
/// headings (within [`crate::Config::max_rotation`]) and replaced by an ICP answer that agrees
/// at least that well and 0.25 better; otherwise it stays, however low its points' score.
/// `prev_pts` and `curr_pts` are the two scans' ranges; empty
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
    let (mut r, replaced) = crate::register::register_sets_verified::<{ crate::register::VERIFIED }>(
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
        complete(r, replaced, prev_pts, curr_pts, guess, cfg)
    } else {
        r
    }
}

/// The registration `reg` of two scans kept when its points agree well enough, else the best
/// ICP answer from it, from `guess` and from no motion, or from the second look over the
/// circle of headings, when that agrees well enough and better (see [`register_scans`]). `replaced`: the features' winner when the points'
/// verification preferred another hypothesis (see [`rejudge`]).
pub(crate) fn complete<const N: usize>(
    reg: crate::Registration,
    replaced: Option<Pose>,
    prev_pts: &RangeScan<N>,
    curr_pts: &RangeScan<N>,
    guess: Option<Pose>,
    cfg: &crate::Config,
) -> crate::Registration {
    // The direction the features could not tell (a corridor's length), kept for the search
    // when the ICP replaces their answer: the ICP's covariance points only roughly along it.
    let hint = match reg.status {
        crate::Status::Degenerate { direction } => Some(direction),
        _ => None,
    };
    let reg = match replaced {
        Some(winner) => rejudge(reg, &winner, prev_pts, curr_pts),
        None => reg,
    };
    let mut reg = complete_from(reg, prev_pts, curr_pts, guess, cfg);
    // An answer the points agree with less than an ICP answer must (or none): the second look
    // over the circle of headings.
    let low = !reg.is_registered()
        || !(agreement(prev_pts, curr_pts, &reg.rel).score() >= cfg.verify_accept);
    if low {
        let rel = reg.is_registered().then_some(reg.rel);
        if let Some(r) = recover::second_look(prev_pts, curr_pts, rel.as_ref(), guess, cfg) {
            reg = from_icp(reg, &r);
        }
    }
    if reg.is_registered() {
        let reg = polish(
            search_along(reg, hint, prev_pts, curr_pts),
            prev_pts,
            curr_pts,
        );
        widen(reg, agreement(prev_pts, curr_pts, &reg.rel).score())
    } else {
        reg
    }
}

/// `reg`, the hypothesis the points' verification preferred to the features' `winner` by their
/// agreement before the ICP, judged again after it: the ICP's answer from `winner` replaces
/// `reg` when its points agree better than both `reg` and the ICP's answer from `reg`.
/// Unrefined, a hypothesis near the right pose can agree less than a wrong one (csail pairs 17
/// and 300: −0.16 and 0.28 against 0.08 and 0.45; 0.61 and 0.53 after the ICP).
fn rejudge<const N: usize>(
    reg: crate::Registration,
    winner: &Pose,
    prev_pts: &RangeScan<N>,
    curr_pts: &RangeScan<N>,
) -> crate::Registration {
    let Some(w) = icp(prev_pts, curr_pts, winner) else {
        return reg;
    };
    let mut own = f32::NEG_INFINITY;
    if reg.is_registered() {
        own = agreement(prev_pts, curr_pts, &reg.rel).score();
        if let Some(r) = icp(prev_pts, curr_pts, &reg.rel) {
            own = own.max(r.agreement.score());
        }
    }
    if w.agreement.score() > own {
        from_icp(reg, &w)
    } else {
        reg
    }
}

/// `reg` replaced by the ICP's answer `r`: its pose, covariance and status.
fn from_icp(reg: crate::Registration, r: &IcpResult) -> crate::Registration {
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

/// The least agreement [`widen`] divides by: an "ok" answer's covariance grows at most
/// fourfold.
const WIDEN_FLOOR: f32 = 0.25;

/// An "ok" answer's covariance divided by its points' agreement `score` (at least
/// [`WIDEN_FLOOR`], at most 1). The features' and the ICP's covariances take every match as
/// a static surface seen in both scans; where only a fraction of the points agree with the
/// answer (people walking by, surfaces seen in one scan only, no returns), only that fraction
/// supports it, and its errors were measured larger in that proportion.
pub(crate) fn widen(reg: crate::Registration, score: f32) -> crate::Registration {
    if !matches!(reg.status, crate::Status::Ok) || !(score < 1.0) {
        return reg;
    }
    let k = 1.0 / score.max(WIDEN_FLOOR);
    crate::Registration {
        cov: reg.cov.map(|r| r.map(|v| v * k)),
        ..reg
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
        Some((r, s)) if s >= cfg.verify_accept && s > own + cfg.verify_margin => from_icp(reg, &r),
        _ => reg,
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The ranges of a rectangular room (x −2.5…3 m, y −2.5…2 m) with a pillar (0.2 m across)
    /// at (1.5 m, 1 m), seen from `pose` all round at 1°.
    fn room(pose: &Pose) -> RangeScan<361> {
        let mut r = [0.0f32; 360];
        for (i, slot) in r.iter_mut().enumerate() {
            let b = pose.theta + (-180.0 + i as f32).to_radians();
            let (s, c) = (libm::sinf(b), libm::cosf(b));
            let mut t = f32::INFINITY;
            if c > 1e-6 {
                t = t.min((3000.0 - pose.x) / c);
            }
            if c < -1e-6 {
                t = t.min((-2500.0 - pose.x) / c);
            }
            if s > 1e-6 {
                t = t.min((2000.0 - pose.y) / s);
            }
            if s < -1e-6 {
                t = t.min((-2500.0 - pose.y) / s);
            }
            let o = [1500.0 - pose.x, 1000.0 - pose.y];
            let along = o[0] * c + o[1] * s;
            let off2 = o[0] * o[0] + o[1] * o[1] - along * along;
            if along > 0.0 && off2 < 100.0 * 100.0 {
                t = t.min(along - crate::geom::sqrt(100.0 * 100.0 - off2));
            }
            *slot = t;
        }
        let mut scan = RangeScan::new();
        assert!(scan.set(-core::f32::consts::PI, 1f32.to_radians(), &r));
        scan
    }

    fn registration(rel: Pose) -> crate::Registration {
        crate::Registration {
            rel,
            cov: [[400.0, 0.0, 0.0], [0.0, 400.0, 0.0], [0.0, 0.0, 1e-4]],
            status: crate::Status::Ok,
            matches: (3, 0),
            hypotheses: 10,
            dropped: 0,
            invalid: 0,
            chi2: 1.0,
        }
    }

    /// The features' winner 0.06 rad and 70 mm off the truth agrees less, unrefined, than the
    /// room's half-turn alias (only the pillar tells them apart), which made the verification
    /// prefer the alias; refined by the ICP the winner reaches the truth and replaces it. The
    /// right hypothesis stays.
    #[test]
    fn rejudge_takes_the_winner_the_icp_brings_to_the_truth() {
        let truth = Pose::new(400.0, 150.0, 0.25);
        let (a, b) = (room(&Pose::IDENTITY), room(&truth));
        let winner = truth.compose(&Pose::new(60.0, -40.0, 0.06));
        let wrong = Pose::new(
            500.0 - truth.x,
            -500.0 - truth.y,
            truth.theta + core::f32::consts::PI,
        );
        let score = |p: &Pose| agreement(&a, &b, p).score();
        assert!(
            score(&wrong) > score(&winner),
            "{} {}",
            score(&wrong),
            score(&winner)
        );
        let r = rejudge(registration(wrong), &winner, &a, &b);
        assert_eq!(r.status, crate::Status::Ok);
        assert!(
            crate::geom::hypot(r.rel.x - truth.x, r.rel.y - truth.y) < 20.0
                && crate::geom::wrap(r.rel.theta - truth.theta).abs() < 0.005,
            "{:?}",
            r.rel
        );
        let kept = rejudge(registration(truth), &wrong, &a, &b);
        assert_eq!(kept.rel, truth);
    }
}
