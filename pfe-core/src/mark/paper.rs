//! The paper's marking (§3.2): every point with `Np` valid predecessors is predicted from
//! them; the first point after a gap (or at the start) opens a segment.

use crate::config::NP;
use crate::flags::START;
use crate::pass::Pass;
use crate::rule::PaperRule;

/// Marks the points of `pass` under the paper's threshold.
pub(crate) fn mark(pass: &mut Pass<'_>, rule: &PaperRule) {
    let mut run = 0usize;
    for k in 0..pass.len() {
        if !pass.valid(k) {
            run = 0;
            continue;
        }
        if run == 0 {
            pass.set(k, START);
        } else if run >= NP {
            let mark = match pass.predict_next(k - NP, k) {
                None => true,
                Some(p) => rule.marks(&p, pass.range(k)),
            };
            if mark {
                pass.set(k, START);
            }
        }
        run += 1;
    }
}
