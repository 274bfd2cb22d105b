//! Gives the corner point between two neighbouring lines to the line it lies on
//! ([`give_corner_point`]). At a corner the walk keeps the first point of the next surface in
//! the segment before it (the point lies near the corner, within the prediction's tolerance
//! of both surfaces), and a segment that starts at an occlusion edge can take one point of the
//! surface before it; at grazing incidence the walk also flags a range jump before a wall's
//! last point and starts the next segment there. The marks are then one beam off, and a face seen over three beams comes
//! out as a four-point line, which no surface is: three beams are too few for a feature.
//! Near the corner the point lies within the noise of both lines; then where the two lines
//! meet tells which surface its beam hit ([`beyond_corner`]).

use crate::config::Config;
use crate::feature::LineFeature;
use crate::fit::line::{fit_line, LineFit};
use crate::geometry::Point;
use crate::output::FeatureSink;
use crate::pass::Pass;
use crate::rule::NoiseRule;

use super::emit;
use super::join::{last_two_lines, unstore_last_two};

/// 99 % of χ²₁: a point further from a line than this (in its residual's σ) is not on it.
const ON_LINE_CHI2: f32 = 6.63;
/// 95 % of χ²₁: a point this far from the line of its segment's other points (in its
/// residual's σ) may be another surface's.
const OFF_LINE_CHI2: f32 = 3.84;
/// σ of the corner's position by which it must pass a point's beam for the point to be the
/// other surface's ([`beyond_corner`]).
const CORNER_SIGMAS: f32 = 1.0;
/// Most points of a segment whose end point may move (its other points are fitted again).
const REST_MAX: usize = 32;

/// When the last two features in `out` are lines of neighbouring segments (no beam between
/// them; a range jump between them may be a grazing wall's, and the tests below decide), the
/// end point of one (of at most [`REST_MAX`] points) next to the other
/// (longer than `min_points`) moves to the other when it lies on the other's line (within
/// [`ON_LINE_CHI2`] of its residual's variance: the range noise's and the line's own there),
/// and off the line of its segment's other points (beyond [`OFF_LINE_CHI2`], or [`ON_LINE_CHI2`]
/// when the rest is too short for a feature, and nearer the other's) or beyond the corner where
/// the two lines meet ([`beyond_corner`]). Both are emitted again.
/// Returns whether it moved. Each move takes one of `moves` (the scan's joins): the work is
/// bounded.
pub(super) fn give_corner_point(
    pass: &mut Pass<'_>,
    rule: &NoiseRule,
    config: &Config,
    out: &mut dyn FeatureSink,
    moves: &mut usize,
) -> bool {
    if *moves == 0 {
        return false;
    }
    let Some((a, b)) = last_two_lines(out) else {
        return false;
    };
    let (a0, a1, b0, b1) = (
        usize::from(a.first),
        usize::from(a.last),
        usize::from(b.first),
        usize::from(b.last),
    );
    if a1 + 1 != b0 {
        return false;
    }
    let (na, nb) = (a1 + 1 - a0, b1 + 1 - b0);
    let min = config.min_points;
    // The split point between the two segments after the move: the first point of the second.
    // A segment the move leaves too short for a feature needs the surer evidence.
    let off = |n: usize| if n > min { OFF_LINE_CHI2 } else { ON_LINE_CHI2 };
    let split = if nb > min && na <= REST_MAX && closer(pass, rule, &b, a1, a0..=a1 - 1, off(na)) {
        a1
    } else if na > min && nb <= REST_MAX && closer(pass, rule, &a, b0, b0 + 1..=b1, off(nb)) {
        b0 + 1
    } else {
        return false;
    };
    *moves -= 1;
    unstore_last_two(pass, out, a1, b0);
    emit::<true>(pass, a0, split - 1, None, config, out);
    emit::<true>(pass, split, b1, None, config, out);
    true
}

/// Whether point `i` lies on the line `l` (within [`ON_LINE_CHI2`]) and either closer to it
/// than to the line of the points `rest` (the short segment's others), each distance in its own
/// σ (the range noise's plus that of the line there), or beyond the corner of the two lines
/// ([`beyond_corner`]).
fn closer(
    pass: &Pass<'_>,
    rule: &NoiseRule,
    l: &LineFeature,
    i: usize,
    rest: core::ops::RangeInclusive<usize>,
    off_chi2: f32,
) -> bool {
    if !pass.valid(i) {
        return false;
    }
    let p = pass.point(i);
    let var_r = rule.sigma_r * rule.sigma_r;
    let (sin, cos) = crate::math::sin_cos(l.alpha);
    let d = p.x * cos + p.y * sin - l.rho;
    // ∂d/∂α = −x sin α + y cos α, ∂d/∂ρ = −1.
    let t = cos * p.y - sin * p.x;
    let var = var_r + t * t * l.var_alpha + l.var_rho - 2.0 * t * l.cov_alpha_rho;
    let on = d * d / var;
    if !(on <= ON_LINE_CHI2) {
        return false;
    }
    // The rest's point next to `i`.
    let next = if *rest.start() > i {
        *rest.start()
    } else {
        *rest.end()
    };
    // The other line, fitted to `rest` and carried to the point: its variance there is
    // σ_r² (1/n + u²/Σu²), u the point's position along it from the centroid.
    let Some(f) = pass.points.get(rest).and_then(|r| fit_line(r).ok()) else {
        return false;
    };
    let u = (p.y - f.centroid.y) * f.cos_alpha - (p.x - f.centroid.x) * f.sin_alpha;
    let (s, c) = (f.sin_alpha, f.cos_alpha);
    let suu = s * s * f.sxx + c * c * f.syy - 2.0 * s * c * f.sxy;
    let var_f = var_r * (1.0 + 1.0 / f.n as f32 + u * u / suu);
    let off = f.signed_distance(&p);
    let off = off * off / var_f;
    (off >= off_chi2 && on < off) || beyond_corner(l, &f, var_r, p, pass.point(next))
}

/// Whether the corner where the lines `l` and `f` meet lies between the beams of the points
/// `p` and `q` (in front of the scanner), off `p`'s beam by more than [`CORNER_SIGMAS`] times
/// its σ there: then `p`'s beam passes the corner on `l`'s side and hits `l`'s surface, `q`'s
/// (and those beyond it) `f`'s. Which surface a beam near the corner hits does not show in its
/// range (within the noise of both lines) but in where the lines, fitted to the other points,
/// meet. The corner's σ across the beam is that of each line there (`f`'s from `var_r` and its
/// points' moments, `l`'s from its covariance) carried along the other line.
fn beyond_corner(l: &LineFeature, f: &LineFit, var_r: f32, p: Point, q: Point) -> bool {
    let (s1, c1) = crate::math::sin_cos(l.alpha);
    let (s2, c2) = (f.sin_alpha, f.cos_alpha);
    // n₁·x = ρ₁, n₂·x = ρ₂ by Cramer's rule.
    let det = c1 * s2 - s1 * c2;
    let c = Point::new(
        (l.rho * s2 - f.rho * s1) / det,
        (c1 * f.rho - c2 * l.rho) / det,
    );
    let cross = |a: Point, b: Point| a.x * b.y - a.y * b.x;
    let turn = cross(p, q);
    // Each line's variance at the corner: f's σ_r² (1/n + u²/Σu²), l's from its covariance.
    let u = (c.y - f.centroid.y) * c2 - (c.x - f.centroid.x) * s2;
    let suu = s2 * s2 * f.sxx + c2 * c2 * f.syy - 2.0 * s2 * c2 * f.sxy;
    let var_f = var_r * (1.0 / f.n as f32 + u * u / suu);
    let t = c1 * c.y - s1 * c.x;
    let var_l = t * t * l.var_alpha + l.var_rho - 2.0 * t * l.cov_alpha_rho;
    // A shift of one line by δ moves the corner along the other by δ / |det|; across the beam
    // (unit u) that is δ |u·n| / |det|, n the normal of the line it moves along.
    let norm = p.norm();
    let (ux, uy) = (p.x / norm, p.y / norm);
    let across_l = ux * c1 + uy * s1;
    let across_f = ux * c2 + uy * s2;
    let var_c = (var_f * across_l * across_l + var_l * across_f * across_f) / (det * det);
    // The corner's distance from p's beam, signed towards q's.
    let off = cross(p, c) / norm * turn.signum();
    // Non-finite values fail every test.
    p.x * c.x + p.y * c.y > 0.0
        && off > 0.0
        && off * off > CORNER_SIGMAS * CORNER_SIGMAS * var_c
        && cross(c, q) * turn > 0.0
}

#[cfg(test)]
#[path = "ends_tests.rs"]
mod tests;

#[cfg(test)]
#[path = "ends_jump_tests.rs"]
mod jump_tests;
