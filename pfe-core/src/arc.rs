//! The default mode's arc test ([`arc_fit`]): whether a run of points is an arc, significantly
//! better explained by a circle than by a line. The walk uses it to continue an arc and to
//! merge a new segment into the arc before it (`mark`), the segment step to merge neighbouring
//! segments of one arc (`segment`).

use crate::fit::circle::{ArcSums, Circle};
use crate::geometry::Point;
use crate::math;
use crate::rule::NoiseRule;

/// Circle through `pts` when it explains them significantly better than a line (by
/// `arc_chi2 σ_r²`), with every radial residual within `k σ_r + floor` and a radius of at most
/// `arc_max_radius`.
pub(crate) fn arc_fit(pts: &[Point], rule: &NoiseRule) -> Option<Circle> {
    let (m, sigma_r) = (&rule.model, rule.sigma_r);
    let var = sigma_r * sigma_r;
    // One pass for both fits. The circle's residual sum is ≥ 0, so a line this good cannot be
    // beaten by enough.
    let sums = ArcSums::of(pts)?;
    let line_sse = sums.line_sse();
    if !(line_sse >= m.arc_chi2 * var) {
        return None;
    }
    let circle = sums.kasa()?;
    if !(circle.radius <= m.arc_max_radius) {
        return None;
    }
    let tol = rule.k_sigma + m.floor;
    // One pass: every radial residual within `tol`, and their sum of squares.
    let mut sse = 0.0f32;
    for p in pts {
        let r = p.distance(&circle.center) - circle.radius;
        if !(math::abs(r) <= tol) {
            return None;
        }
        sse += r * r;
    }
    // An arc explains its points to the noise (RMS ≤ 1.5 σ_r); the rounded-off view of a
    // corner does not.
    (sse <= 2.25 * var * pts.len() as f32 && line_sse - sse >= m.arc_chi2 * var).then_some(circle)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Config;

    /// The default configuration's rule for range noise `sigma_r` mm.
    fn noise_rule(sigma_r: f32) -> crate::rule::Rule {
        crate::rule::Rule::new(&Config::default().with_sigma_r(sigma_r), 8000.0, 1.0)
    }

    /// An arc's points must each lie within `k σ_r + floor` (4 · 10 + 3 = 43 mm) of its
    /// circle: 24 points over 60° of a 500 mm circle, one of them moved out by 0.8 and by 1.3
    /// times that (the fit takes up a twentieth of it).
    #[test]
    fn every_point_of_an_arc_is_within_k_sigma_plus_floor() {
        let rule = noise_rule(10.0);
        let Some(noise) = rule.noise() else {
            panic!("the default rule")
        };
        let tol = noise.k_sigma + noise.model.floor;
        assert_eq!(tol, 43.0);
        let arc = |off: f32| -> heapless::Vec<Point, 32> {
            (0..24)
                .map(|i| {
                    let a = core::f32::consts::PI * (5.0 / 6.0 + i as f32 / 69.0);
                    let r = 500.0 + if i == 12 { off * tol } else { 0.0 };
                    let (s, c) = math::sin_cos(a);
                    Point::new(3500.0 + r * c, r * s)
                })
                .collect()
        };
        assert!(arc_fit(&arc(0.0), noise).is_some());
        assert!(arc_fit(&arc(0.8), noise).is_some());
        assert!(arc_fit(&arc(1.3), noise).is_none());
        assert!(arc_fit(&arc(-0.8), noise).is_some());
        assert!(arc_fit(&arc(-1.3), noise).is_none());
    }

    /// An arc must explain its points better than a line by `arc_chi2 σ_r²` (16 · 100 mm²)
    /// after its own residuals: 24 points over 588 mm of a circle, every other one 16 mm out
    /// (a circle residual sum of about 24 · 8²); of radius 2 m (the line's residual sum about
    /// 1 000 mm² more than the circle's, though 2 500 in all) not an arc, of radius 1 m (4 000
    /// more) an arc.
    #[test]
    fn an_arc_beats_the_line_by_chi2_after_its_own_residuals() {
        let rule = noise_rule(10.0);
        let Some(noise) = rule.noise() else {
            panic!("the default rule")
        };
        let bumpy = |radius: f32| -> heapless::Vec<Point, 32> {
            let span = 588.0 / radius;
            (0..24)
                .map(|i| {
                    let a = core::f32::consts::PI + span * (i as f32 / 23.0 - 0.5);
                    let r = radius + if i % 2 == 1 { 16.0 } else { 0.0 };
                    let (s, c) = math::sin_cos(a);
                    Point::new(3000.0 + radius + r * c, r * s)
                })
                .collect()
        };
        let (wide, tight) = (bumpy(2000.0), bumpy(1000.0));
        let sse = |p: &[Point]| crate::fit::line::fit_line(p).map_or(f32::NAN, |l| l.sse());
        assert!(sse(&wide) > 1600.0 && sse(&wide) < 3000.0, "{}", sse(&wide));
        assert!(arc_fit(&wide, noise).is_none());
        assert!(arc_fit(&tight, noise).is_some(), "{}", sse(&tight));
    }
}
