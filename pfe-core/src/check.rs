//! The check step (§3.3): wherever `Np` mark points follow each other, predict the next point
//! from them; when it fits, the marks after the first were caused by a window straddling the
//! boundary and are removed. Runs of 2..Np marks (a straddling window can fit by chance, e.g.
//! when the boundary point lies on both surfaces, as at a corner) get the same test with the
//! run's own points as the window; a run longer than `Np` is tested at its last `Np` points, so
//! its first marks stay. Runs at the end of a valid stretch are left alone.

use crate::config::NP;
use crate::flags::{next_flag, Seek, START};
use crate::mark::Rule;
use crate::pass::Pass;

/// Applies the check step to the marks of `pass`.
pub(crate) fn check(pass: &mut Pass<'_>, rule: &Rule) {
    match pass.neighbours.take() {
        // The default mode's walk noted every start next to another (in increasing order):
        // the runs of marks are where they are.
        Some(list) => {
            let mut done = 0usize;
            for i in list.iter().map(|&i| usize::from(i)) {
                if i < done || pass.flag(i) & Seek::MARK != Seek::MARK {
                    continue;
                }
                let mut j = i;
                while j > done && pass.flag(j - 1) & Seek::MARK == Seek::MARK {
                    j -= 1;
                }
                done = check_run(pass, j, rule);
            }
        }
        None => {
            let mut j = 0usize;
            while let Some(start) = next_flag(pass.flags, j, Seek::Mark) {
                j = check_run(pass, start, rule);
            }
        }
    }
}

/// The check step for the run of marks starting at `j`; returns the point after it.
#[inline(always)]
fn check_run(pass: &mut Pass<'_>, j: usize, rule: &Rule) -> usize {
    let len = pass.len();
    let next = next_flag(pass.flags, j + 1, Seek::NotMark).unwrap_or(len);
    let e = next - 1;
    if e > j && next < len && pass.valid(next) {
        let from = (e + 1).saturating_sub(NP).max(j);
        let pred = pass.predict_next(from, next);
        if !rule.marks(pred, pass.range(next)) {
            for i in from + 1..next {
                pass.clear(i, START);
            }
        }
    }
    next
}
