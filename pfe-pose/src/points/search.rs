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
            return reg;
        }
        clear = margin(&scores, k0 + n, best, &peak) >= SEARCH_CLEAR;
    }
    let mut best: Option<(IcpResult, f32, bool)> = None;
    for (i, (k, _)) in starts.iter().flatten().enumerate() {
        if let Some(r) = icp(prev_pts, curr_pts, &at(*k)) {
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

#[cfg(test)]
mod tests {
    use super::*;

    fn peaks(scores: &[f32]) -> impl Fn(usize) -> bool + '_ {
        move |i| {
            let s = scores.get(i).copied().unwrap_or(f32::NEG_INFINITY);
            let left = i.checked_sub(1).and_then(|j| scores.get(j)).copied();
            let right = scores.get(i + 1).copied();
            left.is_none_or(|l| l <= s) && right.is_none_or(|r| r < s)
        }
    }

    /// Range along a ray from `o` with heading `b` to a circle (centre `c`, radius `r`), mm.
    fn to_circle(o: [f32; 2], b: f32, c: [f32; 2], r: f32) -> f32 {
        let (s, cs) = sin_cos(b);
        let v = [c[0] - o[0], c[1] - o[1]];
        let along = v[0] * cs + v[1] * s;
        let off2 = v[0] * v[0] + v[1] * v[1] - along * along;
        if along > 0.0 && off2 < r * r {
            along - crate::geom::sqrt(r * r - off2)
        } else {
            f32::INFINITY
        }
    }

    /// An LMS200's scan (180° at 0.5°) from `pose` in a room (x −2.5…4 m, y −1.5…1.5 m) with
    /// a pillar (0.2 m across) at (1.5 m, 0.8 m) and, when `walker`, a person (0.5 m across)
    /// at (2 m, −0.6 m).
    fn room_scan(pose: &Pose, walker: bool) -> RangeScan<361> {
        let o = [pose.x, pose.y];
        let mut r = [0.0f32; 361];
        for (i, slot) in r.iter_mut().enumerate() {
            let b = pose.theta + (-90.0 + 0.5 * i as f32).to_radians();
            let (s, c) = sin_cos(b);
            let mut t = f32::INFINITY;
            for (dir, lo, hi) in [
                (c, -2500.0 - o[0], 4000.0 - o[0]),
                (s, -1500.0 - o[1], 1500.0 - o[1]),
            ] {
                if dir > 1e-6 {
                    t = t.min(hi / dir);
                } else if dir < -1e-6 {
                    t = t.min(lo / dir);
                }
            }
            t = t.min(to_circle(o, b, [1500.0, 800.0], 100.0));
            if walker {
                t = t.min(to_circle(o, b, [2000.0, -600.0], 250.0));
            }
            *slot = t;
        }
        let mut scan = RangeScan::new();
        assert!(scan.set(-core::f32::consts::FRAC_PI_2, 0.5f32.to_radians(), &r));
        scan
    }

    /// A degenerate answer near the truth (40 mm off along its unobservable direction, so
    /// the points agree about as well there), in a scene whose points tell that direction
    /// (one clear maximum of their agreement) but agree less than 0.9 (a person walked in:
    /// infinite-corridor's pairs agreeing 0.7–0.9), is resolved to the truth; without the
    /// walker it was resolved before too.
    #[test]
    fn one_clear_maximum_resolves_a_degenerate_answer() {
        let truth = Pose::new(400.0, 50.0, 0.05);
        for walker in [true, false] {
            let (a, b) = (room_scan(&Pose::IDENTITY, false), room_scan(&truth, walker));
            let at_truth = agreement(&a, &b, &truth).score();
            assert!(walker == (at_truth < SEARCH_RESOLVE), "{at_truth}");
            let off = Pose::new(truth.x + 40.0, truth.y, truth.theta);
            let reg = crate::Registration {
                rel: off,
                cov: [[1e12, 0.0, 0.0], [0.0, 400.0, 0.0], [0.0, 0.0, 1e-4]],
                status: crate::Status::Degenerate {
                    direction: [1.0, 0.0, 0.0],
                },
                matches: (3, 0),
                hypotheses: 10,
                dropped: 0,
                invalid: 0,
                chi2: 1.0,
            };
            let r = search_along(reg, Some([1.0, 0.0, 0.0]), &a, &b);
            assert_eq!(r.status, crate::Status::Ok, "walker {walker}, {at_truth}");
            assert!(
                crate::geom::hypot(r.rel.x - truth.x, r.rel.y - truth.y) < 30.0
                    && crate::geom::wrap(r.rel.theta - truth.theta).abs() < 0.01,
                "{:?}",
                r.rel
            );
        }
    }

    /// Two maxima as high 1 m apart along the direction (pillars along a corridor) leave a
    /// degenerate answer as it was; one clear maximum does not.
    #[test]
    fn margin_of_the_best_maximum() {
        let mut two = [0.2f32; 41];
        two[10] = 0.8;
        two[30] = 0.75;
        assert!(margin(&two, 10, 0.8, &peaks(&two)) < SEARCH_CLEAR);
        two[30] = 0.6;
        assert!(margin(&two, 10, 0.8, &peaks(&two)) >= SEARCH_CLEAR);
        let mut one = [0.2f32; 41];
        one[20] = 0.7;
        assert!((margin(&one, 20, 0.7, &peaks(&one)) - 0.5).abs() < 1e-6);
    }

    /// A broad maximum with bumps on it (aces pair 253: 0.93–0.95 over 0.5 m) has no rival for
    /// an "ok" answer, which only moves to a better agreement; for a degenerate one, which
    /// the search would declare determined, the bumps still count. Two maxima set apart by a
    /// dip (pillars along a corridor) are rivals either way.
    #[test]
    fn bumps_on_one_maximum_are_no_rivals() {
        let mut broad = [0.2f32; 41];
        for (i, s) in broad.iter_mut().enumerate().skip(10).take(20) {
            *s = if i % 3 == 0 { 0.95 } else { 0.92 };
        }
        let peak = peaks(&broad);
        let best = broad.iter().position(|s| *s == 0.95).unwrap_or(0) as i32;
        assert!(!rival(&broad, best, 0.95, true, &peak));
        assert!(rival(&broad, best, 0.95, false, &peak));
        let mut two = [0.2f32; 41];
        two[10] = 0.95;
        two[30] = 0.93;
        assert!(rival(&two, 10, 0.95, true, &peaks(&two)));
        assert!(rival(&two, 10, 0.95, false, &peaks(&two)));
        two[30] = 0.85;
        assert!(!rival(&two, 10, 0.95, true, &peaks(&two)));
    }
}
