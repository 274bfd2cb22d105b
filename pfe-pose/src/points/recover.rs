//! The odometry's second look at a step whose points contradict it: the points' agreement
//! screened over a grid of motions (headings 5° apart up to ±40° from the last motion's,
//! translations 0.5 m apart),
//! the best few refined by ICP, so that a wrong answer of the features (a 90° turn where the
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
/// the two scans' points agree less than [`RECHECK_BELOW`] under it: [`icp`] from `last` (the
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
                if let Some(k) = top.iter().position(|(b, _)| s > *b) {
                    top.copy_within(k..REFINED - 1, k + 1);
                    if let Some(slot) = top.get_mut(k) {
                        *slot = (s, g);
                    }
                }
            }
        }
    }
    let starts =
        core::iter::once(*last).chain(top.iter().filter(|(s, _)| s.is_finite()).map(|(_, g)| *g));
    let mut best: Option<(IcpResult, f32)> = None;
    for start in starts {
        let Some(r) = icp(prev, curr, &start) else {
            continue;
        };
        // An answer far from its start left the start's basin: a wrong one, typically a
        // scene's symmetry (a corridor turned by half a turn).
        let moved = crate::geom::hypot(r.pose.x - start.x, r.pose.y - start.y);
        let turned = crate::geom::wrap(r.pose.theta - start.theta).abs();
        if moved > RECHECK_REACH.0 || turned > RECHECK_REACH.1 {
            continue;
        }
        let s = r.agreement.score();
        if best.as_ref().is_none_or(|(_, b)| s > *b + RECHECK_PREFER) {
            best = Some((r, s));
        }
    }
    best.filter(|(r, s)| *s >= RECHECK_ACCEPT && *s > own + RECHECK_MARGIN && r.pose.is_finite())
        .map(|(r, _)| r)
}
