//! The visibility check of a refined pose: what each scan saw must not be hidden by the other
//! scan's segments, and the robot does not go through walls.

use crate::geom::Pose;
use crate::set::{Line, Set};

/// How much the segments of each scan, seen from the other scan's position under `pose`, would
/// hide segments that scan did see: the number of hidden samples over 5 per segment, summed
/// over both directions. A right pose hides nothing (static, opaque scene); a wrong one puts
/// walls in front of what was seen.
pub(super) fn visibility_penalty(prev: &Set, curr: &Set, pose: &Pose) -> f32 {
    let inv = pose.inverse();
    let (fwd, back) = (pose.transformer(), inv.transformer());
    let a = hidden(
        curr.lines()
            .iter()
            .filter_map(|l| l.ext)
            .map(|(s, e)| (fwd(s), fwd(e))),
        prev.lines(),
    );
    let b = hidden(
        prev.lines()
            .iter()
            .filter_map(|l| l.ext)
            .map(|(s, e)| (back(s), back(e))),
        curr.lines(),
    );
    a + b + 2.0 * crossings(prev, curr, pose)
}

/// How many segments of either scan the straight path between the two scan positions goes
/// through (in the middle 90 % of the segment): a robot does not pass through walls.
fn crossings(prev: &Set, curr: &Set, pose: &Pose) -> f32 {
    let to = [pose.x, pose.y];
    let fwd = pose.transformer();
    let through = |(s, e): ([f32; 2], [f32; 2])| -> bool {
        // Path 0 + u·to, u in (0, 1); segment s + μ (e − s), μ in [0.05, 0.95].
        let w = [e[0] - s[0], e[1] - s[1]];
        let den = to[0] * w[1] - to[1] * w[0];
        if !(den.abs() > 1e-3) {
            return false;
        }
        let u = (s[0] * w[1] - s[1] * w[0]) / den;
        let mu = (s[0] * to[1] - s[1] * to[0]) / den;
        u > 0.0 && u < 1.0 && (0.05..=0.95).contains(&mu)
    };
    let a = prev
        .lines()
        .iter()
        .filter_map(|l| l.ext)
        .filter(|&x| through(x))
        .count();
    let b = curr
        .lines()
        .iter()
        .filter_map(|l| l.ext)
        .map(|(s, e)| (fwd(s), fwd(e)))
        .filter(|&x| through(x))
        .count();
    (a + b) as f32
}

/// Samples of the segments `front` (in a scan's frame) that lie clearly in front of one of the
/// segments `seen` by that scan, over 5 per segment.
fn hidden(front: impl Iterator<Item = ([f32; 2], [f32; 2])>, seen: &[Line]) -> f32 {
    const SAMPLES: usize = 5;
    const END: f32 = 150.0;
    const DEPTH: f32 = 250.0;
    let mut total = 0.0;
    for (s, e) in front {
        let d = [e[0] - s[0], e[1] - s[1]];
        let len = crate::geom::sqrt(d[0] * d[0] + d[1] * d[1]);
        if !(len > 2.0 * END + 100.0) {
            continue;
        }
        let mut count = 0usize;
        for k in 0..SAMPLES {
            let u = (END + (len - 2.0 * END) * k as f32 / (SAMPLES - 1) as f32) / len;
            let q = [s[0] + d[0] * u, s[1] + d[1] * u];
            let rq = crate::geom::sqrt(q[0] * q[0] + q[1] * q[1]);
            if !(rq > 1.0) {
                continue;
            }
            let dir = [q[0] / rq, q[1] / rq];
            let behind = seen.iter().filter_map(|l| l.ext).any(|(ps, pe)| {
                // Ray origin + λ dir meets ps + μ (pe − ps).
                let w = [pe[0] - ps[0], pe[1] - ps[1]];
                let den = dir[0] * w[1] - dir[1] * w[0];
                if !(den * den > 1e-12 * (w[0] * w[0] + w[1] * w[1])) {
                    return false;
                }
                let lambda = (ps[0] * w[1] - ps[1] * w[0]) / den;
                let mu = (ps[0] * dir[1] - ps[1] * dir[0]) / den;
                (0.05..=0.95).contains(&mu) && lambda > rq + DEPTH
            });
            if behind {
                count += 1;
            }
        }
        total += count as f32 / SAMPLES as f32;
    }
    total
}
