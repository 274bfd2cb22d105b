//! Segments (§3.4): every mark point starts or ends a segment; a segment's last point is
//! paired with the next segment's first; segments of at least `min_points` points are typed
//! and fitted ([`crate::classify`]). In the default mode, neighbouring segments (no gap, no
//! jump between them) that together are one arc are merged first: a small or distant pillar,
//! seen over a few beams at growing incidence, can fail the line prediction every few points
//! before an arc window has formed. Runs of consecutive short segments (a distant wall at
//! grazing incidence, its points too far apart to predict one another) that together lie on
//! one line within the noise are joined into one segment. A segment typed a line that is a
//! pillar against a wall (no jump at its edges) is split around the pillar's arc.

use heapless::Vec;

use crate::arc::arc_fit;
use crate::classify;
use crate::config::{Config, Typing};
use crate::feature::{Feature, LineFeature};
use crate::fit::circle::Circle;
use crate::fit::line::{fit_line, LineFit};
use crate::fit::run::{corner_split, line_prefix, on_one_line};
use crate::flags::{next_flag, Seek, END, JUMP, START};
use crate::geometry::Point;
use crate::math;
use crate::output::FeatureSink;
use crate::pass::Pass;
use crate::rule::{NoiseRule, Rule};
use crate::sift;

/// Sizes of the union of two neighbouring segments tested for being one arc (fewer points do
/// not show an arc above the noise; a pillar of 0.3 m radius 0.8 m away covers 63 beams at
/// 0.5°, 127 at 0.25°).
const MERGE_SIZES: core::ops::RangeInclusive<usize> = 6..=128;

/// Fewest points of a run of short segments joined into one line.
const CHAIN_MIN: usize = 5;
/// Most points of a run of short segments tested at once.
const CHAIN_MAX: usize = 64;

/// cos 0.2 rad: neighbouring lines whose normals differ more are not tested for being one.
const COS_JOIN: f32 = 0.980_066_6;
/// 99 % of χ²₂: two lines' parameters further apart than this are two lines.
const SAME_LINE_CHI2: f32 = 9.21;
/// Most joins of neighbouring collinear lines a scan.
const JOINS_MAX: usize = 8;
/// Points of segments searched for a pillar inside a line ([`bump`]) a scan, in scans' lengths:
/// the work it takes is bounded.
const PILLAR_SCANS: usize = 2;
/// Most points of a line joined from two.
const JOIN_MAX_POINTS: usize = 400;

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

/// Joins the parts of the run `cs..=ce` of short segments that lie on one line.
#[inline(never)]
fn join_lines(
    pass: &mut Pass<'_>,
    (cs, ce): (usize, usize),
    rule: &NoiseRule,
    config: &Config,
    out: &mut dyn FeatureSink,
    joins: &mut usize,
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
            emit::<true>(pass, a, b, None, config, out);
            join_collinear(pass, rule, config, out, joins);
        }
        a += n;
    }
}
/// Makes the last two features in `out` one line when they are lines of neighbouring segments
/// (no beam between) whose points together lie on one line within the noise: a wall whose
/// far, grazing part the walk cut off (its points grow apart faster than the prediction
/// allows), or a wall split where its roughness fooled the walk once.
/// At most [`JOINS_MAX`] joins a scan, each of at most [`JOIN_MAX_POINTS`] points: the work
/// they take is bounded.
#[inline(never)]
fn join_collinear(
    pass: &mut Pass<'_>,
    rule: &NoiseRule,
    config: &Config,
    out: &mut dyn FeatureSink,
    joins: &mut usize,
) {
    if *joins == 0 {
        return;
    }
    let n = out.features_mut().len();
    let Some([Feature::Line(a), Feature::Line(b)]) = n
        .checked_sub(2)
        .and_then(|k| out.features_mut().get(k..))
        .and_then(|last| <&[Feature; 2]>::try_from(last).ok())
        .copied()
    else {
        return;
    };
    let (s, e) = (usize::from(a.first), usize::from(b.last));
    // Neighbours, also across a range jump: at grazing incidence a wall's points are far apart.
    if usize::from(a.last) + 1 != usize::from(b.first) || e + 1 - s > JOIN_MAX_POINTS {
        return;
    }
    // Cheap first: the normals within 0.2 rad of each other (or of the other's opposite: one
    // line through the scanner's side has ρ near 0 and either normal).
    let (sa, ca) = math::sin_cos(a.alpha);
    let (sb, cb) = math::sin_cos(b.alpha);
    if !(math::abs(ca * cb + sa * sb) > COS_JOIN) {
        return;
    }
    // The same line within both fits' stated uncertainty (99 % of χ²₂), and their points on one
    // line within the noise.
    if !(same_line(&a, &b) <= SAME_LINE_CHI2) {
        return;
    }
    let tol = rule.k_sigma + rule.model.floor;
    let var = rule.sigma_r * rule.sigma_r;
    if !pass
        .points
        .get(s..=e)
        .is_some_and(|p| on_one_line(p, tol, var))
    {
        return;
    }
    *joins -= 1;
    let mut k = 0usize;
    out.retain(&mut |_| {
        k += 1;
        k + 2 <= n
    });
    pass.clear(usize::from(a.last), END);
    pass.clear(usize::from(b.first), START);
    let stats = &mut *pass.stats;
    stats.segments = stats.segments.saturating_sub(2);
    stats.features = stats.features.saturating_sub(2);
    emit::<true>(pass, s, e, None, config, out);
}

/// The NIS of the difference of the lines `a` and `b` (both in the scanner's frame, ρ ≥ 0),
/// with the sum of their covariances; NaN when it has none.
fn same_line(a: &LineFeature, b: &LineFeature) -> f32 {
    let mut da = a.alpha - b.alpha;
    if da > core::f32::consts::PI {
        da -= 2.0 * core::f32::consts::PI;
    } else if da < -core::f32::consts::PI {
        da += 2.0 * core::f32::consts::PI;
    }
    let dr = a.rho - b.rho;
    let (saa, srr, sar) = (
        a.var_alpha + b.var_alpha,
        a.var_rho + b.var_rho,
        a.cov_alpha_rho + b.cov_alpha_rho,
    );
    let det = saa * srr - sar * sar;
    if !(det > 0.0) {
        return f32::NAN;
    }
    (srr * da * da - 2.0 * sar * da * dr + saa * dr * dr) / det
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
            store(pass, f, out);
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
        let feature = match known.take() {
            Some((ks, ke, f)) if (ks, ke) == (s, e) => f,
            other => {
                known = other;
                typed::<true>(pass, s, e, config)
            }
        };
        let n = e + 1 - s;
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
                .and_then(|a| bump(pass.points.get(s..=e)?, a.0, config))
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
        if todo.len() + 2 <= PIECES && matches!(feature, Some(Some(Feature::Line(_)))) {
            if let Some(k) = pass.points.get(s..=e).and_then(|pts| corner(pts, config)) {
                // Second piece first: the first is emitted first.
                let _ = todo.push((s + k, e));
                let _ = todo.push((s, s + k - 1));
                continue;
            }
        }
        let feature = match feature {
            Some(Some(Feature::Line(_))) => curved_object(pass, s, e, config).or(feature),
            _ => feature,
        };
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
    let (first, second) = if a > s {
        (
            (rest.0, rest.1, short.map_or(Some(None), |()| None)),
            (a, b, Some(Some(line))),
        )
    } else {
        (
            (a, b, Some(Some(line))),
            (rest.0, rest.1, short.map_or(Some(None), |()| None)),
        )
    };
    place(pass, first.0, first.1, first.2, out);
    place(pass, second.0, second.1, second.2, out);
}

/// The small object of the segment `s..=e` typed a line, when its points are curved
/// ([`classify::curved`]) and it is one as the sift step defines them (at most
/// `sift::OBJECT_MAX_MM` across, a range jump or no return on both sides): a pillar or a leg
/// seen over too few beams for a circle is no line.
fn curved_object(pass: &Pass<'_>, s: usize, e: usize, config: &Config) -> Option<Option<Feature>> {
    let pts = pass.points.get(s..=e)?;
    let (a, b) = (pts.first()?, pts.last()?);
    if !(a.distance(b) <= sift::OBJECT_MAX_MM)
        || !sift::isolated(pass, s, e)
        || !classify::curved(pts, config)
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
        Some(Some(f)) => store_making_room(pass, f, out),
        Some(None) => pass.stats.degenerate += 1,
    }
}

/// Stores `f` as [`store`] does; when there is no room, the stored lines the sift step will
/// not report (the scanner cannot have seen them) give up their room first, so that the
/// capacity holds features that are reported.
fn store_making_room(pass: &mut Pass<'_>, f: Feature, out: &mut dyn FeatureSink) {
    if out.push(f) {
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
fn store(pass: &mut Pass<'_>, f: Feature, out: &mut dyn FeatureSink) {
    if out.push(f) {
        pass.stats.features += 1;
    } else {
        pass.stats.dropped += 1;
    }
}

/// Where the line segment `pts` is two lines: the points of the first, when its residual sum
/// exceeds the noise's and the best split near its apex (both pieces of at least `min_points`)
/// lowers it by more than the typing's `chi2 · σ_r²` and below `ratio` times the line's (the
/// test a circle must pass against the line).
fn corner(pts: &[Point], config: &Config) -> Option<usize> {
    let Typing::CompareFits { chi2, ratio, .. } = config.typing else {
        return None;
    };
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

/// Residual (in σ_r) a point must exceed to start the bump an arc makes on a line's fit.
const BUMP_SIGMAS: f32 = 2.0;
/// Times the line under a bump is fitted again without it.
const BUMP_ROUNDS: usize = 3;
/// Residual (in σ_r) to the bump's circle within which neighbouring points join the arc.
const BUMP_GROW_SIGMAS: f32 = 3.0;

/// An arc inside the segment `pts` typed a line whose fit is far beyond the noise (a pillar
/// against a wall, its edges meeting the wall without a range jump, that the walk followed
/// and no single corner explains): its first and last index in `pts`, a strict part of them.
/// The arc is the run of same-side residuals around the largest one ([`peak`]) or a side of
/// the best two-line split, grown while the next point lies on its circle, and must face the
/// scanner ([`facing`]).
fn bump(pts: &[Point], rule: &NoiseRule, config: &Config) -> Option<(usize, usize)> {
    let n = pts.len();
    // The arc of at least `MERGE_SIZES.start()` points and some line beside it.
    if n <= *MERGE_SIZES.start() {
        return None;
    }
    let line = fit_line(pts).ok()?;
    let var = config.sigma_r * config.sigma_r;
    if !(line.sse() > var * (n as f32 - 2.0) && line.sse() > rule.model.arc_chi2 * var) {
        return None;
    }
    let arc_of = |(i, j): (usize, usize)| arc_fit(pts.get(i..=j)?, rule).map(|c| (i, j, c));
    let peak = peak(pts, line, config)?;
    let (mut i, mut j, circle) = arc_of(peak).or_else(|| {
        // An arc at an end of the segment that the peak misses is one side of its best
        // two-line split.
        if peak.0 > 0 && peak.1 + 1 < n {
            return None;
        }
        let (k, _) = corner_split(pts)?;
        arc_of((0, k.checked_sub(1)?)).or_else(|| arc_of((k, n - 1)))
    })?;
    let on = |k: usize| {
        pts.get(k).is_some_and(|p| {
            math::abs(p.distance(&circle.center) - circle.radius)
                <= BUMP_GROW_SIGMAS * config.sigma_r
        })
    };
    while i > 0 && on(i - 1) {
        i -= 1;
    }
    while j + 1 < n && on(j + 1) {
        j += 1;
    }
    (j + 1 - i >= *MERGE_SIZES.start()
        && (i > 0 || j + 1 < n)
        && arc_fit(pts.get(i..=j)?, rule)
            .is_some_and(|c| facing(pts.get(i..=j).unwrap_or(&[]), &c)))
    .then_some((i, j))
}

/// Whether the arc of `pts` on `circle` faces the scanner (its centre beyond the points, as a
/// pillar's): the inside of a rounded corner is no pillar.
fn facing(pts: &[Point], circle: &Circle) -> bool {
    pts.get(pts.len() / 2)
        .is_some_and(|m| math::hypot(circle.center.x, circle.center.y) > math::hypot(m.x, m.y))
}

/// The run of same-side residuals beyond [`BUMP_SIGMAS`] σ_r around the largest residual of
/// `pts` from `line`, the line fitted again without it from the far half of its longer side
/// (the wall a pillar stands against).
fn peak(pts: &[Point], mut line: LineFit, config: &Config) -> Option<(usize, usize)> {
    let n = pts.len();
    let (mut i, mut j) = (0usize, 0usize);
    for _ in 0..BUMP_ROUNDS {
        let d = |k: usize| pts.get(k).map_or(0.0, |p| line.signed_distance(p));
        let (mut m, mut dm) = (0usize, 0.0f32);
        for k in 0..n {
            if math::abs(d(k)) > math::abs(dm) {
                (m, dm) = (k, d(k));
            }
        }
        let far = |k: usize| d(k) * dm > 0.0 && math::abs(d(k)) > BUMP_SIGMAS * config.sigma_r;
        if !far(m) {
            return None;
        }
        (i, j) = (m, m);
        while i > 0 && far(i - 1) {
            i -= 1;
        }
        while j + 1 < n && far(j + 1) {
            j += 1;
        }
        // The far half of the longer side: clear of the rest of a pillar at an end.
        let rest = if i >= n - 1 - j {
            pts.get(..i / 2)
        } else {
            pts.get((j + 1 + n) / 2..)
        };
        match rest.filter(|r| r.len() >= config.min_points).map(fit_line) {
            Some(Ok(l)) => line = l,
            _ => break,
        }
    }
    Some((i, j))
}

// The f64 references need libm (the default feature).
#[cfg(test)]
#[cfg(feature = "libm")]
#[allow(clippy::indexing_slicing)]
mod tests {
    use super::*;

    /// A V of `n` points (apex at index `m`, legs ±`slope` mm a point) with `zig` mm added to
    /// and taken from every other point, and its residual sums in f64: one line, and the best
    /// two lines over every split (runs of ≥ 4).
    fn v(n: usize, m: usize, slope: f64, zig: f64) -> (Vec<Point, 64>, f64, f64) {
        let mut pts = [(0.0f64, 0.0f64); 64];
        for (i, q) in pts.iter_mut().enumerate().take(n) {
            let t = i as f64 - m as f64;
            let z = if i % 2 == 0 { zig } else { -zig };
            *q = (100.0 * t, slope * if t < 0.0 { -t } else { t } + z);
        }
        let pts = &pts[..n];
        let sse = |p: &[(f64, f64)]| {
            let k = p.len() as f64;
            let (mx, my) = p
                .iter()
                .fold((0.0, 0.0), |a, q| (a.0 + q.0 / k, a.1 + q.1 / k));
            let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
            for q in p {
                let (dx, dy) = (q.0 - mx, q.1 - my);
                sxx += dx * dx;
                syy += dy * dy;
                sxy += dx * dy;
            }
            let h = 0.5 * (sxx - syy);
            0.5 * (sxx + syy) - libm::sqrt(h * h + sxy * sxy)
        };
        let two = (4..=n - 4)
            .map(|k| sse(&pts[..k]) + sse(&pts[k..]))
            .fold(f64::INFINITY, f64::min);
        let one = sse(pts);
        let out = pts
            .iter()
            .map(|q| Point::new(q.0 as f32, q.1 as f32))
            .collect();
        (out, one, two)
    }

    /// The default configuration with σ_r² = `var`.
    fn with_var(var: f64) -> Config {
        Config::default().with_sigma_r(libm::sqrt(var) as f32)
    }

    #[test]
    fn a_corner_splits_at_its_apex_when_two_lines_explain_it_far_better() {
        // An exact V: two lines leave nothing.
        let (pts, one, two) = v(16, 9, 20.0, 0.0);
        assert!(two < 1e-6 * one);
        // σ_r² = one/30: the line is beyond the noise (14 degrees of freedom) and the split
        // gains 30 σ_r² > chi2 25.
        assert_eq!(corner(&pts, &with_var(one / 30.0)), Some(9));
        // σ_r² = one/20: 20 σ_r² < 25, not split.
        assert_eq!(corner(&pts, &with_var(one / 20.0)), None);
        // The paper's typing never splits.
        let paper = Config::paper().with_sigma_r(libm::sqrt(one / 30.0) as f32);
        assert_eq!(corner(&pts, &paper), None);
    }

    #[test]
    fn the_gain_and_the_ratio_both_decide() {
        // A shallow V under a zig-zag: two lines keep the zig-zag. Find the zig-zag that leaves
        // 45 % of the line's residual sum to two lines (bisection in f64).
        let at = |target: f64| {
            let (mut lo, mut hi) = (0.0f64, 50.0f64);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                let (_, one, two) = v(20, 10, 10.0, mid);
                if two / one < target {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            v(20, 10, 10.0, lo)
        };
        let (pts, one, two) = at(0.45);
        assert!(libm::fabs(two / one - 0.45) < 0.01, "{}", two / one);
        // Gain 0.55·60 = 33 σ_r² > 25 and ratio 0.45 < 0.5: split (near the apex).
        let k = corner(&pts, &with_var(one / 60.0));
        assert!(k.is_some_and(|k| (9..=11).contains(&k)), "{k:?}");
        // Gain 0.55·40 = 22 σ_r² < 25: not split (the line is still beyond the noise: 40 > 18).
        assert_eq!(corner(&pts, &with_var(one / 40.0)), None);
        // Ratio 0.6 > 0.5 with a gain of 0.4·100 = 40 σ_r²: not split.
        let (pts, one, two) = at(0.6);
        assert!(libm::fabs(two / one - 0.6) < 0.01, "{}", two / one);
        assert_eq!(corner(&pts, &with_var(one / 100.0)), None);
    }

    #[test]
    fn a_line_within_the_noise_is_not_split() {
        // 60 points of a V whose line leaves 0.98 σ_r² a degree of freedom (58): within the
        // noise, though two lines would explain it all (gain 57 σ_r² > 25, ratio 0).
        let (pts, one, two) = v(60, 30, 2.0, 0.0);
        assert!(two < 1e-6 * one);
        assert_eq!(corner(&pts, &with_var(one / (0.98 * 58.0))), None);
        // 1.03 σ_r² a degree of freedom: split.
        assert_eq!(corner(&pts, &with_var(one / (1.03 * 58.0))), Some(30));
        // Runs of fewer than `min_points` are not cut off: the apex at index 2, or 13 of 16.
        for m in [2, 13] {
            let (pts, one, _) = v(16, m, 20.0, 0.0);
            assert_eq!(corner(&pts, &with_var(one / 30.0)), None, "apex {m}");
        }
        // At index 4 and 12 both runs have 4 points: split.
        for m in [4, 12] {
            let (pts, one, _) = v(16, m, 20.0, 0.0);
            let k = corner(&pts, &with_var(one / 30.0));
            assert!(k.is_some_and(|k| k == m || k == m + 1), "apex {m}: {k:?}");
        }
    }

    /// `join_lines` on a run of short segments whose middle lies on one line: posts at 5 and
    /// 9 m (beams 60–63 and 76–80, too far off any line), a wall x = 3 m (beams 64–75). Only
    /// the wall is joined, into one line over 64..=75; the short segments it cut get new ends
    /// (63, whose segment was 63..=64) and starts (76, whose segment was 75..=76); the counts
    /// lose the 11 short segments undone and gain the line and the remainder of 75..=76.
    #[test]
    fn a_chain_of_short_segments_is_joined_only_where_it_is_one_line() {
        use crate::extractor::Extractor;
        use crate::flags::{END, START, VALID};
        use crate::scan::{Scan, ScanGeometry};
        let mut g = ScanGeometry::lms200(180.0, 1.0);
        g.r_max = 50_000.0;
        let ranges: [f32; 181] = core::array::from_fn(|i| match i {
            60..=63 | 76..=80 => [5000.0, 9000.0][i % 2],
            64..=75 => 3000.0 / crate::math::sin_cos(g.bearing(i)).1,
            _ => f32::NAN,
        });
        let config = Config::default();
        // Short segments: 63..=64 and 75..=76, every other point of 60..=80 alone.
        let segments = [
            (60, 60),
            (61, 61),
            (62, 62),
            (63, 64),
            (65, 65),
            (66, 66),
            (67, 67),
            (68, 68),
            (69, 69),
            (70, 70),
            (71, 71),
            (72, 72),
            (73, 73),
            (74, 74),
            (75, 76),
            (77, 77),
            (78, 78),
            (79, 79),
            (80, 80),
        ];
        let mut ex = Extractor::<181, 8>::new();
        let scan = Scan::from_mm(g, &ranges);
        ex.with_pass(&scan, &config, |pass, rule| {
            for &(s, e) in &segments {
                pass.set(s, START);
                pass.set(e, END);
            }
            pass.stats.segments = segments.len();
            pass.stats.short_segments = segments.len();
            let mut out: Vec<Feature, 8> = Vec::new();
            let Some(noise) = rule.noise() else {
                panic!("the default rule")
            };
            join_lines(
                pass,
                (60, 80),
                noise,
                &config,
                &mut out,
                &mut JOINS_MAX.clone(),
            );
            assert!(
                matches!(out.as_slice(), [Feature::Line(l)] if (l.first, l.last) == (64, 75)),
                "{out:?}"
            );
            let flag = |i: usize| pass.flag(i) & (START | END);
            assert_eq!(flag(64), START);
            assert_eq!(flag(75), END);
            assert!((65..75).all(|i| flag(i) == 0));
            assert_eq!(flag(63), START | END);
            assert_eq!(flag(76), START | END);
            for i in [60, 61, 62, 77, 78, 79, 80] {
                assert_eq!(flag(i), START | END, "beam {i}");
            }
            assert!((60..=80).all(|i| pass.flag(i) & VALID != 0));
            let st = *pass.stats;
            assert_eq!(st.segments, segments.len() + 1 - 11 + 1, "{st:?}");
            assert_eq!(st.short_segments, segments.len() + 1 - 11, "{st:?}");
            assert_eq!(st.features, 1, "{st:?}");
        });
    }

    /// A chain that starts at beam 0 on a line (the wall y = −3 m, then posts at 5 and 9 m):
    /// joined from its first point, with nothing before it to end.
    #[test]
    fn a_chain_from_the_first_beam_is_joined_from_it() {
        use crate::extractor::Extractor;
        use crate::flags::{END, START};
        use crate::scan::{Scan, ScanGeometry};
        let mut g = ScanGeometry::lms200(180.0, 1.0);
        g.r_max = 50_000.0;
        let ranges: [f32; 181] = core::array::from_fn(|i| match i {
            0..=11 => -3000.0 / crate::math::sin_cos(g.bearing(i)).0,
            12..=16 => [5000.0, 9000.0][i % 2],
            _ => f32::NAN,
        });
        let config = Config::default();
        let mut ex = Extractor::<181, 8>::new();
        ex.with_pass(&Scan::from_mm(g, &ranges), &config, |pass, rule| {
            for i in 0..=16 {
                pass.set(i, START | END);
            }
            pass.stats.segments = 17;
            pass.stats.short_segments = 17;
            let mut out: Vec<Feature, 8> = Vec::new();
            if let Some(noise) = rule.noise() {
                join_lines(
                    pass,
                    (0, 16),
                    noise,
                    &config,
                    &mut out,
                    &mut JOINS_MAX.clone(),
                );
            }
            assert!(
                matches!(out.as_slice(), [Feature::Line(l)] if (l.first, l.last) == (0, 11)),
                "{out:?}"
            );
            assert_eq!(pass.flag(0) & (START | END), START);
            assert_eq!(pass.flag(11) & (START | END), END);
            assert_eq!(
                (pass.stats.segments, pass.stats.short_segments),
                (17 - 12 + 1, 17 - 12)
            );
        });
    }

    /// The NIS of two lines' difference with the sum of their covariances, cross terms
    /// included (worked by hand: 0.5; without the cross terms it would be 0.625), the angle
    /// difference wrapped across ±π.
    #[test]
    fn same_line_is_the_nis_of_the_difference_with_both_covariances() {
        let p = Point::new(0.0, 0.0);
        let line =
            |alpha: f32, rho: f32| LineFeature::new(0, 9, 10, alpha, rho, 1e-4, 4.0, 0.01, p, p);
        let nis = same_line(&line(0.10, 1000.0), &line(0.11, 1001.0));
        assert!((nis - 0.5).abs() < 1e-3, "{nis}");
        let pi = core::f32::consts::PI;
        for (a, b) in [(pi - 0.005, -pi + 0.005), (-pi + 0.005, pi - 0.005)] {
            let nis = same_line(&line(a, 1000.0), &line(b, 1001.0));
            // Δα = ∓0.01 once wrapped: the same 0.5, or 0.5 with the sign of Δα·Δρ flipped.
            assert!(nis < 2.0, "{a} {b}: {nis}");
        }
        assert!(same_line(&line(0.10, 1000.0), &line(0.10 + 0.5, 1000.0)) > 100.0);
    }

    /// 7 beams (0.5° apart) of a post of 250 mm radius whose centre is 4 m ahead, nothing
    /// else in the scan: its points bend by 17 σ_r² from their line (σ_r 5 mm), too little
    /// for the typing's circle (25 σ_r²) but far beyond the noise for a line. It is reported
    /// as a small object; a flat plate seen over the same beams stays a line.
    #[test]
    fn a_short_curved_run_between_jumps_is_an_object_not_a_line() {
        use crate::extractor::Extractor;
        use crate::geometry::ray_circle_intersection;
        use crate::scan::{Scan, ScanGeometry};
        let g = ScanGeometry::LMS200_180_050;
        let config = Config::default();
        let run = |range: &dyn Fn(f32, f32) -> Option<f32>| {
            let ranges: [f32; 361] = core::array::from_fn(|i| {
                let (s, c) = crate::math::sin_cos(g.bearing(i));
                (177..=183)
                    .contains(&i)
                    .then(|| range(c, s))
                    .flatten()
                    .unwrap_or(0.0)
            });
            let mut ex = Extractor::<361, 16>::new();
            assert!(ex.extract(&Scan::from_mm(g, &ranges), &config).is_ok());
            ex.features().to_vec()
        };
        let post = run(&|c, s| {
            ray_circle_intersection(Point::new(0.0, 0.0), c, s, Point::new(4000.0, 0.0), 250.0)
        });
        assert!(
            matches!(post.as_slice(), [Feature::Object(o)] if o.points == 7),
            "{post:?}"
        );
        let plate = run(&|c, _| Some(3750.0 / c));
        assert!(
            matches!(plate.as_slice(), [Feature::Line(l)] if l.points == 7),
            "{plate:?}"
        );
    }

    /// A pillar standing against a wall (a pilaster: its edges meet the wall without a range
    /// jump, so the walk follows wall, pillar and wall as one run) is found as a circle between
    /// two pieces of the wall, not hidden in a line or cut into lines: a wall 700 mm ahead and
    /// a pillar of 170 mm radius centred 760 mm ahead, without noise and with σ_r = 5 mm.
    #[test]
    fn a_pillar_against_a_wall_is_a_circle_between_two_lines() {
        use crate::extractor::Extractor;
        use crate::geometry::ray_circle_intersection;
        use crate::scan::{Scan, ScanGeometry};
        let g = ScanGeometry::LMS200_180_050;
        let (centre, radius, wall) = (760.0f32, 170.0f32, 700.0f32);
        for noise in [0.0f32, 5.0] {
            let mut seed = 12_345u32;
            let mut uniform = || {
                seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                (seed >> 8) as f32 / 16_777_216.0
            };
            let ranges: [f32; 361] = core::array::from_fn(|i| {
                let (s, c) = crate::math::sin_cos(g.bearing(i));
                let (u1, u2) = (uniform().max(1e-7), uniform());
                let n = noise * libm::sqrtf(-2.0 * libm::logf(u1)) * libm::cosf(6.283_185_5 * u2);
                if c < 0.5 {
                    return 0.0;
                }
                let pillar = ray_circle_intersection(
                    Point::new(0.0, 0.0),
                    c,
                    s,
                    Point::new(centre, 0.0),
                    radius,
                )
                .unwrap_or(f32::INFINITY);
                (wall / c).min(pillar) + n
            });
            let mut ex = Extractor::<361, 16>::new();
            assert!(ex
                .extract(&Scan::from_mm(g, &ranges), &Config::default())
                .is_ok());
            let f = ex.features();
            assert!(
                matches!(f, [Feature::Line(a), Feature::Circle(c), Feature::Line(b)]
                    if (a.rho - wall).abs() < 5.0 && (b.rho - wall).abs() < 5.0
                        && (c.center.x - centre).abs() < 15.0 && c.center.y.abs() < 15.0
                        && (c.radius - radius).abs() < 15.0),
                "noise {noise}: {f:?}"
            );
        }
    }

    /// Two neighbouring segments that are one arc together (a pillar cut in two by a start the
    /// walk set inside it) are merged into one circle; with a jump between them, or an invalid
    /// reading, they stay two. A pillar 3 m ahead (39 beams at 0.5°), and one of 0.3 m radius
    /// 0.8 m ahead at 0.25° (127 beams).
    #[test]
    fn neighbouring_segments_of_one_arc_are_merged() {
        use crate::scan::ScanGeometry;
        merged_arc::<361>(ScanGeometry::LMS200_180_050, 3000.0, 500.0, 39);
        merged_arc::<401>(ScanGeometry::lms200(100.0, 0.25), 1100.0, 300.0, 127);
    }

    /// [`neighbouring_segments_of_one_arc_are_merged`] with a pillar of radius `r` whose
    /// centre is `d` ahead, seen over `beams` beams of `g`.
    fn merged_arc<const N: usize>(g: crate::scan::ScanGeometry, d: f32, r: f32, beams: usize) {
        use crate::extractor::Extractor;
        use crate::flags::{JUMP, START};
        use crate::geometry::ray_circle_intersection;
        use crate::scan::Scan;
        let exact: [f32; N] = core::array::from_fn(|i| {
            let (s, c) = crate::math::sin_cos(g.bearing(i));
            ray_circle_intersection(Point::new(0.0, 0.0), c, s, Point::new(d, 0.0), r)
                .unwrap_or(f32::NAN)
        });
        let (first, last) = (
            exact.iter().position(|r| r.is_finite()).unwrap_or(0),
            exact.iter().rposition(|r| r.is_finite()).unwrap_or(0),
        );
        assert_eq!(last + 1 - first, beams);
        let cut = (first + last) / 2;
        let config = Config::default();
        let run = |flag_cut: u8, gap: bool| {
            let mut ranges = exact;
            if gap {
                ranges[cut - 1] = f32::NAN;
            }
            let mut ex = Extractor::<N, 8>::new();
            ex.with_pass(&Scan::from_mm(g, &ranges), &config, |pass, rule| {
                pass.set(first, START);
                pass.set(cut, START | flag_cut);
                let mut out: Vec<Feature, 8> = Vec::new();
                segments(pass, rule, &config, &mut out);
                out
            })
        };
        let one = run(0, false);
        assert!(
            matches!(one.as_slice(), [Feature::Circle(c)] if usize::from(c.first) == first && usize::from(c.last) == last),
            "{one:?}"
        );
        assert_eq!(run(JUMP, false).len(), 2);
        assert_eq!(run(0, true).len(), 2);
    }

    /// A run of short segments is joined at most `CHAIN_MAX` (64) points at a time (the work
    /// a join may take is bounded): 100 single points of one wall become a line of the first 64
    /// and one of the other 36, which, on one line, are then joined into one.
    #[test]
    fn a_long_chain_is_joined_64_points_at_a_time() {
        use crate::extractor::Extractor;
        use crate::flags::{END, START};
        use crate::scan::{Scan, ScanGeometry};
        let mut g = ScanGeometry::lms200(180.0, 1.0);
        g.r_max = 50_000.0;
        let ranges: [f32; 181] = core::array::from_fn(|i| {
            if (40..140).contains(&i) {
                3000.0 / crate::math::sin_cos(g.bearing(i)).1
            } else {
                f32::NAN
            }
        });
        let config = Config::default();
        let mut ex = Extractor::<181, 8>::new();
        let out = ex.with_pass(&Scan::from_mm(g, &ranges), &config, |pass, rule| {
            for i in 40..140 {
                pass.set(i, START | END);
            }
            let mut out: Vec<Feature, 8> = Vec::new();
            segments(pass, rule, &config, &mut out);
            out
        });
        let spans: Vec<(usize, usize), 8> = out.iter().map(|f| (f.first(), f.last())).collect();
        // Joined 64 points at a time, then the two lines, collinear, made one.
        assert_eq!(spans.as_slice(), [(40, 139)], "{out:?}");
    }
}
