//! Marking (§3.1–3.2, §3.6): every point predicted from the ones before it is a mark point
//! when its prediction error exceeds the threshold. [`paper`]: the paper's rule over a
//! window of `Np` points; [`noise`]: the default mode's walk, with boundary [`refine`]ment.

pub(crate) mod arc;
pub(crate) mod noise;
pub(crate) mod paper;
pub(crate) mod refine;

use heapless::Vec;

use crate::pass::Pass;
use crate::rule::Rule;

/// Most neighbouring segment starts the default mode's walk notes for its check step.
pub(crate) const NEIGHBOURS: usize = 16;

/// Segment starts the default mode's walk set right after another one, in increasing order:
/// the only places where its check step can act. `None` when not known (the paper's mode, or
/// more than [`NEIGHBOURS`]): the check step then reads every flag.
pub(crate) type Neighbours = Option<Vec<u16, NEIGHBOURS>>;

/// Mark points under the configured rule (the paper's, or the default mode's walk); returns
/// what the walk noted for the check step. `uneven`: consecutive points are not one beam step
/// apart in bearing (interleaved sweeps taken from different poses, de-skewed or moved onto
/// sweep 0: a short and a long step in turn); the walk then measures each step rather than
/// assume the beam step.
#[inline(always)]
pub(crate) fn mark(pass: &mut Pass<'_>, rule: &Rule, uneven: bool) -> Neighbours {
    match rule {
        Rule::Paper(rule) => {
            paper::mark(pass, rule);
            None
        }
        Rule::Noise(rule) => noise::mark(pass, rule, uneven),
    }
}
