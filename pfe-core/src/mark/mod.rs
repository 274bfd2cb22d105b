//! Marking (§3.1–3.2, §3.6): every point predicted from the ones before it is a mark point
//! when its prediction error exceeds the threshold. [`paper`]: the paper's rule over a
//! window of `Np` points; [`noise`]: the default mode's walk, with boundary [`refine`]ment.

pub(crate) mod arc;
pub(crate) mod noise;
pub(crate) mod paper;
pub(crate) mod refine;

use crate::pass::Pass;
use crate::rule::Rule;

/// Mark points under the configured rule (the paper's, or the default mode's walk).
#[inline(always)]
pub(crate) fn mark(pass: &mut Pass<'_>, rule: &Rule) {
    pass.neighbours = None;
    match rule {
        Rule::Paper(rule) => paper::mark(pass, rule),
        Rule::Noise(rule) => noise::mark(pass, rule),
    }
}
