//! Type and parameters of a segment (§3.5): a line or a circle, by the paper's mean distance
//! to the fitted line or (default mode) by comparing the two fits; then the feature with its
//! covariance. [`arc`]: the default mode's arc tests. In the default mode a circle must also
//! beat the best two-line (corner) split, cover enough points and arc angle, and every
//! feature's covariance is scaled up by the reduced χ² of its fit when that shows more scatter
//! than σ_r explains.

pub(crate) mod arc;

use crate::config::{Config, Typing};
use crate::feature::{
    circle_feature, line_feature, line_feature_with, CircleFeature, Feature, LineFeature,
};
use crate::fit::circle::{fit_circle, refine_circle, refine_from, Circle, NormalEquations};
use crate::fit::line::{fit_line, LineFit};
use crate::fit::run::best_split_sse;
use crate::geometry::Point;
use crate::math;
use crate::pass::Pass;

/// Fewest points of a circle in the default mode.
const CIRCLE_MIN_POINTS: usize = 6;
/// Smallest arc a circle must cover in the default mode, as tan of its angle (30°): a short
/// bent piece is not an arc.
const CIRCLE_MIN_ARC_TAN: f32 = 0.577_350_3;

/// The feature of the segment `s..=e` (`None`: degenerate).
pub(crate) fn feature<const SCRUTINY: bool>(
    pass: &Pass<'_>,
    s: usize,
    e: usize,
    config: &Config,
) -> Option<Feature> {
    let pts = pass.points.get(s..=e)?;
    let origin = pass.origin((s + e) / 2);
    let line = fit_line(pts).ok();
    let honest = SCRUTINY && matches!(config.typing, Typing::CompareFits { .. });
    let var = config.sigma_r * config.sigma_r;
    match circle_of::<SCRUTINY>(pts, line.as_ref(), config) {
        Some((c, _)) if !honest => circle_feature(pts, s, e, &c, origin, config.sigma_r),
        Some((c, sse)) => {
            let mut f = circle_feature(pts, s, e, &c, origin, config.sigma_r)?;
            if let Feature::Circle(cf) = &mut f {
                let c2 = mean_cos2(pass, s, pts, |p| {
                    Point::new(p.x - c.center.x, p.y - c.center.y)
                });
                let k = scatter_scale(sse, var * c2, pts.len() as f32 - 3.0);
                cf.cov = cf.cov.map(|row| row.map(|v| v * k));
                systematic_circle(cf, origin, config.sigma_sys);
            }
            Some(f)
        }
        None => {
            let line = line?;
            let ends = [pts.first()?, pts.last()?];
            let cov = pass
                .beams
                .span(s, e)
                .filter(|_| pass.motion.is_none())
                .and_then(|beams| line.covariance_beams(&beams, ends, config.sigma_r));
            let f = match cov {
                Some(cov) => line_feature_with(pts, s, e, &line, cov),
                None => line_feature(pts, s, e, &line, origin, config.sigma_r),
            };
            if !honest {
                return f;
            }
            let mut f = f?;
            if let Feature::Line(lf) = &mut f {
                let normal = Point::new(line.cos_alpha, line.sin_alpha);
                let c2 = mean_cos2(pass, s, pts, |_| normal);
                let k = scatter_scale(line.sse(), var * c2, pts.len() as f32 - 2.0);
                lf.var_alpha *= k;
                lf.var_rho *= k;
                lf.cov_alpha_rho *= k;
                systematic_line(lf, config.sigma_sys);
            }
            Some(f)
        }
    }
}

/// The mean share of range noise along the fitted curve's normal, cos²β, over the points `pts`
/// of beams `s..` (β the incidence of each point's beam on the normal `normal(p)`, which need
/// not be a unit vector): the variance of a residual is σ_r² cos²β. 1 when no point tells.
fn mean_cos2(pass: &Pass<'_>, s: usize, pts: &[Point], normal: impl Fn(Point) -> Point) -> f32 {
    let (mut sum, mut n) = (0.0f32, 0usize);
    for (i, &p) in pts.iter().enumerate() {
        let o = pass.origin(s + i);
        let (d, m) = (Point::new(p.x - o.x, p.y - o.y), normal(p));
        let c2 = (d.x * m.x + d.y * m.y) * (d.x * m.x + d.y * m.y)
            / ((d.x * d.x + d.y * d.y) * (m.x * m.x + m.y * m.y));
        if math::finite(c2) {
            sum += c2;
            n += 1;
        }
    }
    if n > 0 {
        sum / n as f32
    } else {
        1.0
    }
}

/// Adds the share of a beam-to-beam systematic range error σ_sys (`s`, mm) to a line's
/// covariance: an offset σ_sys along the normal (ρ) and a tilt about the line's middle M of
/// variance 2σ_sys²/L² (its two ends independent), which moves ρ by the tilt times M's position
/// along the line.
fn systematic_line(lf: &mut LineFeature, s: f32) {
    if !(s > 0.0) {
        return;
    }
    let (dx, dy) = (lf.end.x - lf.start.x, lf.end.y - lf.start.y);
    let len2 = dx * dx + dy * dy;
    if !(len2 > 0.0) {
        return;
    }
    let tilt = 2.0 * s * s / len2;
    let (sin, cos) = math::sin_cos(lf.alpha);
    // M · t, t = (−sin α, cos α) the line's direction.
    let along = 0.5 * ((lf.start.x + lf.end.x) * -sin + (lf.start.y + lf.end.y) * cos);
    lf.var_alpha += tilt;
    lf.cov_alpha_rho += tilt * along;
    lf.var_rho += s * s + tilt * along * along;
}

/// Adds the share of a beam-to-beam systematic range error σ_sys (`s`, mm) to a circle's
/// centre covariance: σ_sys² along the beam from the scanner (`origin`) to the centre (an
/// offset common to its beams moves every point, and so the centre, that way).
fn systematic_circle(cf: &mut CircleFeature, origin: Point, s: f32) {
    let (dx, dy) = (cf.center.x - origin.x, cf.center.y - origin.y);
    let d2 = dx * dx + dy * dy;
    if !(s > 0.0 && d2 > 0.0) {
        return;
    }
    let k = s * s / d2;
    let [[xx, xy, _], [yx, yy, _], _] = &mut cf.cov;
    *xx += k * dx * dx;
    *xy += k * dx * dy;
    *yx += k * dx * dy;
    *yy += k * dy * dy;
}

/// Factor on a fit's covariance: its reduced χ², `sse / (var · dof)` (`var` the variance of a
/// residual under the noise model), when that exceeds 1 by more than three standard deviations
/// of its sampling spread √(2/dof); otherwise 1 (the noise model explains the scatter). No
/// division unless it scales.
fn scatter_scale(sse: f32, var: f32, dof: f32) -> f32 {
    let expected = var * dof;
    // sse/expected − 1 > 3 √(2/dof), squared and times expected².
    let excess = sse - expected;
    if !(dof >= 1.0
        && expected > 0.0
        && excess > 0.0
        && excess * excess * dof > 18.0 * expected * expected)
    {
        return 1.0;
    }
    let ratio = sse / expected;
    if math::finite(ratio) {
        ratio
    } else {
        1.0
    }
}

/// The circle of `pts` when the configured typing says they are one (`line`: their line fit,
/// if any), with its residual sum (NaN where not computed).
fn circle_of<const SCRUTINY: bool>(
    pts: &[Point],
    line: Option<&LineFit>,
    config: &Config,
) -> Option<(Circle, f32)> {
    let circle = || {
        let c = fit_circle(pts, config.circle_method).ok()?;
        if config.circle_refine > 0 {
            refine_circle(pts, c, config.circle_refine).ok()
        } else {
            Some(c)
        }
        .map(|c| (c, f32::NAN))
    };
    let Some(l) = line else { return circle() };
    match config.typing {
        Typing::MeanDistance { d_f } => {
            if l.mean_abs_distance(pts) <= d_f {
                None
            } else {
                circle()
            }
        }
        Typing::CompareFits {
            chi2,
            ratio,
            max_radius,
        } => {
            let sse_l = l.sse();
            let var = config.sigma_r * config.sigma_r;
            // A circle must beat the line by chi2·σ_r²: not possible when the line's own
            // residual is smaller. Then the cheap algebraic fit screens the candidates before
            // the geometric refinement.
            let algebraic = (sse_l > chi2 * var && sse_l > 1.5 * var * pts.len() as f32)
                .then(|| fit_circle(pts, config.circle_method).ok())
                .flatten()
                .map(|c| (c, NormalEquations::at(pts, &c)))
                .filter(|(c, eq)| c.radius <= 1.5 * max_radius && eq.sse < 2.0 * ratio * sse_l);
            algebraic
                .and_then(|(c, eq)| {
                    if config.circle_refine > 0 {
                        refine_from(pts, c, eq, config.circle_refine).ok()
                    } else {
                        Some((c, eq.sse))
                    }
                })
                .filter(|(c, sse_c)| {
                    // The circle must also explain the points (RMS residual ≤ 2σ_r): an
                    // undetected corner fits neither model and stays a line.
                    c.radius <= max_radius
                        && sse_l - sse_c > chi2 * var
                        && *sse_c < ratio * sse_l
                        && *sse_c <= 4.0 * var * pts.len() as f32
                })
                .filter(|(c, sse_c)| !SCRUTINY || is_arc(pts, c, *sse_c, 0.0))
        }
    }
}

/// Whether `circle` (residual sum `sse_c`) is an arc really there: enough points, an arc of
/// at least 30° between the first and the last point, and a residual sum below the best
/// two-line (corner) split's by `margin` (a corner, door frame or bend is two lines).
fn is_arc(pts: &[Point], circle: &Circle, sse_c: f32, margin: f32) -> bool {
    let (Some(a), Some(b)) = (pts.first(), pts.last()) else {
        return false;
    };
    let c = circle.center;
    let (ax, ay, bx, by) = (a.x - c.x, a.y - c.y, b.x - c.x, b.y - c.y);
    let (dot, cross) = (ax * bx + ay * by, ax * by - ay * bx);
    // Beyond 90° (dot < 0) this holds whatever the cross product.
    let wide = math::abs(cross) >= CIRCLE_MIN_ARC_TAN * dot;
    pts.len() >= CIRCLE_MIN_POINTS
        && wide
        && best_split_sse(pts).is_some_and(|split| split - sse_c > margin)
}

#[cfg(test)]
mod tests;
