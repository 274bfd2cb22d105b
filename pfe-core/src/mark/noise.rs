//! The default mode's marking: a walk over the points that predicts each from points of its
//! own segment only (so no window straddles a boundary), with the threshold `k σ_D + floor`,
//! a jump limit, arc continuation, boundary localisation and refinement, and the merge of a
//! new segment that continues the arc before it.

use heapless::Vec;

use super::arc::continues_arc;
use super::refine::{locate, refine_boundary, REFINE_AFTER};
use super::Neighbours;
use crate::arc::arc_fit;
use crate::beams::MIN_INCIDENCE;
use crate::flags::{JUMP, START};
use crate::geometry::Point;
use crate::math;
use crate::pass::{point_at, Pass};
use crate::predict::WindowLine;
use crate::rule::NoiseRule;

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

/// The walk's points and their ranges, of one length, whether they are unevenly spaced in
/// bearing (see [`super::mark`]), and whether a step within every jump limit is taken for no
/// jump before its limit is computed ([`never_jumps2`]; not on the slow path alone, which
/// the tests hold the others to).
#[derive(Clone, Copy)]
struct Cloud<'a> {
    points: &'a [Point],
    ranges: &'a [f32],
    uneven: bool,
    near_first: bool,
}

/// Marks the points of `pass` in the default mode (`uneven`: see [`super::mark`]); returns the
/// neighbouring starts it noted.
pub(crate) fn mark(pass: &mut Pass<'_>, rule: &NoiseRule, uneven: bool) -> Neighbours {
    // The fast path: no de-skewing (the scanner at the origin) and a floor small enough for
    // its test (`WindowLine::accepts_within`); otherwise every point takes the slow path, with
    // the same outcome.
    let floor = rule.model.floor;
    let fast = pass.motion.is_none()
        && !uneven
        && floor * floor <= WindowLine::FLOOR2_WITHIN * rule.k_sigma2;
    if fast {
        walk::<true>(pass, rule, uneven, TIGHT)
    } else {
        walk::<false>(pass, rule, uneven, TIGHT)
    }
}

/// How the walk without its fast path tests the stale line's run over unevenly spaced points
/// seen from the origin: each point on its own (`Off`), or in a tight loop, one point at a
/// time (`Serial`, [`accepted_run_after_serial`]) or [`LANES`] at once (`Lanes`,
/// [`accepted_run_after_lanes`]): the same marks and counts.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Tight {
    Off,
    Serial,
    Lanes,
}

/// [`Tight::Lanes`] on the host (`std`: a vector unit), [`Tight::Serial`] on the board.
const TIGHT: Tight = match cfg!(feature = "std") {
    true => Tight::Lanes,
    false => Tight::Serial,
};

/// The walk over every point, with the fast path (`FAST`: the scanner at the origin, points
/// evenly spaced: the uneven cases' tests compile out) or without, then testing unevenly
/// spaced points seen from the origin as `tight` says.
fn walk<const FAST: bool>(
    pass: &mut Pass<'_>,
    rule: &NoiseRule,
    uneven: bool,
    tight: Tight,
) -> Neighbours {
    let mut noted = Some(Vec::new());
    // Points and ranges cut to the number of readings once: one bounds check for both.
    let n = pass.len();
    let (Some(points), Some(ranges)) = (pass.points.get(..n), pass.ranges.get(..n)) else {
        return noted;
    };
    let cloud = Cloud {
        points,
        ranges,
        uneven,
        near_first: tight != Tight::Off,
    };
    // Unevenly spaced points without de-skewing: the stale line's run has a tight loop too.
    let steady = tight != Tight::Off && uneven && pass.motion.is_none();
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
        } else if let (Some((line, until)), true) = (cached, !FAST && steady) {
            // The same for unevenly spaced points seen from the origin: the slow path's tests
            // in a tight loop. The point it stops at is tested again by `step` (and counted
            // there), as the slow path alone would.
            let stop = walk.next_check(k, until + 1).min(n);
            // (The board's build leaves the lanes out.)
            let next = match tight {
                Tight::Lanes if cfg!(any(feature = "std", test)) => {
                    accepted_run_after_lanes(points, ranges, k, stop, line, rule)
                }
                _ => accepted_run_after_serial(points, ranges, k, stop, line, rule),
            };
            pass.stats.predictions += next - k;
            k = next;
            if k >= n {
                break;
            }
        }
        step::<FAST>(pass, cloud, k, (&mut walk, &mut noted), stale_failed, rule);
        k += 1;
    }
    noted
}

/// Sets a segment start at `i` in increasing order, noting it in `noted` when point `i − 1`
/// starts one too (see [`Neighbours`]).
fn start(pass: &mut Pass<'_>, noted: &mut Neighbours, i: usize) {
    pass.set(i, START);
    if i.checked_sub(1).is_some_and(|j| pass.flag(j) & START != 0) {
        let kept = match (&mut *noted, u16::try_from(i)) {
            (Some(list), Ok(i)) => list.push(i).is_ok(),
            _ => false,
        };
        if !kept {
            *noted = None;
        }
    }
}

/// The walk at point `k`, with everything the fast path does not do: segment starts, jumps,
/// fresh windows, arc continuation, boundary placement, refinement and merges.
/// `stale_failed`: the fast path just saw the cached line reject `k`.
fn step<const FAST: bool>(
    pass: &mut Pass<'_>,
    cloud: Cloud<'_>,
    k: usize,
    (walk, noted): (&mut Walk, &mut Neighbours),
    stale_failed: bool,
    rule: &NoiseRule,
) {
    let Cloud {
        points,
        ranges,
        uneven,
        near_first,
    } = cloud;
    if !pass.valid(k) {
        *walk = Walk::default();
        return;
    }
    let Some(s) = walk.seg else {
        start(pass, noted, k);
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
    let (ex, ey) = (p.x - prev.x, p.y - prev.y);
    let d2 = ex * ex + ey * ey;
    let jump = if !FAST && uneven {
        // No limit between points of their own angle apart is needed for a step within every
        // limit (`prev` is valid: its range is too).
        let o = pass.origin(k);
        let seen = |q: Point| Point::new(q.x - o.x, q.y - o.y);
        let near = near_first && d2 <= never_jumps2(rule);
        !near && d2 > sq(rule.jump_limit_between(seen(prev), seen(p), prev_r))
    } else {
        d2 > sq(rule.jump_limit(prev_r))
    };
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
            if !FAST && uneven && !spans(&first, &last, rule) {
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
        start(pass, noted, b);
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
            let best = refine_boundary(points, old, b, k + 1, rule.sigma_r);
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

/// The square of a step no jump limit is below (`NoiseRule::jump_add`, which each adds to a
/// share of the gap that is not negative for a predecessor at a finite range that is not
/// negative: a valid point's); below 0, none, when `jump_add` is negative.
#[inline(always)]
fn never_jumps2(rule: &NoiseRule) -> f32 {
    match rule.jump_add >= 0.0 {
        true => sq(rule.jump_add),
        false => -1.0,
    }
}

/// `x²`.
#[inline(always)]
fn sq(x: f32) -> f32 {
    x * x
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
    if FAST || (pass.motion.is_none() && !cloud.uneven) {
        return line.accepts(p.x, p.y, r, k_sigma2, floor);
    }
    let o = pass.origin(k);
    let seen = line.seen_from(o);
    let (x, y) = (p.x - o.x, p.y - o.y);
    if cloud.uneven {
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
    // The candidates' far ends `k − limit + 1 ..= k − w`, nearest first, without a bounds test
    // a point (the loop below reads a point past the scan's end as invalid).
    let far = match w < limit {
        true => k
            .checked_sub(limit - 1)
            .and_then(|a| points.get(a..=k.checked_sub(w)?)),
        false => None,
    };
    if let Some(far) = far {
        let span2 = span * span;
        for p in far.iter().rev() {
            let (dx, dy) = (p.x - last.x, p.y - last.y);
            if dx * dx + dy * dy >= span2 {
                return w;
            }
            w += 1;
        }
        return w;
    }
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

/// The points and ranges of `from..to` and the point and range before `from`, the run the
/// tight loops below walk (`None` when they are not all there).
#[inline(always)]
fn run_from<'a>(
    points: &'a [Point],
    ranges: &'a [f32],
    from: usize,
    to: usize,
) -> Option<(&'a [Point], &'a [f32], Point, f32)> {
    let before = from.checked_sub(1)?;
    Some((
        points.get(from..to)?,
        ranges.get(from..to)?,
        *points.get(before)?,
        *ranges.get(before)?,
    ))
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
    let Some((pts, rs, mut prev, mut prev_r)) = run_from(points, ranges, from, to) else {
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

/// Points [`accepted_run_after_lanes`] tests at once.
const LANES: usize = 8;

/// [`accepted_run_after_serial`] testing [`LANES`] points at once, branch-free (the loop
/// vectorises, square roots and divisions included), then taking the first that fails: the
/// same tests of the same points (a point's test reads only it and its predecessor), so the
/// same answer; past it, the tests are wasted (at most `LANES − 1`). For a vector unit (the
/// host).
#[cfg_attr(not(any(feature = "std", test)), allow(dead_code))]
fn accepted_run_after_lanes(
    points: &[Point],
    ranges: &[f32],
    from: usize,
    to: usize,
    line: &WindowLine,
    rule: &NoiseRule,
) -> usize {
    if run_from(points, ranges, from, to).is_none() {
        return from;
    }
    let (k_sigma2, floor) = (rule.k_sigma2, rule.model.floor);
    let incidence = math::sin_cos(MIN_INCIDENCE);
    let mut at = from;
    while at < to {
        let end = (at + LANES).min(to);
        // From the predecessor of `at` (in the scan: `run_from` found `from − 1 ..= to − 1`).
        let (Some(pts), Some(rs)) = (points.get(at - 1..end), ranges.get(at - 1..end)) else {
            return at;
        };
        let mut fit = [true; LANES];
        let pairs = pts.windows(2).zip(rs.windows(2));
        for (ok, (pw, rw)) in fit.iter_mut().zip(pairs) {
            let (&[prev, p], &[prev_r, r]) = (pw, rw) else {
                continue;
            };
            // As `accepted_run_after_serial`, with `&` for `||` (no branch).
            let limit = jump_limit_between_lanes(rule, incidence, prev, p, prev_r);
            let (ex, ey) = (p.x - prev.x, p.y - prev.y);
            *ok = (ex * ex + ey * ey <= limit * limit)
                & line.accepts_after_lanes(&prev, (p.x, p.y), r, k_sigma2, floor);
        }
        // The lanes that failed as the bits of a mask (those past `end` are left `true`): its
        // lowest bit is the first point that fails.
        let failed = fit
            .iter()
            .enumerate()
            .fold(0u32, |m, (j, &ok)| m | u32::from(!ok) << j);
        if failed != 0 {
            return at + failed.trailing_zeros() as usize;
        }
        at = end;
    }
    to
}

/// [`NoiseRule::jump_limit_between`] without a branch, its square root [`math::sqrt_lanes`]
/// and the sine and cosine of [`MIN_INCIDENCE`] given (`incidence`): the same arithmetic, for
/// loops meant to vectorise.
#[inline(always)]
fn jump_limit_between_lanes(
    rule: &NoiseRule,
    (sin_l, cos_l): (f32, f32),
    a: Point,
    b: Point,
    prev_r: f32,
) -> f32 {
    let cross = math::abs(a.x * b.y - a.y * b.x);
    let dot = a.x * b.x + a.y * b.y;
    let norm = math::sqrt_lanes((a.x * a.x + a.y * a.y) * (b.x * b.x + b.y * b.y));
    let below = sin_l * dot - cos_l * cross;
    let floor = 1e-3 * norm;
    let gap = cross / if below > floor { below } else { floor };
    if math::finite(gap) {
        prev_r * gap + rule.jump_add
    } else {
        rule.jump_limit(prev_r)
    }
}

/// [`accepted_run`] for unevenly spaced points (no de-skewing): the first point from `from`
/// (up to `to`, exclusive) that the slow path's [`step`] would not accept with `line` as its
/// stale line: not valid, a jump from its predecessor at their own angle apart
/// ([`crate::rule::NoiseRule::jump_limit_between`]), or not accepted with the lever of its own
/// step ([`WindowLine::accepts_after`]); the same arithmetic as [`step`] and [`line_accepts`]
/// with the scanner at the origin.
fn accepted_run_after_serial(
    points: &[Point],
    ranges: &[f32],
    from: usize,
    to: usize,
    line: &WindowLine,
    rule: &NoiseRule,
) -> usize {
    let Some((pts, rs, mut prev, mut prev_r)) = run_from(points, ranges, from, to) else {
        return from;
    };
    let (k_sigma2, floor) = (rule.k_sigma2, rule.model.floor);
    let near2 = never_jumps2(rule);
    for (at, (p, &r)) in (from..).zip(pts.iter().zip(rs)) {
        // An invalid point is NaN (`Point::INVALID`): it fails the jump test.
        // A step within every limit needs none at the points' own angle apart (`prev_r` is
        // a valid point's range).
        let (ex, ey) = (p.x - prev.x, p.y - prev.y);
        let d2 = ex * ex + ey * ey;
        let near = d2 <= near2 || d2 <= sq(rule.jump_limit_between(prev, *p, prev_r));
        if !near || !line.accepts_after(&prev, (p.x, p.y), r, k_sigma2, floor) {
            return at;
        }
        (prev, prev_r) = (*p, r);
    }
    to
}

#[cfg(test)]
mod tests;
