//! The configured threshold as the steps use it ([`Rule`]): the paper's (§3.2, §3.6) or the
//! default mode's noise model, with the numbers it needs derived once per extraction, and
//! whether a prediction says "mark".

use crate::beams::MIN_INCIDENCE;
use crate::config::{Config, NoiseModel, Threshold};
use crate::geometry::Point;
use crate::math;
use crate::predict::{paper_threshold, Prediction};

/// The configured threshold with the numbers it needs, derived once per extraction.
#[derive(Clone, Copy)]
pub(crate) enum Rule {
    /// Paper §3.6.
    Paper(PaperRule),
    /// The default mode's.
    Noise(NoiseRule),
}

/// The paper's threshold: `d_m = (d_0/λ)(r/r_max + (π − ϕ)/π)`.
#[derive(Clone, Copy)]
pub(crate) struct PaperRule {
    /// d_0, mm.
    pub d0: f32,
    /// λ.
    pub lambda: f32,
    /// The scanner's maximum range, mm.
    pub r_max: f32,
}

/// The default mode's threshold, `k σ_r f + floor` (see [`NoiseModel`]), and its jump limit.
#[derive(Clone, Copy)]
pub(crate) struct NoiseRule {
    /// The configured model.
    pub model: NoiseModel,
    /// Range noise σ_r, mm.
    pub sigma_r: f32,
    /// `k σ_r`.
    pub k_sigma: f32,
    /// `(k σ_r)²`.
    pub k_sigma2: f32,
    /// Largest gap between consecutive points of one surface per mm of range (from the beam
    /// table).
    pub gap_factor: f32,
    /// Allowance added to the jump limit, mm: the noise of two readings and the floor.
    pub jump_add: f32,
}

impl Rule {
    /// The rule of `config` for a scanner of maximum range `r_max` whose beams allow
    /// `gap_factor` (see [`NoiseRule::gap_factor`]).
    pub(crate) fn new(config: &Config, r_max: f32, gap_factor: f32) -> Self {
        match config.threshold {
            Threshold::Paper { d0, lambda } => Rule::Paper(PaperRule { d0, lambda, r_max }),
            Threshold::Noise(model) => {
                let k_sigma = model.k * config.sigma_r;
                Rule::Noise(NoiseRule {
                    model,
                    sigma_r: config.sigma_r,
                    k_sigma,
                    k_sigma2: k_sigma * k_sigma,
                    gap_factor,
                    jump_add: k_sigma * core::f32::consts::SQRT_2 + model.floor,
                })
            }
        }
    }

    /// Whether a prediction of the point at measured range `r` says "mark" (no prediction:
    /// a mark).
    pub(crate) fn marks(&self, pred: Option<Prediction>, r: f32) -> bool {
        let Some(p) = pred else { return true };
        match self {
            Rule::Paper(rule) => rule.marks(&p, r),
            Rule::Noise(rule) => rule.marks(&p),
        }
    }

    /// The default mode's rule, when it is the one configured.
    pub(crate) fn noise(&self) -> Option<&NoiseRule> {
        match self {
            Rule::Noise(rule) => Some(rule),
            Rule::Paper(_) => None,
        }
    }
}

impl PaperRule {
    /// Paper §3.2: the error exceeds `d_m`.
    pub(crate) fn marks(&self, p: &Prediction, r: f32) -> bool {
        p.error > paper_threshold(self.d0, self.lambda, r, self.r_max, p.phi())
    }
}

impl NoiseRule {
    /// The error exceeds `k σ_r f + floor`.
    pub(crate) fn marks(&self, p: &Prediction) -> bool {
        p.exceeds(self.model.k, self.sigma_r, self.model.floor)
    }

    /// Largest distance, mm, from a point at range `prev_r` to the next one on one surface.
    #[inline(always)]
    pub(crate) fn jump_limit(&self, prev_r: f32) -> f32 {
        prev_r * self.gap_factor + self.jump_add
    }

    /// [`Self::jump_limit`] from the point `a` (at range `prev_r`) to `b`, both relative to
    /// the scanner, at the angle they are apart rather than one beam step: the gap a surface
    /// seen at down to [`MIN_INCIDENCE`] leaves between them. For points not evenly spaced in
    /// bearing (interleaved sweeps de-skewed or moved onto sweep 0).
    pub(crate) fn jump_limit_between(&self, a: Point, b: Point, prev_r: f32) -> f32 {
        // |a × b| = |a||b| sin Δφ, a·b = |a||b| cos Δφ: sin(λ − Δφ) |a||b| below.
        let cross = math::abs(a.x * b.y - a.y * b.x);
        let dot = a.x * b.x + a.y * b.y;
        let norm = math::sqrt((a.x * a.x + a.y * a.y) * (b.x * b.x + b.y * b.y));
        let (sin_l, cos_l) = math::sin_cos(MIN_INCIDENCE);
        let below = sin_l * dot - cos_l * cross;
        let floor = 1e-3 * norm;
        let gap = cross / if below > floor { below } else { floor };
        if math::finite(gap) {
            prev_r * gap + self.jump_add
        } else {
            self.jump_limit(prev_r)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The jump limit between two points at their own angle Δφ apart is the gap a surface seen
    /// at 10° incidence leaves, `r sin Δφ / sin(λ − Δφ)`, plus the noise allowance (f64
    /// reference, both points at range r); one beam step apart, the beam table's limit.
    #[test]
    fn the_jump_limit_between_two_points_follows_their_angle() -> Result<(), &'static str> {
        let lam = 10.0f64.to_radians();
        let step = 0.5f64.to_radians();
        let gap = (step.sin() / (lam - step).sin()) as f32;
        let Rule::Noise(rule) = Rule::new(&Config::default(), 8000.0, gap) else {
            return Err("not the noise rule");
        };
        for r in [500.0f64, 3000.0, 20000.0] {
            for dphi in [0.0027f64, step, 0.0147, 0.1] {
                let b = 0.3f64;
                let a = Point::new((r * b.cos()) as f32, (r * b.sin()) as f32);
                let c = Point::new((r * (b + dphi).cos()) as f32, (r * (b + dphi).sin()) as f32);
                let want = r * dphi.sin() / (lam - dphi).sin() + f64::from(rule.jump_add);
                let got = f64::from(rule.jump_limit_between(a, c, r as f32));
                assert!(
                    (got - want).abs() <= 1e-3 * want,
                    "r {r} Δφ {dphi}: {got} {want}"
                );
                if dphi == step {
                    let table = f64::from(rule.jump_limit(r as f32));
                    assert!((got - table).abs() <= 1e-3 * table, "{got} {table}");
                }
            }
        }
        // At or past λ the gap has no bound but the floor's (10³ r sin Δφ), and a point that
        // is not finite gives the beam table's limit.
        let (a, c) = (Point::new(1000.0, 0.0), Point::new(0.0, 1000.0));
        assert!(rule.jump_limit_between(a, c, 1000.0) > 1e5);
        for (dphi, ra, rc) in [(0.5f64, 1000.0f64, 3000.0f64), (0.2, 2500.0, 700.0)] {
            let at = |r: f64, t: f64| Point::new((r * t.cos()) as f32, (r * t.sin()) as f32);
            let (a, c) = (at(ra, 0.7), at(rc, 0.7 + dphi));
            let want = ra * 1e3 * dphi.sin() + f64::from(rule.jump_add);
            let got = f64::from(rule.jump_limit_between(a, c, ra as f32));
            assert!((got - want).abs() <= 1e-4 * want, "Δφ {dphi}: {got} {want}");
        }
        let nan = Point::new(f32::NAN, 0.0);
        assert_eq!(
            rule.jump_limit_between(a, nan, 1000.0),
            rule.jump_limit(1000.0)
        );
        Ok(())
    }
}
