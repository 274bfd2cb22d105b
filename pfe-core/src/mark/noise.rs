//! The default mode's marking: a walk over the points that predicts each from points of its
//! own segment only (so no window straddles a boundary), with the threshold `k σ_D + floor`,
//! a jump limit, arc continuation, boundary localisation and refinement, and the merge of a
//! new segment that continues the arc before it.

use heapless::Vec;

use super::refine::{locate, refine_boundary, REFINE_AFTER};
use super::NoiseRule;
use crate::classify::arc::{arc_fit, continues_arc};
use crate::flags::{JUMP, START};
use crate::geometry::Point;
use crate::pass::{point_at, Pass};
use crate::predict::WindowLine;

/// Size of a new segment at which it is tested for being the same arc as the one before.
const MERGE_AT: usize = 8;

/// The walk's state.
#[derive(Clone, Copy, Default)]
struct Walk {
    /// Start of the current segment.
    seg: Option<usize>,
    /// The last fresh window's line and the last point it may test.
    cache: Option<(WindowLine, usize)>,
    /// Boundary awaiting refinement: (its index, the start of the segment before it).
    pending: Option<(usize, usize)>,
    /// Last boundary that was not a jump and the start of the segment before it (a jump is
    /// never inside one surface, so never merged).
    joinable: Option<(usize, usize)>,
}

impl Walk {
    /// The first point from `k` (before `limit`) where a boundary is refined or a merge is
    /// tested.
    fn next_check(&self, k: usize, limit: usize) -> usize {
        let refine = self.pending.map(|(b, _)| b + REFINE_AFTER);
        let merge = self.joinable.map(|(b, _)| b + MERGE_AT - 1);
        [refine, merge]
            .into_iter()
            .flatten()
            .filter(|&at| at >= k)
            .fold(limit, usize::min)
    }
}

/// The walk's points and their ranges, of one length.
#[derive(Clone, Copy)]
struct Cloud<'a> {
    points: &'a [Point],
    ranges: &'a [f32],
}

/// Marks the points of `pass` in the default mode.
pub(crate) fn mark(pass: &mut Pass<'_>, rule: &NoiseRule) {
    // The fast path: no de-skewing (the scanner at the origin) and a floor small enough for
    // its test (`WindowLine::accepts_within`); otherwise every point takes the slow path, with
    // the same outcome.
    let floor = rule.model.floor;
    let fast = pass.motion.is_none()
        && !pass.uneven
        && floor * floor <= WindowLine::FLOOR2_WITHIN * rule.k_sigma2;
    if fast {
        walk::<true>(pass, rule);
    } else {
        walk::<false>(pass, rule);
    }
}

/// The walk over every point, with the fast path (`FAST`: the scanner at the origin, points
/// evenly spaced: the uneven cases' tests compile out) or without.
fn walk<const FAST: bool>(pass: &mut Pass<'_>, rule: &NoiseRule) {
    pass.neighbours = Some(Vec::new());
    // Points and ranges cut to the number of readings once: one bounds check for both.
    let n = pass.len();
    let (Some(points), Some(ranges)) = (pass.points.get(..n), pass.ranges.get(..n)) else {
        return;
    };
    let cloud = Cloud { points, ranges };
    let mut walk = Walk::default();
    let mut k = 0usize;
    while k < n {
        let mut stale_failed = false;
        // Fast path: the points the cached line accepts, up to the next point where a
        // boundary awaits refinement or a merge test is due.
        let cached = walk.cache.as_ref().filter(|_| walk.seg.is_some());
        if let (Some((line, until)), true) = (cached, FAST) {
            let stop = walk.next_check(k, until + 1).min(n);
            let next = accepted_run(points, ranges, k, stop, line, rule);
            pass.stats.predictions += next - k;
            stale_failed = next < stop;
            k = next;
            if k >= n {
                break;
            }
        }
        step::<FAST>(pass, cloud, k, &mut walk, stale_failed, rule);
        k += 1;
    }
}

/// The walk at point `k`, with everything the fast path does not do: segment starts, jumps,
/// fresh windows, arc continuation, boundary placement, refinement and merges.
/// `stale_failed`: the fast path just saw the cached line reject `k`.
fn step<const FAST: bool>(
    pass: &mut Pass<'_>,
    cloud: Cloud<'_>,
    k: usize,
    walk: &mut Walk,
    stale_failed: bool,
    rule: &NoiseRule,
) {
    let Cloud { points, ranges } = cloud;
    if !pass.valid(k) {
        *walk = Walk::default();
        return;
    }
    let Some(s) = walk.seg else {
        pass.start(k);
        walk.seg = Some(k);
        walk.cache = None;
        return;
    };
    let c = k - s;
    // Point `k` (in the scan: the walk's loop checked it) and its predecessor.
    let (Some(&p), Some(&prev), Some(&prev_r)) =
        (points.get(k), points.get(k - 1), ranges.get(k - 1))
    else {
        return;
    };
    let limit = if !FAST && pass.uneven {
        let o = pass.origin(k);
        let seen = |q: Point| Point::new(q.x - o.x, q.y - o.y);
        rule.jump_limit_between(seen(prev), seen(p), prev_r)
    } else {
        rule.jump_limit(prev_r)
    };
    let (ex, ey) = (p.x - prev.x, p.y - prev.y);
    let jump = ex * ex + ey * ey > limit * limit;
    let boundary = if jump {
        // A jump no surface explains (also where the window's line runs along the beam and
        // the prediction says nothing).
        Some(k)
    } else if c == 1 {
        None
    } else {
        // A recent window's line first (unless the fast path just saw it fail here).
        let stale = walk.cache.filter(|(_, until)| !stale_failed && k <= *until);
        let stale_ok = stale.is_some_and(|(line, _)| {
            // The fast path counts the points it tests; here, without it, each one.
            if !FAST {
                pass.stats.predictions += 1;
            }
            line_accepts::<FAST>(pass, cloud, &line, k, rule)
        });
        if stale_ok {
            None
        } else {
            let w = window(points, k, c, rule);
            let (first, last) = (point_at(points, k - w), prev);
            if !FAST && pass.uneven && !spans(&first, &last, rule) {
                // Points not evenly spaced (interleaved sweeps de-skewed or moved: close to
                // the scanner one sweep's point may even pass the other's) give a window that
                // does not yet span the noise no direction: no test until it does.
                None
            } else {
                // It may test the next 8w points while they fit it, no more loosely than a
                // fresh line (`WindowLine::accepts`); a point it rejects gets a fresh window.
                walk.cache = pass
                    .window_line(k - w, k, k)
                    .map(|l| (l.capped(&first, &last, w), k + 8 * w));
                let line = walk.cache.as_ref().map(|(l, _)| l);
                let over = !line.is_some_and(|l| line_accepts::<FAST>(pass, cloud, l, k, rule));
                (over && !continues_arc(pass, s, k, rule)).then(|| {
                    let pred = line.and_then(|l| pass.predict_with(l, k));
                    locate(pass, s, k, pred, rule)
                })
            }
        }
    };
    if let Some(b) = boundary {
        pass.start(b);
        if jump {
            pass.set(b, JUMP);
        }
        walk.seg = Some(b);
        walk.cache = None;
        walk.pending = (!jump).then_some((b, s));
        walk.joinable = (!jump).then_some((b, s));
    } else if let Some((b, old)) = walk.joinable.filter(|(b, _)| k + 1 - b == MERGE_AT) {
        // An arc's edge seen at grazing incidence curves away from a short line window: when
        // the two segments together are one arc, they are one segment.
        let m = &rule.model;
        let from = old.max(b.saturating_sub(m.arc_window));
        let joined = points.get(from..k + 1);
        if m.arc_window >= 5 && joined.and_then(|pts| arc_fit(pts, rule)).is_some() {
            pass.clear(b, START);
            *walk = Walk {
                seg: Some(old),
                ..Walk::default()
            };
        }
    }
    if let (None, Some((b, old))) = (boundary, walk.pending) {
        if k == b + REFINE_AFTER {
            let best = refine_boundary(points, old, b, k + 1);
            if best != b {
                pass.clear(b, START);
                pass.set(best, START);
                walk.seg = Some(best);
                // A line of the points from b on is still one of the segment's when it starts
                // earlier.
                if best > b {
                    walk.cache = None;
                }
                walk.joinable = Some((best, old));
            }
            walk.pending = None;
        }
    }
}

/// Whether `line` accepts point `k` ([`WindowLine::accepts`]: the lever of the beam after the
/// line's window for every beam it tests). When de-skewing, from beam `k`'s own pose: the same
/// test, so that odometry of a scanner standing still changes nothing.
#[inline(always)]
fn line_accepts<const FAST: bool>(
    pass: &Pass<'_>,
    cloud: Cloud<'_>,
    line: &WindowLine,
    k: usize,
    rule: &NoiseRule,
) -> bool {
    let p = point_at(cloud.points, k);
    let r = cloud.ranges.get(k).copied().unwrap_or(f32::NAN);
    let (k_sigma2, floor) = (rule.k_sigma2, rule.model.floor);
    if FAST || (pass.motion.is_none() && !pass.uneven) {
        return line.accepts(p.x, p.y, r, k_sigma2, floor);
    }
    let o = pass.origin(k);
    let seen = line.seen_from(o);
    let (x, y) = (p.x - o.x, p.y - o.y);
    if pass.uneven {
        let prev = point_at(cloud.points, k.wrapping_sub(1));
        let prev = Point::new(prev.x - o.x, prev.y - o.y);
        seen.accepts_after(&prev, (x, y), r, k_sigma2, floor)
    } else {
        seen.accepts(x, y, r, k_sigma2, floor)
    }
}

/// Prediction window for point `k` with `c` points of its segment before it: `window` points,
/// grown (up to `max_window`) until it spans `min_span · σ_r`, so that close to the scanner,
/// where beams are a few mm apart, the window still sees a line's direction above the noise.
fn window(points: &[Point], k: usize, c: usize, rule: &NoiseRule) -> usize {
    let m = &rule.model;
    let mut w = c.min(m.window);
    let limit = c.min(m.max_window.max(m.window));
    let span = m.min_span * rule.sigma_r;
    let last = point_at(points, k - 1);
    while w < limit {
        let p = point_at(points, k - w);
        let (dx, dy) = (p.x - last.x, p.y - last.y);
        if dx * dx + dy * dy >= span * span {
            break;
        }
        w += 1;
    }
    w
}

/// Whether the window from `first` to `last` spans `min_span · σ_r`.
fn spans(first: &Point, last: &Point, rule: &NoiseRule) -> bool {
    let span = rule.model.min_span * rule.sigma_r;
    let (dx, dy) = (last.x - first.x, last.y - first.y);
    dx * dx + dy * dy >= span * span
}

/// The first point from `from` (up to `to`, exclusive) that is not valid, jumps from its
/// predecessor, or is not accepted by `line`: the walk's test for most points, as a tight loop
/// (no de-skewing: the scanner is at the origin).
fn accepted_run(
    points: &[Point],
    ranges: &[f32],
    from: usize,
    to: usize,
    line: &WindowLine,
    rule: &NoiseRule,
) -> usize {
    let (Some(pts), Some(rs)) = (points.get(from..to), ranges.get(from..to)) else {
        return from;
    };
    let Some(before) = from.checked_sub(1) else {
        return from;
    };
    let (Some(mut prev), Some(mut prev_r)) =
        (points.get(before).copied(), ranges.get(before).copied())
    else {
        return from;
    };
    let (k_sigma2, floor) = (rule.k_sigma2, rule.model.floor);
    // Point `p` at range `r` after `prev` at `prev_r`: no jump, and on the line. An invalid
    // point is NaN (`Point::INVALID`): it fails the jump test.
    let fits = |prev: &Point, prev_r: f32, p: &Point, r: f32| {
        let limit = rule.jump_limit(prev_r);
        let (ex, ey) = (p.x - prev.x, p.y - prev.y);
        ex * ex + ey * ey <= limit * limit && line.accepts_within(p.x, p.y, r, k_sigma2, floor)
    };
    // Two points an iteration: the second one's predecessor is still in registers, and the
    // loop's counting is shared.
    let mut pairs = pts.chunks_exact(2).zip(rs.chunks_exact(2));
    let mut at = from;
    for (p2, r2) in pairs.by_ref() {
        if let ([a, b], &[ra, rb]) = (p2, r2) {
            if !fits(&prev, prev_r, a, ra) {
                return at;
            }
            if !fits(a, ra, b, rb) {
                return at + 1;
            }
            (prev, prev_r) = (*b, rb);
        }
        at += 2;
    }
    match (pts.get(at - from), rs.get(at - from)) {
        (Some(p), Some(&r)) if !fits(&prev, prev_r, p, r) => at,
        _ => to,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Config;
    use crate::mark::Rule;

    /// The window grows from `window` (10) points until its far end is `min_span · σ_r` (12 ·
    /// 5 = 60 mm) from the last point, up to `max_window` (24): points 3 mm apart, along y
    /// and along x, need 21 (20 steps of 3 mm); 10 mm apart, the first 10 already span 90 mm;
    /// 1 mm apart, the cap.
    #[test]
    fn the_window_grows_until_it_spans_min_span_sigmas() {
        let config = Config::default().with_sigma_r(5.0);
        let rule = Rule::new(&config, 8000.0, 1.0);
        let Some(noise) = rule.noise() else {
            panic!("the default rule")
        };
        for (step, want) in [(3.0f32, 21usize), (10.0, 10), (1.0, 24)] {
            for along_y in [true, false] {
                let pts: heapless::Vec<Point, 64> = (0..40)
                    .map(|i| {
                        let t = step * i as f32;
                        if along_y {
                            Point::new(400.0, -50.0 + t)
                        } else {
                            Point::new(300.0 + t, 80.0)
                        }
                    })
                    .collect();
                assert_eq!(
                    window(&pts, 35, 30, noise),
                    want,
                    "step {step}, along y {along_y}"
                );
            }
        }
        // Never more points than the segment has before k.
        let pts: heapless::Vec<Point, 64> = (0..40).map(|i| Point::new(400.0, i as f32)).collect();
        assert_eq!(window(&pts, 35, 12, noise), 12);
    }
}
