//! Whether a circle fitted to a segment is an arc really there (default mode, with the checks
//! for real scans): enough points and arc, a residual sum that a corner (two lines) does not
//! beat, or one within the split allowance that no beam next to the run sees through.

use crate::fit::circle::Circle;
use crate::fit::run::best_split_sse;
use crate::geometry::Point;
use crate::math;
use crate::pass::Pass;

/// Fewest points of a circle in the default mode.
const CIRCLE_MIN_POINTS: usize = 6;
/// Smallest arc a circle must cover in the default mode, as tan of its angle (30°): a short
/// bent piece is not an arc.
const CIRCLE_MIN_ARC_TAN: f32 = 0.577_350_3;

/// How much more residual sum than the best two-line split a circle may leave, in σ_r²: the
/// split has one line parameter more and picks its meeting point, so on an arc it leaves about
/// two noise variances less than the circle ([`allowance`]).
const SPLIT_ALLOWANCE: f32 = 2.0;

/// Fewest points of a circle that may use the split allowance. Below it one of the best
/// split's two lines holds at most three points, one residual degree of freedom: the split
/// then hardly tests the corner, and on real scans such few-beam bends (clutter, furniture
/// far away) are circles the next scan does not confirm.
const ALLOWANCE_MIN_POINTS: usize = 8;

/// Largest distance from the circle's centre, as a fraction of its radius, at which a beam next
/// to the run crosses the circle's face (incidence within 53°) for [`seen_through`] to count it.
const FACE: f32 = 0.8;
/// How far beyond the circle's far side (in σ_r) a neighbouring beam's return must lie to see
/// through it.
const THROUGH_SIGMA: f32 = 4.0;

/// Whether `circle` (residual sum `sse_c`) is an arc really there: enough points, an arc of
/// at least 30° between the first and the last point, and a residual sum below the best
/// two-line (corner) split's by `margin` (a corner, door frame or bend is two lines).
#[cfg(test)]
pub(super) fn is_arc(pts: &[Point], circle: &Circle, sse_c: f32, margin: f32) -> bool {
    lead_over_split(pts, circle, sse_c).is_some_and(|lead| lead > margin)
}

/// How `circle` (residual sum `sse_c`, noise variance `var`) passes as an arc: `Some(false)`
/// when it beats the best two-line split outright, `Some(true)` when only within the split
/// allowance ([`allowance`]), `None` when it is no arc ([`is_arc`]).
pub(super) fn arc_test(pts: &[Point], circle: &Circle, sse_c: f32, var: f32) -> Option<bool> {
    let lead = lead_over_split(pts, circle, sse_c)?;
    if lead > 0.0 {
        Some(false)
    } else {
        (lead > allowance(pts, circle, var)).then_some(true)
    }
}

/// The best two-line split's residual sum less the circle's, when the points are enough and
/// the arc wide enough for a circle (`None` otherwise).
fn lead_over_split(pts: &[Point], circle: &Circle, sse_c: f32) -> Option<f32> {
    let (dot, cross) = ends(pts, circle)?;
    // Beyond 90° (dot < 0) this holds whatever the cross product.
    let wide = math::abs(cross) >= CIRCLE_MIN_ARC_TAN * dot;
    if pts.len() < CIRCLE_MIN_POINTS || !wide {
        return None;
    }
    best_split_sse(pts).map(|split| split - sse_c)
}

/// The margin of [`is_arc`] for `circle` over `pts`, noise variance `var`: −[`SPLIT_ALLOWANCE`]
/// σ_r² for an arc of at most 120° between its ends over at least [`ALLOWANCE_MIN_POINTS`]
/// points, none otherwise. The split's extra parameters earn it about two variances on any
/// arc; but a right-angle corner seen over a few beams fits a circle of 130–170° (its legs the
/// circle's tangents) as well as two lines, so a wider arc must beat the split outright; and
/// over fewer points one of the split's lines has at most three, whose fit says little.
pub(super) fn allowance(pts: &[Point], circle: &Circle, var: f32) -> f32 {
    // At most 120°: cos ≥ −1/2, i.e. dot ≥ 0 or 3 dot² ≤ cross².
    match ends(pts, circle) {
        Some((dot, cross))
            if pts.len() >= ALLOWANCE_MIN_POINTS
                && (dot >= 0.0 || 3.0 * dot * dot <= cross * cross) =>
        {
            -SPLIT_ALLOWANCE * var
        }
        _ => 0.0,
    }
}

/// Dot and cross product of the first and the last point of `pts` about the circle's centre.
fn ends(pts: &[Point], circle: &Circle) -> Option<(f32, f32)> {
    let (a, b) = (pts.first()?, pts.last()?);
    let c = circle.center;
    let (ax, ay, bx, by) = (a.x - c.x, a.y - c.y, b.x - c.x, b.y - c.y);
    Some((ax * bx + ay * by, ax * by - ay * bx))
}

/// Whether a beam next to the segment `s..=e` sees through `circle`: it crosses the circle
/// well inside its outline (within [`FACE`] R of the centre, in front of the scanner) and
/// returns from more than [`THROUGH_SIGMA`] σ_r beyond the circle's far side (not merely
/// beyond its face, which the fit extrapolates past the run's end), or returns nothing and
/// neither does the beam past it (one missing return, a dark spot, says nothing). A pillar
/// hides what is behind it; a corner's circle (a rounded-off wedge of two walls) reaches past
/// the walls' ends, where the scanner sees the room behind. Not checked while de-skewing (the
/// beams then leave from other origins) nor at the scan's ends.
pub(super) fn seen_through(
    pass: &Pass<'_>,
    s: usize,
    e: usize,
    circle: &Circle,
    sigma: f32,
) -> bool {
    if pass.motion.is_some() {
        return false;
    }
    let (c, r) = (circle.center, circle.radius);
    let face = (FACE * r).min(r - 2.0 * sigma);
    // Range at which beam k leaves the circle, when it crosses the circle's face.
    let exit = |k: usize| {
        let d = pass.beams.dirs.get(k)?;
        let (along, perp) = (d.x * c.x + d.y * c.y, d.x * c.y - d.y * c.x);
        (along > 0.0 && math::abs(perp) < face).then(|| along + math::sqrt(r * r - perp * perp))
    };
    let beyond = |k: usize, exit: f32| pass.range(k) > exit + THROUGH_SIGMA * sigma;
    // Beam k next to the run, `past` the one after it.
    let through = |k: usize, past: Option<usize>| {
        let Some(x) = exit(k) else {
            return false;
        };
        if pass.valid(k) {
            return beyond(k, x);
        }
        match past.filter(|&p| p < pass.len()) {
            Some(p) if pass.valid(p) => exit(p).is_some_and(|x| beyond(p, x)),
            Some(_) => true,
            None => false,
        }
    };
    s.checked_sub(1)
        .is_some_and(|k| through(k, k.checked_sub(1)))
        || (e + 1 < pass.len() && through(e + 1, Some(e + 2)))
}
