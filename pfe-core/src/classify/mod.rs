//! Type and parameters of a segment (§3.5): a line or a circle, by the paper's mean distance
//! to the fitted line or (default mode) by comparing the two fits; then the feature with its
//! covariance. [`arc`]: the default mode's arc tests.

pub(crate) mod arc;

use crate::config::{Config, Typing};
use crate::feature::{circle_feature, line_feature, line_feature_with, Feature};
use crate::fit::circle::{fit_circle, refine_circle, refine_from, Circle, NormalEquations};
use crate::fit::line::{fit_line, LineFit};
use crate::geometry::Point;
use crate::pass::Pass;

/// The feature of the segment `s..=e` (`None`: degenerate).
pub(crate) fn feature(pass: &Pass<'_>, s: usize, e: usize, config: &Config) -> Option<Feature> {
    let pts = pass.points.get(s..=e)?;
    let origin = pass.origin((s + e) / 2);
    let line = fit_line(pts).ok();
    match circle_of(pts, line.as_ref(), config) {
        Some(c) => circle_feature(pts, s, e, &c, origin, config.sigma_r),
        None => {
            let line = line?;
            let ends = [pts.first()?, pts.last()?];
            let cov = pass
                .beams
                .span(s, e)
                .filter(|_| pass.motion.is_none())
                .and_then(|beams| line.covariance_beams(&beams, ends, config.sigma_r));
            match cov {
                Some(cov) => line_feature_with(pts, s, e, &line, cov),
                None => line_feature(pts, s, e, &line, origin, config.sigma_r),
            }
        }
    }
}

/// The circle of `pts` when the configured typing says they are one (`line`: their line fit,
/// if any).
fn circle_of(pts: &[Point], line: Option<&LineFit>, config: &Config) -> Option<Circle> {
    let circle = || {
        let c = fit_circle(pts, config.circle_method).ok()?;
        if config.circle_refine > 0 {
            refine_circle(pts, c, config.circle_refine).ok()
        } else {
            Some(c)
        }
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
                .map(|(c, _)| c)
        }
    }
}
