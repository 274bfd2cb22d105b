//! Type and parameters of a segment (§3.5): a line or a circle, by the paper's mean distance
//! to the fitted line or (default mode) by comparing the two fits; then the feature with its
//! covariance. In the default mode a circle must also
//! beat the best two-line (corner) split, cover enough points and arc angle; an arc of at
//! most 120° over at least 8 points may come within 2 σ_r² of the split instead, if the
//! beams next to its run do not see through it ([`arc`]); and every
//! feature's covariance is scaled up by the reduced χ² of its fit when that shows more scatter
//! than σ_r explains, and further when that scatter is correlated from beam to beam
//! ([`covariance`]).

mod arc;
mod covariance;

use crate::config::{Config, Typing};
use crate::feature::{circle_feature, line_feature, line_feature_with, Feature};
use crate::fit::circle::{fit_circle, refine_circle, refine_from, Circle, NormalEquations};
use crate::fit::line::{fit_line, LineFit};
use crate::geometry::Point;
use crate::math;
use crate::pass::Pass;
#[cfg(test)]
use arc::is_arc;
use arc::{arc_test, seen_through};
use covariance::{correlated_scale, mean_cos2, scatter_scale, systematic_circle, systematic_line};

/// Drop of the residual sum a circle must give over the line, in units of σ_r², for a short
/// run's points to be curved (99 % of χ²₁: the circle's one more parameter).
const CURVED_CHI2: f32 = 6.63;
/// Largest reduced residual sum (in σ_r²) of the circle that shows a run curved.
const CURVED_FIT: f32 = 1.5;
/// Largest radius of the circle that shows a run curved, mm.
const CURVED_MAX_RADIUS: f32 = 1000.0;

/// Whether the points `pts` of the segment from beam `s` typed a line are curved instead (in
/// the default mode): a circle of at most [`CURVED_MAX_RADIUS`] explains them to the noise and
/// significantly better than the line, though not by as much as the typing asks of a circle
/// (too few points or too short an arc for one): a pillar seen over a few beams. The noise is
/// the range noise's share along the line's normal ([`mean_cos2`]): a pillar's side seen
/// obliquely bends by less than σ_r, but by far more than the noise across it. The caller
/// reports such a run, when it is small, as an object rather than a line.
pub(crate) fn curved(pass: &Pass<'_>, s: usize, pts: &[Point], config: &Config) -> bool {
    if !matches!(config.typing, Typing::CompareFits { .. }) || pts.len() < 4 {
        return false;
    }
    let Ok(line) = fit_line(pts) else {
        return false;
    };
    let normal = Point::new(line.cos_alpha, line.sin_alpha);
    let var = config.sigma_r * config.sigma_r;
    let var_l = var * mean_cos2(pass, s, pts, |_| normal);
    let sse_l = line.sse();
    if !(sse_l > CURVED_CHI2 * var_l) {
        return false;
    }
    let Some((c, sse_c)) = fit_circle(pts, config.circle_method)
        .ok()
        .and_then(|c| refine_from(pts, c, NormalEquations::at(pts, &c), config.circle_refine).ok())
    else {
        return false;
    };
    let dof = pts.len().saturating_sub(3).max(1) as f32;
    c.radius <= CURVED_MAX_RADIUS
        && sse_l - sse_c > CURVED_CHI2 * var_l
        && sse_c <= CURVED_FIT * var * dof
}

/// Whether the features' covariance is made honest ([`covariance`]): with the checks for real
/// scans (`scrutiny`), when the typing compares the fits.
pub(crate) fn honest(config: &Config, scrutiny: bool) -> bool {
    scrutiny && matches!(config.typing, Typing::CompareFits { .. })
}

/// The feature of the segment `s..=e` (`None`: degenerate), with the checks for real scans
/// when `SCRUTINY`.
pub(crate) fn feature<const SCRUTINY: bool>(
    pass: &Pass<'_>,
    s: usize,
    e: usize,
    config: &Config,
) -> Option<Feature> {
    feature_and_line::<SCRUTINY>(pass, s, e, config).0
}

/// [`feature`] with the plain line fit of the segment's points (`None` when it failed), which
/// the caller may use again instead of fitting the same points again.
pub(crate) fn feature_and_line<const SCRUTINY: bool>(
    pass: &Pass<'_>,
    s: usize,
    e: usize,
    config: &Config,
) -> (Option<Feature>, Option<LineFit>) {
    let Some(pts) = pass.points.get(s..=e) else {
        return (None, None);
    };
    let line = fit_line(pts).ok();
    (feature_of::<SCRUTINY>(pass, s, e, pts, line, config), line)
}

/// [`feature`] of the points `pts` of the segment `s..=e`, `line` their line fit.
#[inline(always)]
fn feature_of<const SCRUTINY: bool>(
    pass: &Pass<'_>,
    s: usize,
    e: usize,
    pts: &[Point],
    line: Option<LineFit>,
    config: &Config,
) -> Option<Feature> {
    let origin = pass.origin((s + e) / 2);
    let honest = honest(config, SCRUTINY);
    let var = config.sigma_r * config.sigma_r;
    // A circle the split allowance let through must also hide what lies behind it.
    let circle = circle_of::<SCRUTINY>(pts, line.as_ref(), config)
        .filter(|&(c, _, allowed)| !allowed || !seen_through(pass, s, e, &c, config.sigma_r));
    match circle {
        Some((c, _, _)) if !honest => circle_feature(pts, s, e, &c, origin, config.sigma_r),
        Some((c, sse, _)) => honest_circle(pass, s, e, pts, (&c, sse), config),
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
                let (sse, dof) = (line.sse(), pts.len() as f32 - 2.0);
                let mut k = scatter_scale(sse, var * c2, dof);
                if k > 1.0 {
                    let residuals = pts.iter().map(|p| line.signed_distance(p));
                    k = correlated_scale(residuals, var * c2, dof).unwrap_or(k);
                }
                lf.var_alpha *= k;
                lf.var_rho *= k;
                lf.cov_alpha_rho *= k;
                systematic_line(lf, config.sigma_sys);
            }
            Some(f)
        }
    }
}

/// The circle feature of the points `pts` of the segment `s..=e` on the circle `c` with residual
/// sum `sse`, its covariance scaled by the scatter the noise does not explain (and its
/// correlation) and the systematic error's share.
fn honest_circle(
    pass: &Pass<'_>,
    s: usize,
    e: usize,
    pts: &[Point],
    (c, sse): (&Circle, f32),
    config: &Config,
) -> Option<Feature> {
    let origin = pass.origin((s + e) / 2);
    let var = config.sigma_r * config.sigma_r;
    let mut f = circle_feature(pts, s, e, c, origin, config.sigma_r)?;
    if let Feature::Circle(cf) = &mut f {
        let c2 = mean_cos2(pass, s, pts, |p| {
            Point::new(p.x - c.center.x, p.y - c.center.y)
        });
        let dof = pts.len() as f32 - 3.0;
        let mut k = scatter_scale(sse, var * c2, dof);
        // Only a significant scatter can show its correlation (see `correlated_scale`).
        if k > 1.0 {
            let (o, r) = (c.center, c.radius);
            let residuals = pts.iter().map(|p| math::hypot(p.x - o.x, p.y - o.y) - r);
            k = correlated_scale(residuals, var * c2, dof).unwrap_or(k);
        }
        cf.cov = cf.cov.map(|row| row.map(|v| v * k));
        systematic_circle(cf, origin, config.sigma_sys);
    }
    Some(f)
}

/// The circle feature of the segment `s..=e` (default mode, with the checks for real scans)
/// when its points are curved ([`curved`]) though the typing made them no circle: for a caller
/// that knows more of the scene (a pillar's two pieces between the walls it stands in).
pub(crate) fn curved_circle(
    pass: &Pass<'_>,
    s: usize,
    e: usize,
    config: &Config,
) -> Option<Feature> {
    let pts = pass.points.get(s..=e)?;
    if !curved(pass, s, pts, config) {
        return None;
    }
    let c = fit_circle(pts, config.circle_method).ok()?;
    let (c, sse) = refine_from(pts, c, NormalEquations::at(pts, &c), config.circle_refine).ok()?;
    (c.radius <= CURVED_MAX_RADIUS).then(|| honest_circle(pass, s, e, pts, (&c, sse), config))?
}

/// The circle of `pts` when the configured typing says they are one (`line`: their line fit,
/// if any), with its residual sum (NaN where not computed) and whether only the split
/// allowance made it an arc ([`arc::arc_test`]).
fn circle_of<const SCRUTINY: bool>(
    pts: &[Point],
    line: Option<&LineFit>,
    config: &Config,
) -> Option<(Circle, f32, bool)> {
    let circle = || {
        let c = fit_circle(pts, config.circle_method).ok()?;
        if config.circle_refine > 0 {
            refine_circle(pts, c, config.circle_refine).ok()
        } else {
            Some(c)
        }
        .map(|c| (c, f32::NAN, false))
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
                .filter(|c| c.radius <= 1.5 * max_radius)
                .map(|c| (c, NormalEquations::at(pts, &c)))
                .filter(|(_, eq)| eq.sse < 2.0 * ratio * sse_l);
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
                .and_then(|(c, sse_c)| {
                    let allowed = if SCRUTINY {
                        arc_test(pts, &c, sse_c, var)?
                    } else {
                        false
                    };
                    Some((c, sse_c, allowed))
                })
        }
    }
}

#[cfg(test)]
mod tests;
