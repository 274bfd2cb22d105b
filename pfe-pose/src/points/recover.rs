//! The second look at a step whose points contradict it (the odometry's [`recheck`] and
//! [`bridge`], the pair's `second_look`): the points' agreement screened over a grid of
//! motions (headings 5° apart up to ±40° from the last motion's, translations 0.5 m apart;
//! or the circle of headings), the best few refined by ICP, so that a wrong answer of the features (a 90° turn where the
//! robot went on straight, a corridor's length off by metres) is replaced by what the points
//! show.

use super::{agreement, icp, IcpResult, RangeScan};
use crate::geom::Pose;

/// A step whose points agree less than this with the previous scan is looked at again.
pub const RECHECK_BELOW: f32 = 0.6;
/// An answer of the second look replaces the step when its points agree at least this well...
const RECHECK_ACCEPT: f32 = 0.5;
/// ...and this much better than the step's.
const RECHECK_MARGIN: f32 = 0.25;
/// A later start's answer replaces an earlier one's only when its points agree this much
/// better (the last motion's comes first: along what the points cannot tell it stays there).
const RECHECK_PREFER: f32 = 0.02;
/// The grid's headings: `HEADINGS` either side of the last motion's, `HEADING_STEP` apart
/// (rad): the robot's turn changes little from scan to scan, and a wider fan lets a scene's
/// symmetry (a corridors' crossing turned by a quarter turn) win.
const HEADINGS: i32 = 8;
const HEADING_STEP: f32 = 0.087_266_46;
/// Its translations, mm: forward from `-STEP` to `FORWARD·STEP`, sideways `±SIDE·STEP`.
const GRID_STEP: f32 = 500.0;
const FORWARD: i32 = 4;
const SIDE: i32 = 2;
/// How far the ICP may move a start, mm and rad (a grid cell and a half; three headings).
const RECHECK_REACH: (f32, f32) = (750.0, 0.26);
/// Grid motions (best screened first) refined by ICP.
const REFINED: usize = 8;

/// The step `rel` (the current scan's pose in the previous scan's frame) looked at again when
/// the two scans' points agree less than [`RECHECK_BELOW`] under it: [`icp()`] from `last` (the
/// last motion) and from the best 8 (`REFINED`) motions of a grid (headings 5° apart up to ±40°
/// from the last motion's,
/// translations 0.5 m apart from 0.5 m back to 2 m forward and 1 m either side) under which
/// the points agree best; the best answer (the last motion's unless another agrees clearly
/// better) when its points agree at least 0.5 and 0.25 better than under `rel`; `None`
/// otherwise (keep `rel`).
pub fn recheck<const N: usize>(
    prev: &RangeScan<N>,
    curr: &RangeScan<N>,
    rel: &Pose,
    last: &Pose,
) -> Option<IcpResult> {
    if prev.is_empty() || curr.is_empty() {
        return None;
    }
    let own = if rel.is_finite() {
        agreement(prev, curr, rel).score()
    } else {
        f32::NEG_INFINITY
    };
    if own >= RECHECK_BELOW {
        return None;
    }
    // The grid's best motions, best first.
    let mut top = [(f32::NEG_INFINITY, Pose::IDENTITY); REFINED];
    for xi in -1..=FORWARD {
        for yi in -SIDE..=SIDE {
            for ti in -HEADINGS..=HEADINGS {
                let g = Pose::new(
                    xi as f32 * GRID_STEP,
                    yi as f32 * GRID_STEP,
                    crate::geom::wrap(last.theta + ti as f32 * HEADING_STEP),
                );
                let s = agreement(prev, curr, &g).score();
                ranked(&mut top, s, g);
            }
        }
    }
    let starts =
        core::iter::once(*last).chain(top.iter().filter(|(s, _)| s.is_finite()).map(|(_, g)| *g));
    refined(prev, curr, starts, |_| true)
        .filter(|(r, s)| *s >= RECHECK_ACCEPT && *s > own + RECHECK_MARGIN && r.pose.is_finite())
        .map(|(r, _)| r)
}

/// A bridge is taken when its points agree at least this well...
const BRIDGE_ACCEPT: f32 = 0.3;
/// ...and this much better than under the last motion's bridge.
const BRIDGE_MARGIN: f32 = 0.1;
/// The bridge's fan: the whole circle in this many headings (10° apart).
const FAN: i32 = 36;
/// The fan's motions (best first) refined by ICP.
const FAN_REFINED: usize = 4;
/// Smallest standard deviation of a bridge, mm and rad.
const BRIDGE_SIGMA: (f32, f32) = (100.0, 0.05);

/// A bridge over a step nothing registered (the features, the pair's ICP and [`recheck`]
/// failed): `rel` (the last motion again) is compared with no motion and the whole circle of
/// headings 10° apart (at no motion's and at the last motion's translation), the best 4 of
/// those and both `rel` and no motion refined by [`icp()`]; the answer whose points agree best
/// (one of `rel` and no motion unless another agrees 0.02 better) replaces `rel` when its
/// points agree at least 0.3 and 0.1 better than under `rel`. Its covariance says how unsure
/// the bridge is: the ICP's widened by the distance to `rel`, the other guess, at least
/// 0.1 m and 0.05 rad (σ). `None`: keep `rel`.
pub fn bridge<const N: usize>(
    prev: &RangeScan<N>,
    curr: &RangeScan<N>,
    rel: &Pose,
) -> Option<(Pose, crate::geom::Cov3)> {
    if prev.is_empty() || curr.is_empty() || !rel.is_finite() {
        return None;
    }
    let own = agreement(prev, curr, rel).score();
    let mut top = [(f32::NEG_INFINITY, Pose::IDENTITY); FAN_REFINED];
    for arc in [false, true] {
        for k in 0..FAN {
            let theta = crate::geom::wrap(k as f32 * (core::f32::consts::TAU / FAN as f32));
            // No translation, or the last motion's turned by half the change of heading
            // (the chord of an arc).
            let g = if arc {
                let (s, c) = crate::geom::sin_cos(0.5 * crate::geom::wrap(theta - rel.theta));
                Pose::new(c * rel.x - s * rel.y, s * rel.x + c * rel.y, theta)
            } else {
                Pose::new(0.0, 0.0, theta)
            };
            let s = agreement(prev, curr, &g).score();
            ranked(&mut top, s, g);
        }
    }
    let starts = [*rel, Pose::IDENTITY]
        .into_iter()
        .chain(top.iter().filter(|(s, _)| s.is_finite()).map(|(_, g)| *g));
    let (IcpResult { pose, mut cov, .. }, s) = refined(prev, curr, starts, Pose::is_finite)?;
    if !(s >= BRIDGE_ACCEPT && s > own + BRIDGE_MARGIN) {
        return None;
    }
    let d = crate::geom::hypot(pose.x - rel.x, pose.y - rel.y).max(BRIDGE_SIGMA.0);
    let t = crate::geom::wrap(pose.theta - rel.theta)
        .abs()
        .max(BRIDGE_SIGMA.1);
    for (i, v) in [d * d, d * d, t * t].into_iter().enumerate() {
        if let Some(c) = cov.get_mut(i).and_then(|row| row.get_mut(i)) {
            *c = (*c).min(crate::register::UNOBSERVABLE_VARIANCE) + v;
        }
    }
    Some((pose, cov))
}

/// The second look's fan: the whole circle in this many headings (5° apart).
const LOOK_FAN: i32 = 72;
/// The second look's screened motions (best first) refined by ICP.
const LOOK_REFINED: usize = 8;

/// A pair's answer `rel` (or none) whose points agree less than
/// [`crate::Config::verify_accept`] looked at again over the whole circle: the points'
/// agreement screened at headings 5° apart, at no translation, at `guess`'s (the last motion,
/// say) and at its translation turned by half the change of heading (an arc's chord); `guess`
/// and the best 8 refined by [`icp()`] (each within a grid cell and a half and three headings of
/// its start). The best answer (`guess`'s unless another agrees 0.02 better) when its points
/// agree at least [`crate::Config::verify_accept`] and 0.25 better than under `rel`; `None`
/// otherwise.
pub(super) fn second_look<const N: usize>(
    prev: &RangeScan<N>,
    curr: &RangeScan<N>,
    rel: Option<&Pose>,
    guess: Option<Pose>,
    cfg: &crate::Config,
) -> Option<IcpResult> {
    if prev.is_empty() || curr.is_empty() {
        return None;
    }
    let own = rel
        .filter(|r| r.is_finite())
        .map_or(f32::NEG_INFINITY, |r| agreement(prev, curr, r).score());
    let guess = guess.filter(Pose::is_finite);
    let t = guess.unwrap_or(Pose::IDENTITY);
    let mut top = [(f32::NEG_INFINITY, Pose::IDENTITY); LOOK_REFINED];
    for k in 0..LOOK_FAN {
        let theta = crate::geom::wrap(k as f32 * (core::f32::consts::TAU / LOOK_FAN as f32));
        if !(theta.abs() <= cfg.max_rotation) {
            continue;
        }
        let (s, c) = crate::geom::sin_cos(0.5 * crate::geom::wrap(theta - t.theta));
        let arc = Pose::new(c * t.x - s * t.y, s * t.x + c * t.y, theta);
        for g in [Pose::new(0.0, 0.0, theta), Pose::new(t.x, t.y, theta), arc] {
            let s = agreement(prev, curr, &g).score();
            ranked(&mut top, s, g);
        }
    }
    let starts = guess
        .into_iter()
        .chain(top.iter().filter(|(s, _)| s.is_finite()).map(|(_, g)| *g));
    let inside = |p: &Pose| {
        crate::geom::hypot(p.x, p.y) <= cfg.max_translation
            && crate::geom::wrap(p.theta).abs() <= cfg.max_rotation
    };
    refined(prev, curr, starts, inside)
        .filter(|(_, s)| *s >= cfg.verify_accept && *s > own + RECHECK_MARGIN)
        .map(|(r, _)| r)
}

/// Puts the motion `g` whose points agree `s` into `top` (best first) when it beats the last.
fn ranked(top: &mut [(f32, Pose)], s: f32, g: Pose) {
    if let Some(k) = top.iter().position(|(b, _)| s > *b) {
        top.copy_within(k..top.len() - 1, k + 1);
        if let Some(slot) = top.get_mut(k) {
            *slot = (s, g);
        }
    }
}

/// [`icp()`] from each of `starts` and the best answer with its points' agreement: the first
/// start's unless a later one agrees [`RECHECK_PREFER`] better. An answer farther than
/// [`RECHECK_REACH`] from its start left the start's basin (typically a scene's symmetry: a
/// corridor turned by half a turn) and is dropped, as is one whose pose `keep` refuses.
fn refined<const N: usize>(
    prev: &RangeScan<N>,
    curr: &RangeScan<N>,
    starts: impl Iterator<Item = Pose>,
    keep: impl Fn(&Pose) -> bool,
) -> Option<(IcpResult, f32)> {
    let mut best: Option<(IcpResult, f32)> = None;
    for start in starts {
        let Some(r) = icp(prev, curr, &start) else {
            continue;
        };
        let moved = crate::geom::hypot(r.pose.x - start.x, r.pose.y - start.y);
        let turned = crate::geom::wrap(r.pose.theta - start.theta).abs();
        if moved > RECHECK_REACH.0 || turned > RECHECK_REACH.1 || !keep(&r.pose) {
            continue;
        }
        let s = r.agreement.score();
        if best.as_ref().is_none_or(|(_, b)| s > *b + RECHECK_PREFER) {
            best = Some((r, s));
        }
    }
    best
}
