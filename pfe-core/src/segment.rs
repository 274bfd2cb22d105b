//! Segments (§3.4): every mark point starts or ends a segment; a segment's last point is
//! paired with the next segment's first; segments of at least `min_points` points are typed
//! and fitted ([`crate::classify`]). In the default mode, neighbouring segments (no gap, no
//! jump between them) that together are one arc are merged first: a small or distant pillar,
//! seen over a few beams at growing incidence, can fail the line prediction every few points
//! before an arc window has formed.

use crate::classify::{self, arc::arc_fit};
use crate::config::Config;
use crate::extractor::FeatureSink;
use crate::flags::{next_flag, Seek, END, JUMP, START};
use crate::mark::Rule;
use crate::pass::Pass;

/// Sizes of the union of two neighbouring segments tested for being one arc (fewer points do
/// not show an arc above the noise).
const MERGE_SIZES: core::ops::RangeInclusive<usize> = 6..=64;

/// Pairs the marks of `pass` into segments and emits the feature of each into `out`.
pub(crate) fn segments(
    pass: &mut Pass<'_>,
    rule: &Rule,
    config: &Config,
    out: &mut dyn FeatureSink,
) {
    let merge = rule.noise().filter(|n| n.model.arc_window >= 5);
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
            emit(pass, ps, pe, config, out);
        }
        pending = Some((s, e));
    }
    if let Some((ps, pe)) = pending {
        emit(pass, ps, pe, config, out);
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
