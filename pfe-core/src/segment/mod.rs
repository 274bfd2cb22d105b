//! Segments (§3.4): every mark point starts or ends a segment; a segment's last point is
//! paired with the next segment's first; segments of at least `min_points` points are typed
//! and fitted ([`crate::classify`]). In the default mode, neighbouring segments (no gap, no
//! jump between them) that together are one arc are merged first: a small or distant pillar,
//! seen over a few beams at growing incidence, can fail the line prediction every few points
//! before an arc window has formed. Runs of consecutive short segments (a distant wall at
//! grazing incidence, its points too far apart to predict one another) that together lie on
//! one line within the noise are joined into one segment. A segment typed a line that is a
//! pillar against a wall (no jump at its edges) is split around the pillar's arc.

mod arcs;
mod ends;
mod join;
mod own;
mod split;

use heapless::Vec;

use crate::arc::arc_fit;
use crate::classify;
use crate::config::Config;
use crate::feature::Feature;
use crate::fit::line::{fit_line, LineFit};
use crate::flags::{next_flag, Seek, END, JUMP, START};
use crate::math;
use crate::output::FeatureSink;
use crate::pass::Pass;
use crate::rule::{NoiseRule, Rule};
use crate::sift;

use join::{join_collinear, join_lines};
use split::{bump, corner};

/// Sizes of the union of two neighbouring segments tested for being one arc (fewer points do
/// not show an arc above the noise; a pillar of 0.3 m radius 0.8 m away covers 63 beams at
/// 0.5°, 127 at 0.25°).
const MERGE_SIZES: core::ops::RangeInclusive<usize> = 6..=128;

/// Fewest points of a run of short segments joined into one line.
const CHAIN_MIN: usize = 5;
/// Most points of a run of short segments tested at once.
const CHAIN_MAX: usize = 64;

/// Most joins of neighbouring collinear lines a scan.
const JOINS_MAX: usize = 8;
/// Points of segments searched for a pillar inside a line ([`bump`]) a scan, in scans' lengths:
/// the work it takes is bounded.
const PILLAR_SCANS: usize = 2;

/// Pairs the marks of `pass` into segments and emits the feature of each into `out`.
#[inline(never)]
pub(crate) fn segments(
    pass: &mut Pass<'_>,
    rule: &Rule,
    config: &Config,
    out: &mut dyn FeatureSink,
) {
    // Compiled once with and once without the checks for real scans: without, no check of
    // them is left in the per-segment path.
    if config.scrutinised() {
        segments_with::<true>(pass, rule, config, out);
    } else {
        segments_with::<false>(pass, rule, config, out);
    }
}

/// [`segments`] with the checks for real scans when `SCRUTINY`.
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
        joins: JOINS_MAX,
        pillars: PILLAR_SCANS * pass.len(),
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
            if SCRUTINY && pe + 1 == s && pass.flag(s) & JUMP == 0 {
                if let Some(t) = tail_arc(pass, ps, pe, e, rule, config) {
                    // The arc runs from the tail of the segment before into this one.
                    emitter.emit::<SCRUTINY>(pass, ps, pe - t, config, out);
                    pass.clear(s, START);
                    pending = Some((pe + 1 - t, e));
                    continue;
                }
            }
        }
        let mut s = s;
        if let Some((ps, mut pe)) = pending {
            if SCRUTINY && pe + 1 == s && pass.flag(s) & JUMP == 0 {
                // A corner beam counted into a short line is the neighbour's ([`own`]).
                if own::hands_over(pass, ps, pe, true, config) {
                    pass.clear(pe, END);
                    pass.clear(s, START);
                    (pe, s) = (pe - 1, pe);
                } else if own::hands_over(pass, s, e, false, config) {
                    pass.clear(pe, END);
                    pass.clear(s, START);
                    (pe, s) = (s, s + 1);
                }
            }
            emitter.emit::<SCRUTINY>(pass, ps, pe, config, out);
        }
        pending = Some((s, e));
    }
    if let Some((ps, pe)) = pending {
        emitter.emit::<SCRUTINY>(pass, ps, pe, config, out);
    }
    if let Some(rule) = emitter.join {
        emitter.flush(pass, config, out);
        arcs::join_arcs(pass, rule, config, out);
    }
}

/// Points at the end of a segment tried, longest first, for an arc that runs on into the next
/// segment ([`tail_arc`]).
const TAIL_RUNS: [usize; 2] = [16, 8];

/// How many of the last points of the segment `ps..=pe` make one arc with the next segment
/// `pe + 1..=e` (no range jump between them) when the two together do not, typed a circle: a
/// pillar in front of a wall whose arc the walk marked inside (the wall and the arc's first
/// points one segment, the rest the next, which ends at the pillar's far edge: a range jump or
/// no return). Both segments keep at least `min_points` points: the arc's piece in the next
/// segment is long enough for a feature of its own (a line that is no surface).
fn tail_arc(
    pass: &Pass<'_>,
    ps: usize,
    pe: usize,
    e: usize,
    rule: &NoiseRule,
    config: &Config,
) -> Option<usize> {
    let edge = e + 1 >= pass.len() || !pass.valid(e + 1) || pass.flag(e + 1) & JUMP != 0;
    if !edge || e < pe + config.min_points {
        return None;
    }
    TAIL_RUNS.iter().copied().find(|&t| {
        pe + 1 >= ps + t + config.min_points
            && MERGE_SIZES.contains(&(e + t - pe))
            && pass
                .points
                .get(pe + 1 - t..e + 1)
                .and_then(|pts| arc_fit(pts, rule))
                .is_some()
            && matches!(
                classify::feature::<true>(pass, pe + 1 - t, e, config),
                Some(Feature::Circle(_))
            )
    })
}

/// Emits segments in order, noting the last run of consecutive short ones (default mode) to
/// join what of it lies on one line.
struct Emitter<'r> {
    /// The run of short segments since the last long one: its first and last point.
    chain: Option<(usize, usize)>,
    /// The default mode's rule (`None`: nothing is joined).
    join: Option<&'r NoiseRule>,
    /// Joins of neighbouring collinear lines left for this scan ([`join_collinear`]).
    joins: usize,
    /// Points left for this scan to search for a pillar inside a line ([`bump`]).
    pillars: usize,
}

impl<'r> Emitter<'r> {
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
            emit::<SCRUTINY>(pass, s, e, self.arc(), config, out);
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
        emit::<SCRUTINY>(pass, s, e, self.arc(), config, out);
        if let Some(rule) = self.join {
            join_collinear(pass, rule, config, out, &mut self.joins);
        }
    }

    /// The rule of the arc test that finds a pillar inside a segment typed a line, and the
    /// points left for this scan to search.
    fn arc(&mut self) -> Option<(&'r NoiseRule, &mut usize)> {
        self.join
            .and_then(arc_rule)
            .map(|rule| (rule, &mut self.pillars))
    }

    /// Joins the parts of at least [`CHAIN_MIN`] points of the noted run that lie on one line
    /// into one segment each (its short segments were emitted already: undone here).
    fn flush(&mut self, pass: &mut Pass<'_>, config: &Config, out: &mut dyn FeatureSink) {
        match (self.chain.take(), self.join) {
            (Some((cs, ce)), Some(rule)) if ce + 1 - cs >= CHAIN_MIN => {
                join_lines(pass, (cs, ce), rule, config, out, &mut self.joins);
            }
            _ => {}
        }
    }
}

/// `rule` when its arc window lets it test arcs (the default mode's).
fn arc_rule(rule: &NoiseRule) -> Option<&NoiseRule> {
    (rule.model.arc_window >= 5).then_some(rule)
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
    mut arc: Option<(&NoiseRule, &mut usize)>,
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
            store(pass, &f, out);
        } else {
            pass.stats.degenerate += 1;
        }
        return;
    }
    let mut todo: Vec<(usize, usize), PIECES> = Vec::new();
    let _ = todo.push((s, e));
    // The arc piece of a split around a pillar, typed already.
    let mut known: Option<(usize, usize, Option<Option<Feature>>)> = None;
    while let Some((s, e)) = todo.pop() {
        let (feature, fitted) = match known.take() {
            Some((ks, ke, f)) if (ks, ke) == (s, e) => (f, None),
            other => {
                known = other;
                typed_and_line(pass, s, e, config)
            }
        };
        let n = e + 1 - s;
        // The segment's plain line fit (the typing's), which the pillar and the corner search
        // share.
        let line = if todo.len() + 2 <= PIECES && matches!(feature, Some(Some(Feature::Line(_)))) {
            fitted.or_else(|| pass.points.get(s..=e).and_then(|p| fit_line(p).ok()))
        } else {
            None
        };
        if todo.len() + 3 <= PIECES
            && matches!(feature, Some(Some(Feature::Line(_))))
            && n > *MERGE_SIZES.start()
            && arc.as_ref().is_some_and(|a| *a.1 >= n)
        {
            if let Some(a) = arc.as_mut() {
                *a.1 -= n;
            }
            let pillar = arc
                .as_ref()
                .and_then(|a| bump(pass.points.get(s..=e)?, line.as_ref()?, a.0, config))
                .map(|(i, j)| (i, j, typed::<true>(pass, s + i, s + j, config)));
            if let Some((i, j, f)) =
                pillar.filter(|p| matches!(p.2, Some(Some(Feature::Circle(_)))))
            {
                // The line's pieces either side of the arc (when any), last first.
                if s + j < e {
                    let _ = todo.push((s + j + 1, e));
                }
                let _ = todo.push((s + i, s + j));
                if i > 0 {
                    let _ = todo.push((s, s + i - 1));
                }
                known = Some((s + i, s + j, f));
                continue;
            }
        }
        if let Some(line) = line {
            if let Some(k) = pass
                .points
                .get(s..=e)
                .and_then(|pts| corner(pts, &line, config))
            {
                // Second piece first: the first is emitted first.
                let _ = todo.push((s + k, e));
                let _ = todo.push((s, s + k - 1));
                continue;
            }
        }
        // The features by reference: each is copied once, into the sink.
        let object = match feature {
            Some(Some(Feature::Line(_))) => curved_object(pass, s, e, config),
            _ => None,
        };
        let feature = if object.is_some() { &object } else { &feature };
        match visible_part(pass, s, e, feature.as_ref(), config) {
            Some((a, b, line)) => place_visible(pass, s, e, (a, b), line, config, out),
            None => place(pass, s, e, feature, out),
        }
    }
}

/// For a line seen at more than 85° incidence at its midpoint (a wall running away from the
/// scanner, [`sift`]), the part of its segment from its near end that the scanner sees as a
/// surface (the longest whose midpoint is within 85°: `a..=b`) and that part's line, when it
/// is one the sift step reports.
fn visible_part(
    pass: &Pass<'_>,
    s: usize,
    e: usize,
    feature: Option<&Option<Feature>>,
    config: &Config,
) -> Option<(usize, usize, Feature)> {
    let Some(Some(Feature::Line(l))) = feature else {
        return None;
    };
    if sift::seen(l) {
        return None;
    }
    // Position along the line: |t| ≤ ρ·tan 85° is within 85° of the line's normal.
    let (sin, cos) = math::sin_cos(l.alpha);
    let along = |i: usize| {
        let p = pass.point(i);
        cos * p.y - sin * p.x
    };
    let reach = math::abs(l.rho) * sift::TAN_MAX_INCIDENCE;
    let (ts, te) = (along(s), along(e));
    let (a, b) = if math::abs(ts) <= math::abs(te) {
        let b = (s..=e)
            .rev()
            .find(|&k| pass.valid(k) && math::abs(ts + along(k)) <= 2.0 * reach)?;
        (s, b)
    } else {
        let a = (s..=e).find(|&k| pass.valid(k) && math::abs(te + along(k)) <= 2.0 * reach)?;
        (a, e)
    };
    if (a, b) == (s, e) {
        return None;
    }
    match typed::<true>(pass, a, b, config) {
        Some(Some(f @ Feature::Line(_))) if sift::unreported(pass, &f).is_none() => Some((a, b, f)),
        _ => None,
    }
}

/// Places the segment `s..=e` as the line `line` over its visible part `a..=b` and what lies
/// beyond it as a segment without a feature (a wall's far part, seen at more than 85°).
fn place_visible(
    pass: &mut Pass<'_>,
    s: usize,
    e: usize,
    (a, b): (usize, usize),
    line: Feature,
    config: &Config,
    out: &mut dyn FeatureSink,
) {
    let rest = if a > s { (s, a - 1) } else { (b + 1, e) };
    let short = (rest.1 + 1 - rest.0 < config.min_points).then_some(());
    let (rest, line) = (
        (rest.0, rest.1, short.map_or(Some(None), |()| None)),
        (a, b, Some(Some(line))),
    );
    let (first, second) = if a > s {
        (&rest, &line)
    } else {
        (&line, &rest)
    };
    place(pass, first.0, first.1, &first.2, out);
    place(pass, second.0, second.1, &second.2, out);
}

/// Most points of a curved run set apart on one side only that is an object: over more
/// beams, a curved surface shows enough of itself for a circle or lines, and the middle of
/// its points moves with the viewpoint (a pillar beside the scanner seen in two halves).
const ONE_SIDED_MAX_POINTS: usize = 8;

/// The small object of the segment `s..=e` typed a line, when its points are curved
/// ([`classify::curved`]), at most `sift::OBJECT_MAX_MM` across and set apart from its
/// neighbours by a range jump or no return on both sides ([`sift::isolated`]), or on one side
/// when it has at most [`ONE_SIDED_MAX_POINTS`] points ([`sift::detached`]): a pillar or a leg
/// seen over too few beams for a circle is no line, also when it stands in front of a wall
/// or is partly hidden.
fn curved_object(pass: &Pass<'_>, s: usize, e: usize, config: &Config) -> Option<Option<Feature>> {
    let pts = pass.points.get(s..=e)?;
    let (a, b) = (pts.first()?, pts.last()?);
    if !(a.distance(b) <= sift::OBJECT_MAX_MM)
        || !(sift::isolated(pass, s, e)
            || (pts.len() <= ONE_SIDED_MAX_POINTS && sift::detached(pass, s, e)))
        || !classify::curved(pass, s, pts, config)
    {
        return None;
    }
    sift::object(pass, s, e, config).map(|o| Some(Feature::Object(o)))
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

/// [`typed`] with the checks for real scans, and the line fit of the segment's points when it
/// was typed (`None` when short or when the fit failed).
fn typed_and_line(
    pass: &Pass<'_>,
    s: usize,
    e: usize,
    config: &Config,
) -> (Option<Option<Feature>>, Option<LineFit>) {
    if e + 1 - s >= config.min_points {
        let (f, line) = classify::feature_and_line::<true>(pass, s, e, config);
        (Some(f), line)
    } else {
        (None, None)
    }
}

/// Marks the segment `s..=e` and stores its feature, counting what happened.
fn place(
    pass: &mut Pass<'_>,
    s: usize,
    e: usize,
    feature: &Option<Option<Feature>>,
    out: &mut dyn FeatureSink,
) {
    pass.set(s, START);
    pass.set(e, END);
    pass.stats.segments += 1;
    match feature {
        None => pass.stats.short_segments += 1,
        Some(Some(f)) => store_making_room(pass, f, out),
        Some(None) => pass.stats.degenerate += 1,
    }
}

/// Stores `f` as [`store`] does; when there is no room, the stored lines the sift step will
/// not report (the scanner cannot have seen them) give up their room first, so that the
/// capacity holds features that are reported.
fn store_making_room(pass: &mut Pass<'_>, f: &Feature, out: &mut dyn FeatureSink) {
    if out.push_copy(f) {
        pass.stats.features += 1;
        return;
    }
    // Once a full sink held no such line, none has come in since: nothing was stored.
    if pass.stats.dropped == 0 {
        let mut freed = false;
        for g in out.features_mut().iter() {
            if let Some(l) = sift::unreported(pass, g) {
                sift::free(pass, &l);
                freed = true;
            }
        }
        if freed {
            let pass = &*pass;
            out.retain(&mut |g| sift::unreported(pass, g).is_none());
        }
    }
    store(pass, f, out);
}

/// Stores `f`, counting it as stored or dropped.
#[inline(always)]
fn store(pass: &mut Pass<'_>, f: &Feature, out: &mut dyn FeatureSink) {
    if out.push_copy(f) {
        pass.stats.features += 1;
    } else {
        pass.stats.dropped += 1;
    }
}

// The f64 references need libm (the default feature).
#[cfg(test)]
#[cfg(feature = "libm")]
mod tests;

#[cfg(test)]
#[cfg(feature = "libm")]
mod beside_tests;

#[cfg(test)]
mod pieces_tests;

#[cfg(test)]
mod emitted;
