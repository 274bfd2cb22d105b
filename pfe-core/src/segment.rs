//! Segments (§3.4): every mark point starts or ends a segment; a segment's last point is
//! paired with the next segment's first; segments of at least `min_points` points are typed
//! and fitted ([`crate::classify`]). In the default mode, neighbouring segments (no gap, no
//! jump between them) that together are one arc are merged first: a small or distant pillar,
//! seen over a few beams at growing incidence, can fail the line prediction every few points
//! before an arc window has formed. Runs of consecutive short segments (a distant wall at
//! grazing incidence, its points too far apart to predict one another) that together lie on
//! one line within the noise are joined into one segment.

use crate::classify::{self, arc::arc_fit};
use crate::config::Config;
use crate::extractor::FeatureSink;
use crate::fit::run::{line_prefix, on_one_line};
use crate::flags::{next_flag, Seek, END, JUMP, START};
use crate::mark::{NoiseRule, Rule};
use crate::pass::Pass;

/// Sizes of the union of two neighbouring segments tested for being one arc (fewer points do
/// not show an arc above the noise).
const MERGE_SIZES: core::ops::RangeInclusive<usize> = 6..=64;

/// Fewest points of a run of short segments joined into one line.
const CHAIN_MIN: usize = 5;
/// Most points of a run of short segments tested at once.
const CHAIN_MAX: usize = 64;

/// Pairs the marks of `pass` into segments and emits the feature of each into `out`.
pub(crate) fn segments(
    pass: &mut Pass<'_>,
    rule: &Rule,
    config: &Config,
    out: &mut dyn FeatureSink,
) {
    let merge = rule.noise().filter(|n| n.model.arc_window >= 5);
    let mut emitter = Emitter {
        chain: None,
        join: rule.noise(),
    };
    let len = pass.len();
    let mut pending: Option<(usize, usize)> = None;
    let mut k = 0usize;
    while let Some(s) = next_flag(pass.flags, k, Seek::Valid) {
        // The segment runs to the next start or invalid point.
        k = next_flag(pass.flags, s + 1, Seek::SegmentEnd).unwrap_or(len);
        let e = k - 1;
        if let (Some((ps, pe)), Some(rule)) = (pending, merge) {
            if pe + 1 == s
                && pass.flag(s) & JUMP == 0
                && MERGE_SIZES.contains(&(e + 1 - ps))
                && pass
                    .points
                    .get(ps..e + 1)
                    .and_then(|pts| arc_fit(pts, rule))
                    .is_some()
            {
                pass.clear(s, START);
                pending = Some((ps, e));
                continue;
            }
        }
        if let Some((ps, pe)) = pending {
            emitter.emit(pass, ps, pe, config, out);
        }
        pending = Some((s, e));
    }
    if let Some((ps, pe)) = pending {
        emitter.emit(pass, ps, pe, config, out);
    }
    emitter.flush(pass, config, out);
}

/// Emits segments in order, holding back a run of consecutive short ones (default mode) to
/// join what of it lies on one line.
struct Emitter<'r> {
    /// The run of short segments held back: its first and last point.
    chain: Option<(usize, usize)>,
    /// The default mode's rule (`None`: nothing is joined).
    join: Option<&'r NoiseRule>,
}

impl Emitter<'_> {
    /// Emits the segment `s..=e` after the held-back run, or holds it back too.
    fn emit(
        &mut self,
        pass: &mut Pass<'_>,
        s: usize,
        e: usize,
        config: &Config,
        out: &mut dyn FeatureSink,
    ) {
        if self.join.is_some() && e + 1 - s < config.min_points {
            match self.chain {
                Some((cs, ce)) if ce + 1 == s && e + 1 - cs <= CHAIN_MAX => {
                    self.chain = Some((cs, e));
                }
                _ => {
                    self.flush(pass, config, out);
                    self.chain = Some((s, e));
                }
            }
            return;
        }
        self.flush(pass, config, out);
        emit(pass, s, e, config, out);
    }

    /// Emits the held-back run: the parts of at least [`CHAIN_MIN`] points that lie on one
    /// line as one segment each, the rest as the short segments they were.
    fn flush(&mut self, pass: &mut Pass<'_>, config: &Config, out: &mut dyn FeatureSink) {
        let (Some((cs, ce)), Some(rule)) = (self.chain.take(), self.join) else {
            return;
        };
        let tol = rule.k_sigma + rule.model.floor;
        let var = rule.sigma_r * rule.sigma_r;
        let (mut a, mut done) = (cs, cs);
        while a + CHAIN_MIN <= ce + 1 {
            let pts = pass.points.get(a..=ce).unwrap_or(&[]);
            let n = line_prefix(pts, tol).max(1);
            let joined = n >= CHAIN_MIN && pts.get(..n).is_some_and(|p| on_one_line(p, tol, var));
            if joined {
                let b = a + n - 1;
                emit_marked(pass, done, a, config, out);
                for i in a + 1..=b {
                    pass.clear(i, START);
                }
                if b < ce {
                    pass.set(b + 1, START);
                }
                emit(pass, a, b, config, out);
                done = b + 1;
            }
            a += n;
        }
        emit_marked(pass, done, ce + 1, config, out);
    }
}

/// Emits the segments of `from..to` as their starts delimit them.
fn emit_marked(
    pass: &mut Pass<'_>,
    from: usize,
    to: usize,
    config: &Config,
    out: &mut dyn FeatureSink,
) {
    let mut s = from;
    while s < to {
        let e = next_flag(pass.flags, s + 1, Seek::SegmentEnd)
            .unwrap_or(to)
            .min(to);
        emit(pass, s, e - 1, config, out);
        s = e;
    }
}

/// Marks, types and fits (when long enough) the segment `s..=e`.
fn emit(pass: &mut Pass<'_>, s: usize, e: usize, config: &Config, out: &mut dyn FeatureSink) {
    pass.set(s, START);
    pass.set(e, END);
    pass.stats.segments += 1;
    if e + 1 - s >= config.min_points {
        match classify::feature(pass, s, e, config) {
            Some(f) => {
                if out.push(f) {
                    pass.stats.features += 1;
                } else {
                    pass.stats.dropped += 1;
                }
            }
            None => pass.stats.degenerate += 1,
        }
    } else {
        pass.stats.short_segments += 1;
    }
}
