//! Marking (§3.1–3.2, §3.6): every point predicted from the ones before it is a mark point
//! when its prediction error exceeds the threshold. [`paper`]: the paper's rule over a
//! window of `Np` points; [`noise`]: the default mode's walk, with boundary [`refine`]ment.

pub(crate) mod noise;
pub(crate) mod paper;
pub(crate) mod refine;

use crate::config::{Config, NoiseModel, Threshold};
use crate::pass::Pass;
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
}

/// Mark points under the configured rule (the paper's, or the default mode's walk).
#[inline(always)]
pub(crate) fn mark(pass: &mut Pass<'_>, rule: &Rule) {
    pass.neighbours = None;
    match rule {
        Rule::Paper(rule) => paper::mark(pass, rule),
        Rule::Noise(rule) => noise::mark(pass, rule),
    }
}
