//! The points' search along an answer's least determined direction, the ICP's polish of the
//! features' answer and the refinement against a key scan.

use super::{agreement, icp, IcpResult, RangeScan, RESOLVE_SLACK};
use crate::geom::{sin_cos, Pose};
use crate::register::ROTATION_SCALE;

/// The ICP may move an "ok" answer of the features at most this far to polish it, mm (θ in
/// units of [`ROTATION_SCALE`]).
const POLISH_REACH: f32 = 150.0;

/// An "ok" answer of the features refined by [`icp()`] on the points (the features' fits leave
/// a few cm the raw points resolve), taken when the points determine every direction, agree at
/// least as well and the ICP moved it less than [`POLISH_REACH`]; the covariance stays the
/// features' (the ICP's own is no better calibrated).
pub(super) fn polish<const N: usize>(
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
/// A local maximum along the features' unobservable direction that agrees at least
/// [`SEARCH_CLEAR_FLOOR`] stays (its variance along it [`SEARCH_STEP`]²) when the ICP's answer
/// from it agrees this much less (see [`search_along`]).
const SEARCH_SLIDE: f32 = 0.03;
/// Local maxima of the agreement along the direction refined by the ICP, best first.
const SEARCH_STARTS: usize = 2;
/// The best local maximum must agree this much better than any other at least 0.3 m from it
/// that a dip of as much sets apart, or the direction stays ambiguous (periodic pillars, doors
/// along a corridor); bumps on one broad peak are no rivals.
const SEARCH_DISTINCT: f32 = 0.05;
/// A degenerate answer becomes "ok" only when the search's agrees at least this well...
const SEARCH_RESOLVE: f32 = 0.9;
/// ...or when the profile has one clear maximum: it agrees this much better than every other
/// local maximum (or end of the profile) at least 0.3 m from it...
const SEARCH_CLEAR: f32 = 0.08;
/// ...and the ICP's answer from it agrees at least this well, and at most this much less
/// than the degenerate answer (the ICP fits the surfaces, not the agreement: a few
/// hundredths either way are its tolerance's, not the pose's).
const SEARCH_CLEAR_FLOOR: f32 = 0.5;
const SEARCH_CLEAR_SLACK: f32 = 0.05;

/// `reg` (registered) checked along the direction its covariance determines least (a
/// corridor's length, periodic pillars; `hint`, the features' unobservable direction, when
/// they had one): the points' agreement at offsets of up to
/// [`SEARCH_OFFSETS`] × [`SEARCH_STEP`] either way, the best local maxima refined by [`icp()`]; the best ICP answer
/// replaces `reg` when its points agree clearly better, or, for a degenerate `reg`, when it
/// determines every direction and agrees at least as well.
pub(super) fn search_along<const N: usize>(
    reg: crate::Registration,
    hint: Option<[f32; 3]>,
    prev_pts: &RangeScan<N>,
    curr_pts: &RangeScan<N>,
) -> crate::Registration {
    let c = &reg.cov;
    let axis = match hint {
        // Mostly a translation: its heading.
        Some(d) if d[0] * d[0] + d[1] * d[1] > 0.5 => libm::atan2f(d[1], d[0]),
        _ => 0.5 * libm::atan2f(2.0 * c[0][1], c[0][0] - c[1][1]),
    };
    if !axis.is_finite() {
        return reg;
    }
    let own = agreement(prev_pts, curr_pts, &reg.rel).score();
    let at = along(&reg.rel, axis);
    let n = SEARCH_OFFSETS as i32;
    let scores = profile(&reg.rel, axis, prev_pts, curr_pts);
    let peak = |i: usize| is_peak(&scores, i);
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
    let degenerate = matches!(reg.status, crate::Status::Degenerate { .. });
    let mut clear = false;
    if let Some((k0, best)) = starts.first().copied().flatten() {
        // A degenerate answer is resolved by a distinct maximum only: on a broad one the
        // points cannot tell where along it either.
        if rival(&scores, k0 + n, best, !degenerate, &peak) {
            return if degenerate {
                refined_rivals(reg, own, k0, best, axis, &scores, prev_pts, curr_pts)
            } else {
                reg
            };
        }
        clear = margin(&scores, k0 + n, best, &peak) >= SEARCH_CLEAR;
    }
    let mut best: Option<(IcpResult, f32, bool)> = None;
    for (i, (k, sk)) in starts.iter().flatten().enumerate() {
        if let Some(mut r) = icp(prev_pts, curr_pts, &at(*k)) {
            // The ICP fits the surfaces, not the agreement: along a corridor (the features'
            // unobservable direction) it can slide off a start its points agree with well and
            // clearly better. Then the start stands, with the ICP's covariance widened along
            // the corridor by the profile's step (a standard deviation of one step).
            if hint.is_some()
                && *sk >= SEARCH_CLEAR_FLOOR
                && r.agreement.score() < sk - SEARCH_SLIDE
            {
                r.pose = at(*k);
                r.agreement = agreement(prev_pts, curr_pts, &r.pose);
                let (sn, cs) = sin_cos(axis);
                let v = SEARCH_STEP * SEARCH_STEP;
                r.cov[0][0] += v * cs * cs;
                r.cov[1][1] += v * sn * sn;
                r.cov[0][1] += v * cs * sn;
                r.cov[1][0] += v * cs * sn;
            }
            let s = r.agreement.score();
            if r.unobservable.is_none() && best.as_ref().is_none_or(|(_, b, _)| s > *b) {
                best = Some((r, s, i == 0));
            }
        }
    }
    match best {
        Some((r, s, first))
            if s > own + SEARCH_MARGIN
                || (degenerate && s >= own - RESOLVE_SLACK && s >= SEARCH_RESOLVE)
                || (degenerate
                    && clear
                    && first
                    && s >= own - SEARCH_CLEAR_SLACK
                    && s >= SEARCH_CLEAR_FLOOR) =>
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

/// Rivals of a degenerate answer's best maximum refined by the ICP, at most this many (more
/// leave the answer as it was).
const RIVALS_REFINED: usize = 4;

/// The degenerate `reg` (its points agree `own`) whose profile `scores` along `axis` has
/// rivals to its best maximum (`k0`, agreeing `best`), judged after the ICP refined them: the
/// ICP's answer from the best maximum replaces `reg` ("ok") when it determines every
/// direction, agrees at least [`SEARCH_RESOLVE`] and within [`RESOLVE_SLACK`] of `own`, and
/// the ICP's answer from every rival (at most [`RIVALS_REFINED`] of them) agrees
/// [`SEARCH_DISTINCT`] less or lands within 0.3 m of it, determining every direction and
/// agreeing no better; `reg` otherwise. Unrefined, the profile's offsets keep the degenerate
/// answer's heading and sideways position: bumps on one broad maximum, or a maximum the wrong
/// heading spreads, make rivals that the ICP takes apart.
#[allow(clippy::too_many_arguments)]
fn refined_rivals<const N: usize>(
    reg: crate::Registration,
    own: f32,
    k0: i32,
    best: f32,
    axis: f32,
    scores: &[f32],
    prev_pts: &RangeScan<N>,
    curr_pts: &RangeScan<N>,
) -> crate::Registration {
    let at = along(&reg.rel, axis);
    let Some(r0) = icp(prev_pts, curr_pts, &at(k0)) else {
        return reg;
    };
    let s0 = r0.agreement.score();
    if r0.unobservable.is_some() || !(s0 >= SEARCH_RESOLVE && s0 >= own - RESOLVE_SLACK) {
        return reg;
    }
    let n = SEARCH_OFFSETS as i32;
    let apart = (300.0 / SEARCH_STEP) as i32;
    let mut count = 0usize;
    for (i, &s) in scores.iter().enumerate() {
        let k = i as i32 - n;
        if (k - k0).abs() < apart || !(s > best - SEARCH_DISTINCT) || !is_peak(scores, i) {
            continue;
        }
        count += 1;
        if count > RIVALS_REFINED {
            return reg;
        }
        let Some(r) = icp(prev_pts, curr_pts, &at(k)) else {
            return reg;
        };
        let same = crate::geom::hypot(r.pose.x - r0.pose.x, r.pose.y - r0.pose.y) < 300.0
            && r.unobservable.is_none()
            && r.agreement.score() <= s0;
        if !same && r.agreement.score() > s0 - SEARCH_DISTINCT {
            return reg;
        }
    }
    crate::Registration {
        rel: r0.pose,
        cov: r0.cov,
        status: crate::Status::Ok,
        matches: (0, 0),
        chi2: 0.0,
        ..reg
    }
}

/// The pose `k` × [`SEARCH_STEP`] from `rel` along the heading `axis` (rad).
fn along(rel: &Pose, axis: f32) -> impl Fn(i32) -> Pose + '_ {
    let (sn, cs) = sin_cos(axis);
    move |k: i32| {
        let d = k as f32 * SEARCH_STEP;
        Pose::new(rel.x + d * cs, rel.y + d * sn, rel.theta)
    }
}

/// The points' agreement at offsets of up to [`SEARCH_OFFSETS`] × [`SEARCH_STEP`] either
/// side of `rel` along the heading `axis` (rad).
fn profile<const N: usize>(
    rel: &Pose,
    axis: f32,
    prev_pts: &RangeScan<N>,
    curr_pts: &RangeScan<N>,
) -> [f32; 2 * SEARCH_OFFSETS + 1] {
    let at = along(rel, axis);
    let n = SEARCH_OFFSETS as i32;
    let mut scores = [f32::NEG_INFINITY; 2 * SEARCH_OFFSETS + 1];
    for (k, slot) in (-n..=n).zip(scores.iter_mut()) {
        *slot = agreement(prev_pts, curr_pts, &at(k)).score();
    }
    scores
}

/// True when sample `i` of `scores` is a local maximum (the first of a plateau; an end counts
/// when its one neighbour is not above it).
fn is_peak(scores: &[f32], i: usize) -> bool {
    let s = scores.get(i).copied().unwrap_or(f32::NEG_INFINITY);
    let left = i.checked_sub(1).and_then(|j| scores.get(j)).copied();
    let right = scores.get(i + 1).copied();
    s.is_finite() && left.is_none_or(|l| l <= s) && right.is_none_or(|r| r < s)
}

/// True when `scores` (the profile) has a local maximum (`peak`) at least 0.3 m from the best
/// one at `at` that agrees within [`SEARCH_DISTINCT`] of its score `best` and, with `dip`, is
/// set apart from it by a dip of [`SEARCH_DISTINCT`] below its own score.
fn rival(scores: &[f32], at: i32, best: f32, dip: bool, peak: &dyn Fn(usize) -> bool) -> bool {
    let apart = (300.0 / SEARCH_STEP) as i32;
    scores.iter().enumerate().any(|(i, &s)| {
        let i = i as i32;
        if (i - at).abs() < apart || !(s > best - SEARCH_DISTINCT) || !peak(i as usize) {
            return false;
        }
        if !dip {
            return true;
        }
        let (lo, hi) = (i.min(at), i.max(at));
        let low = scores
            .iter()
            .skip(lo as usize)
            .take((hi - lo) as usize)
            .fold(f32::INFINITY, |m, &v| m.min(v));
        low < s - SEARCH_DISTINCT
    })
}

/// How much better the profile's best maximum at `at` (score `best`) agrees than every other
/// local maximum (`peak`, the profile's ends included) at least 0.3 m from it; `best` less the
/// profile's least score when there is none.
fn margin(scores: &[f32], at: i32, best: f32, peak: &dyn Fn(usize) -> bool) -> f32 {
    let apart = (300.0 / SEARCH_STEP) as i32;
    let mut other = scores.iter().fold(f32::INFINITY, |m, &v| m.min(v));
    for (i, &s) in scores.iter().enumerate() {
        if (i as i32 - at).abs() >= apart && peak(i) && s > other {
            other = s;
        }
    }
    best - other
}

/// A key scan refines a pose when their points agree at least this well after the ICP.
const KEY_AGREE: f32 = 0.9;
/// ...and the ICP moved the pose less than this, mm (θ in units of [`ROTATION_SCALE`]).
const KEY_REACH: f32 = 80.0;

/// `pose` (of the scan `curr`, in the odometry frame) refined by [`icp()`] against the key scan
/// `key` at `key_pose`: registering against one key scan for many scans keeps their errors from
/// adding up as chained pairs do. `None` (the caller then takes `curr` as the new key) when the
/// points do not determine every direction, agree less than 0.9 ([`agreement`]) or the ICP
/// moved the pose 80 mm or more (θ in units of [`ROTATION_SCALE`]).
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

/// A former key scan takes a scan back ([`back_to_key`]) when their points agree at least this
/// well after the ICP...
const BACK_AGREE: f32 = 0.8;
/// ...and this much better than under the chain's pose.
const BACK_MARGIN: f32 = 0.25;

/// `curr`'s pose against a former key scan `key` at `key_pose`, when the steps since it went
/// astray (scans from elsewhere, registered as a jump): [`icp()`] from `guess` (the pose the
/// motion before the jump predicts) determines every direction, agrees at least 0.8 and
/// `BACK_MARGIN` (0.25) better than `curr` at `pose` (the chain's answer). The pose (odometry
/// frame) and the ICP's covariance in `key`'s frame; `None` keeps the chain's answer.
pub fn back_to_key<const N: usize>(
    key: &RangeScan<N>,
    key_pose: &Pose,
    curr: &RangeScan<N>,
    guess: &Pose,
    pose: &Pose,
) -> Option<(Pose, crate::geom::Cov3)> {
    if key.is_empty() || curr.is_empty() {
        return None;
    }
    let from = key_pose.inverse();
    let r = icp(key, curr, &from.compose(guess))?;
    let own = agreement(key, curr, &from.compose(pose)).score();
    let score = r.agreement.score();
    let out = key_pose.compose(&r.pose);
    (r.unobservable.is_none()
        && score >= BACK_AGREE
        && score >= own + BACK_MARGIN
        && out.is_finite())
    .then_some((out, r.cov))
}

#[cfg(test)]
#[path = "search_tests.rs"]
mod tests;
