//! Splits a segment typed a line that is more than one thing: a pillar against a wall
//! ([`bump`]) and a corner the walk left unmarked ([`corner`]).

use crate::arc::arc_fit;
use crate::config::{Config, Typing};
use crate::fit::circle::Circle;
use crate::fit::line::{fit_line, LineFit};
use crate::fit::run::corner_split;
use crate::geometry::Point;
use crate::math;
use crate::rule::NoiseRule;

use super::MERGE_SIZES;

/// Where the line segment `pts` is two lines: the points of the first, when its residual sum
/// exceeds the noise's and the best split near its apex (both pieces of at least `min_points`)
/// lowers it by more than the typing's `chi2 · σ_r²` and below `ratio` times the line's (the
/// test a circle must pass against the line). `line` is the fit of `pts`.
pub(super) fn corner(pts: &[Point], line: &LineFit, config: &Config) -> Option<usize> {
    let Typing::CompareFits { chi2, ratio, .. } = config.typing else {
        return None;
    };
    let sse_l = line.sse();
    let var = config.sigma_r * config.sigma_r;
    // A line within the noise (at most σ_r² a degree of freedom) is not split.
    if !(sse_l > var * (pts.len() as f32 - 2.0) && sse_l > chi2 * var) {
        return None;
    }
    let (k, sse_2) = corner_split(pts)?;
    let long = k >= config.min_points && pts.len() - k >= config.min_points;
    (long && sse_l - sse_2 > chi2 * var && sse_2 < ratio * sse_l).then_some(k)
}

/// Residual (in σ_r) a point must exceed to start the bump an arc makes on a line's fit.
const BUMP_SIGMAS: f32 = 2.0;
/// Times the line under a bump is fitted again without it.
const BUMP_ROUNDS: usize = 3;
/// Residual (in σ_r) to the bump's circle within which neighbouring points join the arc.
const BUMP_GROW_SIGMAS: f32 = 3.0;
/// Points at a segment's end tried for an arc there, shortest first.
const END_RUNS: [usize; 2] = [16, 32];
/// Most times the arc is grown and its circle fitted again.
const BUMP_GROW_ROUNDS: usize = 8;

/// An arc inside the segment `pts` typed a line whose fit is far beyond the noise (a pillar
/// against a wall, its edges meeting the wall without a range jump, that the walk followed
/// and no single corner explains): its first and last index in `pts`, a strict part of them.
/// The arc is the run of same-side residuals around the largest one ([`peak`]) or a side of
/// the best two-line split, grown while the next point lies on its circle, and must face the
/// scanner ([`facing`]). `line` is the fit of `pts`.
pub(super) fn bump(
    pts: &[Point],
    line: &LineFit,
    rule: &NoiseRule,
    config: &Config,
) -> Option<(usize, usize)> {
    let n = pts.len();
    // The arc of at least `MERGE_SIZES.start()` points and some line beside it.
    if n <= *MERGE_SIZES.start() {
        return None;
    }
    let var = config.sigma_r * config.sigma_r;
    if !(line.sse() > var * (n as f32 - 2.0) && line.sse() > rule.model.arc_chi2 * var) {
        return None;
    }
    let arc_of = |(i, j): (usize, usize)| arc_fit(pts.get(i..=j)?, rule).map(|c| (i, j, c));
    let peak = peak(pts, *line, config)?;
    let at_end = peak.0 == 0 || peak.1 + 1 == n;
    let (mut i, mut j, mut circle) = arc_of(peak)
        .or_else(|| {
            // An arc at an end of the segment that the peak misses is one side of its best
            // two-line split,
            if !at_end {
                return None;
            }
            let (k, _) = corner_split(pts)?;
            arc_of((0, k.checked_sub(1)?)).or_else(|| arc_of((k, n - 1)))
        })
        .or_else(|| {
            // or, when the split is in the arc, the last points at that end.
            END_RUNS
                .iter()
                .filter(|&&m| at_end && m < n)
                .find_map(|&m| {
                    if peak.1 + 1 == n {
                        arc_of((n - m, n - 1))
                    } else {
                        arc_of((0, m - 1))
                    }
                })
        })?;
    // Grown while the next point lies on the circle, the circle fitted again to what it grew
    // to: a circle fitted to part of an arc strays from the rest. `grown` is the arc test of
    // `i..=j` (`circle` until one fails: the same points give the same circle, so neither an
    // ungrown run nor the final one is tested again).
    let mut grown = Some(circle);
    for _ in 0..BUMP_GROW_ROUNDS {
        let on = |k: usize| {
            pts.get(k).is_some_and(|p| {
                math::abs(p.distance(&circle.center) - circle.radius)
                    <= BUMP_GROW_SIGMAS * config.sigma_r
            })
        };
        let (i0, j0) = (i, j);
        while i > 0 && on(i - 1) {
            i -= 1;
        }
        while j + 1 < n && on(j + 1) {
            j += 1;
        }
        if (i, j) == (i0, j0) {
            break;
        }
        grown = arc_of((i, j)).map(|(_, _, c)| c);
        match grown {
            Some(c) => circle = c,
            None => break,
        }
    }
    (j + 1 - i >= *MERGE_SIZES.start()
        && (i > 0 || j + 1 < n)
        && grown.is_some_and(|c| facing(pts.get(i..=j).unwrap_or(&[]), &c)))
    .then_some((i, j))
}

/// Whether the arc of `pts` on `circle` faces the scanner (its centre beyond the points, as a
/// pillar's): the inside of a rounded corner is no pillar.
fn facing(pts: &[Point], circle: &Circle) -> bool {
    pts.get(pts.len() / 2)
        .is_some_and(|m| math::hypot(circle.center.x, circle.center.y) > math::hypot(m.x, m.y))
}

/// The run of same-side residuals beyond [`BUMP_SIGMAS`] σ_r around the largest residual of
/// `pts` from `line`, the line fitted again without it from the far half of its longer side
/// (the wall a pillar stands against).
fn peak(pts: &[Point], mut line: LineFit, config: &Config) -> Option<(usize, usize)> {
    let n = pts.len();
    let (mut i, mut j) = (0usize, 0usize);
    for _ in 0..BUMP_ROUNDS {
        let d = |k: usize| pts.get(k).map_or(0.0, |p| line.signed_distance(p));
        let (mut m, mut dm) = (0usize, 0.0f32);
        for k in 0..n {
            if math::abs(d(k)) > math::abs(dm) {
                (m, dm) = (k, d(k));
            }
        }
        let far = |k: usize| d(k) * dm > 0.0 && math::abs(d(k)) > BUMP_SIGMAS * config.sigma_r;
        if !far(m) {
            return None;
        }
        (i, j) = (m, m);
        while i > 0 && far(i - 1) {
            i -= 1;
        }
        while j + 1 < n && far(j + 1) {
            j += 1;
        }
        // The far half of the longer side: clear of the rest of a pillar at an end.
        let rest = if i >= n - 1 - j {
            pts.get(..i / 2)
        } else {
            pts.get((j + 1 + n) / 2..)
        };
        match rest.filter(|r| r.len() >= config.min_points).map(fit_line) {
            Some(Ok(l)) => line = l,
            _ => break,
        }
    }
    Some((i, j))
}

#[cfg(test)]
#[path = "split_tests.rs"]
mod tests;
