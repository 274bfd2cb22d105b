//! Joins neighbouring pieces of one line: runs of short segments ([`join_lines`]) and the last
//! two lines stored ([`join_collinear`]).

use crate::config::Config;
use crate::feature::{Feature, LineFeature};
use crate::fit::run::{line_prefix, on_one_line};
use crate::flags::{END, START};
use crate::math;
use crate::output::FeatureSink;
use crate::pass::Pass;
use crate::rule::NoiseRule;

use super::ends::give_corner_point;
use super::{emit, CHAIN_MIN};

/// cos 0.2 rad: neighbouring lines whose normals differ more are not tested for being one.
const COS_JOIN: f32 = 0.980_066_6;
/// 99 % of χ²₂: two lines' parameters further apart than this are two lines.
const SAME_LINE_CHI2: f32 = 9.21;
/// Most points of a line joined from two.
const JOIN_MAX_POINTS: usize = 400;

/// Joins the parts of the run `cs..=ce` of short segments that lie on one line.
#[inline(never)]
pub(super) fn join_lines(
    pass: &mut Pass<'_>,
    (cs, ce): (usize, usize),
    rule: &NoiseRule,
    config: &Config,
    out: &mut dyn FeatureSink,
    joins: &mut usize,
) {
    let tol = rule.k_sigma + rule.model.floor;
    let var = rule.sigma_r * rule.sigma_r;
    let mut a = cs;
    while a + CHAIN_MIN <= ce + 1 {
        let pts = pass.points.get(a..=ce).unwrap_or(&[]);
        let n = line_prefix(pts, tol).max(1);
        if n >= CHAIN_MIN && pts.get(..n).is_some_and(|p| on_one_line(p, tol, var)) {
            let b = a + n - 1;
            // Undo the short segments inside: a is the start of one or ends the one before.
            let mut undone = 0usize;
            for i in a..=b {
                undone += usize::from(pass.flag(i) & START != 0);
                pass.clear(i, START | END);
            }
            if a > cs {
                pass.set(a - 1, END);
            }
            let mut redone = 0usize;
            if b < ce && pass.flag(b + 1) & START == 0 {
                pass.set(b + 1, START);
                redone = 1;
            }
            let stats = &mut *pass.stats;
            stats.segments = (stats.segments + redone).saturating_sub(undone);
            stats.short_segments = (stats.short_segments + redone).saturating_sub(undone);
            emit::<true>(pass, a, b, None, config, out);
            join_collinear(pass, rule, config, out, joins);
        }
        a += n;
    }
}

/// Makes the last two features in `out` one line when they are lines of neighbouring segments
/// (no beam between) whose points together lie on one line within the noise: a wall whose
/// far, grazing part the walk cut off (its points grow apart faster than the prediction
/// allows), or a wall split where its roughness fooled the walk once.
/// At most [`JOINS_MAX`](super::JOINS_MAX) joins a scan, each of at most
/// [`JOIN_MAX_POINTS`] points: the work they take is bounded.
/// When it does not, the corner point between them may move ([`give_corner_point`]).
#[inline(never)]
pub(super) fn join_collinear(
    pass: &mut Pass<'_>,
    rule: &NoiseRule,
    config: &Config,
    out: &mut dyn FeatureSink,
    joins: &mut usize,
) {
    if !join_pair(pass, rule, config, out, joins) {
        give_corner_point(pass, rule, config, out, joins);
    }
}

/// The last two stored features, when both are lines.
pub(super) fn last_two_lines(out: &mut dyn FeatureSink) -> Option<(LineFeature, LineFeature)> {
    let n = out.features_mut().len();
    let last = out.features_mut().get(n.checked_sub(2)?..)?;
    match <&[Feature; 2]>::try_from(last).ok()? {
        [Feature::Line(a), Feature::Line(b)] => Some((*a, *b)),
        _ => None,
    }
}

/// Takes the last two stored features back (the segments `..=a_last` and `b_first..`), to
/// be emitted again.
pub(super) fn unstore_last_two(
    pass: &mut Pass<'_>,
    out: &mut dyn FeatureSink,
    a_last: usize,
    b_first: usize,
) {
    let n = out.features_mut().len();
    let mut k = 0usize;
    out.retain(&mut |_| {
        k += 1;
        k + 2 <= n
    });
    pass.clear(a_last, END);
    pass.clear(b_first, START);
    let stats = &mut *pass.stats;
    stats.segments = stats.segments.saturating_sub(2);
    stats.features = stats.features.saturating_sub(2);
}

/// [`join_collinear`]'s join: whether it joined the two lines.
fn join_pair(
    pass: &mut Pass<'_>,
    rule: &NoiseRule,
    config: &Config,
    out: &mut dyn FeatureSink,
    joins: &mut usize,
) -> bool {
    if *joins == 0 {
        return false;
    }
    let Some((a, b)) = last_two_lines(out) else {
        return false;
    };
    let (s, e) = (usize::from(a.first), usize::from(b.last));
    // Neighbours, also across a range jump: at grazing incidence a wall's points are far apart.
    if usize::from(a.last) + 1 != usize::from(b.first) || e + 1 - s > JOIN_MAX_POINTS {
        return false;
    }
    // Cheap first: the normals within 0.2 rad of each other (or of the other's opposite: one
    // line through the scanner's side has ρ near 0 and either normal).
    let (sa, ca) = math::sin_cos(a.alpha);
    let (sb, cb) = math::sin_cos(b.alpha);
    if !(math::abs(ca * cb + sa * sb) > COS_JOIN) {
        return false;
    }
    // The same line within both fits' stated uncertainty (99 % of χ²₂), and their points on one
    // line within the noise.
    if !(same_line(&a, &b) <= SAME_LINE_CHI2) {
        return false;
    }
    let tol = rule.k_sigma + rule.model.floor;
    let var = rule.sigma_r * rule.sigma_r;
    if !pass
        .points
        .get(s..=e)
        .is_some_and(|p| on_one_line(p, tol, var))
    {
        return false;
    }
    *joins -= 1;
    unstore_last_two(pass, out, usize::from(a.last), usize::from(b.first));
    emit::<true>(pass, s, e, None, config, out);
    true
}

/// The NIS of the difference of the lines `a` and `b` (both in the scanner's frame, ρ ≥ 0),
/// with the sum of their covariances; NaN when it has none.
pub(super) fn same_line(a: &LineFeature, b: &LineFeature) -> f32 {
    let mut da = a.alpha - b.alpha;
    if da > core::f32::consts::PI {
        da -= 2.0 * core::f32::consts::PI;
    } else if da < -core::f32::consts::PI {
        da += 2.0 * core::f32::consts::PI;
    }
    let dr = a.rho - b.rho;
    let (saa, srr, sar) = (
        a.var_alpha + b.var_alpha,
        a.var_rho + b.var_rho,
        a.cov_alpha_rho + b.cov_alpha_rho,
    );
    let det = saa * srr - sar * sar;
    if !(det > 0.0) {
        return f32::NAN;
    }
    (srr * da * da - 2.0 * sar * da * dr + saa * dr * dr) / det
}

#[cfg(test)]
#[path = "join_tests.rs"]
mod tests;
