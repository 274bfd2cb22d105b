//! Segments (§3.4): every mark point starts or ends a segment; a segment's last point is
//! paired with the next segment's first; segments of at least `min_points` points are typed
//! and fitted ([`crate::classify`]). In the default mode, neighbouring segments (no gap, no
//! jump between them) that together are one arc are merged first: a small or distant pillar,
//! seen over a few beams at growing incidence, can fail the line prediction every few points
//! before an arc window has formed. Runs of consecutive short segments (a distant wall at
//! grazing incidence, its points too far apart to predict one another) that together lie on
//! one line within the noise are joined into one segment.

use heapless::Vec;

use crate::classify::{self, arc::arc_fit};
use crate::config::{Config, Typing};
use crate::extractor::FeatureSink;
use crate::feature::Feature;
use crate::fit::line::fit_line;
use crate::fit::run::{corner_split, line_prefix, on_one_line};
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
    // Compiled once with and once without `Config::scrutiny`: without, no check of it is left
    // in the per-segment path.
    if config.scrutiny {
        segments_with::<true>(pass, rule, config, out);
    } else {
        segments_with::<false>(pass, rule, config, out);
    }
}

/// [`segments`] with `Config::scrutiny == SCRUTINY`.
fn segments_with<const SCRUTINY: bool>(
    pass: &mut Pass<'_>,
    rule: &Rule,
    config: &Config,
    out: &mut dyn FeatureSink,
) {
    let merge = rule.noise().filter(|n| n.model.arc_window >= 5);
    let mut emitter = Emitter {
        chain: None,
        join: rule.noise().filter(|_| SCRUTINY),
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
            emitter.emit::<SCRUTINY>(pass, ps, pe, config, out);
        }
        pending = Some((s, e));
    }
    if let Some((ps, pe)) = pending {
        emitter.emit::<SCRUTINY>(pass, ps, pe, config, out);
    }
    if emitter.join.is_some() {
        emitter.flush(pass, config, out);
    }
}

/// Emits segments in order, noting the last run of consecutive short ones (default mode) to
/// join what of it lies on one line.
struct Emitter<'r> {
    /// The run of short segments since the last long one: its first and last point.
    chain: Option<(usize, usize)>,
    /// The default mode's rule (`None`: nothing is joined).
    join: Option<&'r NoiseRule>,
}

impl Emitter<'_> {
    /// Emits the segment `s..=e`, after joining the run of short segments before it when it is
    /// long.
    fn emit<const SCRUTINY: bool>(
        &mut self,
        pass: &mut Pass<'_>,
        s: usize,
        e: usize,
        config: &Config,
        out: &mut dyn FeatureSink,
    ) {
        if !SCRUTINY || self.join.is_none() {
            // Nothing is joined: the plain path.
            emit::<SCRUTINY>(pass, s, e, config, out);
            return;
        }
        if e + 1 - s < config.min_points {
            match self.chain {
                Some((cs, ce)) if ce + 1 == s && e + 1 - cs <= CHAIN_MAX => {
                    self.chain = Some((cs, e));
                }
                _ => {
                    self.flush(pass, config, out);
                    self.chain = Some((s, e));
                }
            }
        } else {
            self.flush(pass, config, out);
        }
        emit::<SCRUTINY>(pass, s, e, config, out);
    }

    /// Joins the parts of at least [`CHAIN_MIN`] points of the noted run that lie on one line
    /// into one segment each (its short segments were emitted already: undone here).
    fn flush(&mut self, pass: &mut Pass<'_>, config: &Config, out: &mut dyn FeatureSink) {
        match (self.chain.take(), self.join) {
            (Some((cs, ce)), Some(rule)) if ce + 1 - cs >= CHAIN_MIN => {
                join_lines(pass, (cs, ce), rule, config, out);
            }
            _ => {}
        }
    }
}

/// Joins the parts of the run `cs..=ce` of short segments that lie on one line.
#[inline(never)]
fn join_lines(
    pass: &mut Pass<'_>,
    (cs, ce): (usize, usize),
    rule: &NoiseRule,
    config: &Config,
    out: &mut dyn FeatureSink,
) {
    let tol = rule.k_sigma + rule.model.floor;
    let var = rule.sigma_r * rule.sigma_r;
    let mut a = cs;
    while a + CHAIN_MIN <= ce + 1 {
        let pts = pass.points.get(a..=ce).unwrap_or(&[]);
        let n = line_prefix(pts, tol).max(1);
        if n >= CHAIN_MIN && pts.get(..n).is_some_and(|p| on_one_line(p, tol, var)) {
            let b = a + n - 1;
            // Undo the short segments inside: a is the start of one or ends the one before.
            let mut undone = 0usize;
            for i in a..=b {
                undone += usize::from(pass.flag(i) & START != 0);
                pass.clear(i, START | END);
            }
            if a > cs {
                pass.set(a - 1, END);
            }
            let mut redone = 0usize;
            if b < ce && pass.flag(b + 1) & START == 0 {
                pass.set(b + 1, START);
                redone = 1;
            }
            let stats = &mut *pass.stats;
            stats.segments = (stats.segments + redone).saturating_sub(undone);
            stats.short_segments = (stats.short_segments + redone).saturating_sub(undone);
            emit::<true>(pass, a, b, config, out);
        }
        a += n;
    }
}
/// Most pieces waiting while a segment is split at corners the walk left unmarked.
const PIECES: usize = 8;

/// Marks, types and fits (when long enough) the segment `s..=e`. In the default mode a line
/// that two lines explain far better (a corner the walk did not mark, e.g. a rounded one it
/// followed as an arc) is split there first, each piece typed again.
fn emit<const SCRUTINY: bool>(
    pass: &mut Pass<'_>,
    s: usize,
    e: usize,
    config: &Config,
    out: &mut dyn FeatureSink,
) {
    if !SCRUTINY {
        // The board's path: typed and stored in place, no split.
        pass.set(s, START);
        pass.set(e, END);
        pass.stats.segments += 1;
        if e + 1 - s < config.min_points {
            pass.stats.short_segments += 1;
        } else if let Some(f) = classify::feature::<false>(pass, s, e, config) {
            store(pass, f, out);
        } else {
            pass.stats.degenerate += 1;
        }
        return;
    }
    let mut todo: Vec<(usize, usize), PIECES> = Vec::new();
    let _ = todo.push((s, e));
    while let Some((s, e)) = todo.pop() {
        let feature = typed::<true>(pass, s, e, config);
        if todo.len() + 2 <= PIECES && matches!(feature, Some(Some(Feature::Line(_)))) {
            if let Some(k) = corner(pass, s, e, config) {
                // Second piece first: the first is emitted first.
                let _ = todo.push((s + k, e));
                let _ = todo.push((s, s + k - 1));
                continue;
            }
        }
        place(pass, s, e, feature, out);
    }
}

/// The feature of the segment `s..=e`: `None` when it is short, `Some(None)` when its fit
/// failed.
fn typed<const SCRUTINY: bool>(
    pass: &Pass<'_>,
    s: usize,
    e: usize,
    config: &Config,
) -> Option<Option<Feature>> {
    (e + 1 - s >= config.min_points).then(|| classify::feature::<SCRUTINY>(pass, s, e, config))
}

/// Marks the segment `s..=e` and stores its feature, counting what happened.
fn place(
    pass: &mut Pass<'_>,
    s: usize,
    e: usize,
    feature: Option<Option<Feature>>,
    out: &mut dyn FeatureSink,
) {
    pass.set(s, START);
    pass.set(e, END);
    pass.stats.segments += 1;
    match feature {
        None => pass.stats.short_segments += 1,
        Some(Some(f)) => store(pass, f, out),
        Some(None) => pass.stats.degenerate += 1,
    }
}

/// Stores `f`, counting it as stored or dropped.
#[inline(always)]
fn store(pass: &mut Pass<'_>, f: Feature, out: &mut dyn FeatureSink) {
    if out.push(f) {
        pass.stats.features += 1;
    } else {
        pass.stats.dropped += 1;
    }
}

/// Where the line segment `s..=e` is two lines: the points of the first, when its residual sum
/// exceeds the noise's and the best split near its apex (both pieces of at least `min_points`)
/// lowers it by more than the typing's `chi2 · σ_r²` and below `ratio` times the line's (the
/// test a circle must pass against the line).
fn corner(pass: &Pass<'_>, s: usize, e: usize, config: &Config) -> Option<usize> {
    let Typing::CompareFits { chi2, ratio, .. } = config.typing else {
        return None;
    };
    let pts = pass.points.get(s..=e)?;
    let sse_l = fit_line(pts).ok()?.sse();
    let var = config.sigma_r * config.sigma_r;
    // A line within the noise (at most σ_r² a degree of freedom) is not split.
    if !(sse_l > var * (pts.len() as f32 - 2.0) && sse_l > chi2 * var) {
        return None;
    }
    let (k, sse_2) = corner_split(pts)?;
    let long = k >= config.min_points && pts.len() - k >= config.min_points;
    (long && sse_l - sse_2 > chi2 * var && sse_2 < ratio * sse_l).then_some(k)
}
