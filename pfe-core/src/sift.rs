//! Ours, with the checks for real scans, after the fits: only what the scanner can see, and
//! small objects as such.
//!
//! - A line seen at more than 85° incidence from the scanner at its midpoint (the angle
//!   between the beam to its midpoint and its normal), or shorter than 10 mm, is no surface
//!   the beams could have measured: the mixed pixels of a veil along a line of sight at an
//!   object's edge, or a run with no extent. It is not reported. (A wall running away from the
//!   scanner is cut before this step: `segment` keeps the part of its segment from the near
//!   end whose line is seen within 85° at its midpoint, and leaves the far part without a
//!   feature.)
//! - A small object (a run of at least [`OBJECT_MIN_POINTS`] returns with a range jump of at
//!   least [`OBJECT_JUMP_MM`] or no return on both sides, at most [`OBJECT_MAX_MM`] across)
//!   that no feature holds, or that only a line of undetermined direction (σ_α above
//!   [`MAX_SIGMA_ALPHA`]) holds, is reported as an [`ObjectFeature`]: a chair leg, a person's
//!   leg, a post. Its arc, where its points show one, was a circle and stays one. A run that
//!   is a straight face of at least `min_points` beams and one beam off it at an end (the
//!   surface round a corner: a door jamb's face seen with one beam of the wall) is that
//!   face's line instead ([`corner_face`]).
//! - The points of a line not reported that are no small object are flagged as mixed pixels
//!   ([`VEIL`]) and counted in [`Stats::veils`](crate::Stats).

use crate::classify;
use crate::config::Config;
use crate::feature::{Feature, LineFeature, ObjectFeature};
use crate::fit::circle::{fit_circle, refine_from, NormalEquations};
use crate::fit::line::fit_line;
use crate::flags::{END, START, VALID, VEIL};
use crate::geometry::Point;
use crate::math;
use crate::output::FeatureSink;
use crate::pass::Pass;

/// cos 85°: a line whose normal makes a larger angle with the beam to its midpoint is not seen.
const COS_MAX_INCIDENCE: f32 = 0.087_155_74;
/// tan 85°: a point of a line farther along it from the normal's foot than ρ·tan 85° is seen
/// at more than 85° incidence.
pub(crate) const TAN_MAX_INCIDENCE: f32 = 11.430_052;
/// Shortest line reported, mm.
const MIN_LINE_MM: f32 = 10.0;
/// Fewest returns of a small object.
pub(crate) const OBJECT_MIN_POINTS: usize = 3;
/// Range jump that separates a small object from its neighbours, mm.
pub(crate) const OBJECT_JUMP_MM: f32 = 300.0;
/// Widest small object, mm.
pub(crate) const OBJECT_MAX_MM: f32 = 300.0;
/// 99 % of χ²₁: an end beam further than this (in its residual's σ) from the line of the
/// run's other points is not on it ([`corner_face`]).
const OFF_CHI2: f32 = 6.63;
/// 95 % of χ²₁: a face's end beam this near the line of its other points (in its residual's
/// σ) is on it ([`corner_face`]).
const ON_CHI2: f32 = 3.84;
/// Largest residual sum of a face's line per degree of freedom, in σ_r² ([`corner_face`]).
const FACE_SSE: f32 = 3.0;
/// 95 % of χ²₁: how much more residual sum (in σ_r²) the circle through all of a run's points
/// must leave than the line of all but its end beam ([`corner_face`]): a pillar's end beam
/// lies on the circle of its others, a corner's on neither.
const CIRCLE_CHI2: f32 = 3.84;

/// σ_α beyond which a line's direction is undetermined, rad (a line over a small object with
/// it is reported as the object).
const MAX_SIGMA_ALPHA: f32 = 0.1;

/// Sifts the features in `out` as the module says.
pub(crate) fn sift(pass: &mut Pass<'_>, config: &Config, out: &mut dyn FeatureSink) {
    // Lines not reported: their points freed (flagged as veils until an object takes them).
    let mut freed = 0usize;
    // Which of the first 128 features are such lines, so that they are judged once.
    let mut gone = 0u128;
    for (k, f) in out.features_mut().iter().enumerate() {
        if let Some(l) = unreported(pass, f) {
            gone |= 1u128.checked_shl(k as u32).unwrap_or(0);
            free(pass, &l);
            freed += 1;
        }
    }
    if freed > 0 {
        let pass = &*pass;
        // `retain` asks each feature once, in order: `k` is its index.
        let mut k = 0usize;
        out.retain(&mut |f| {
            let at = k;
            k += 1;
            match at < 128 {
                true => gone & (1u128 << at) == 0,
                false => unreported(pass, f).is_none(),
            }
        });
    }
    // Small objects no feature holds.
    let len = pass.len();
    let mut i = 0usize;
    let mut added = false;
    while i < len {
        if !pass.valid(i) {
            i += 1;
            continue;
        }
        let e = run_end(pass, i);
        let whole = (e + 1 - i >= OBJECT_MIN_POINTS && !held(out.features_mut(), i, e))
            .then(|| segment_bounds(pass, i, e, config.min_points))
            .flatten();
        if let Some((a, b)) = whole {
            if let Some((fa, fb, line)) = corner_face(pass, i, e, config) {
                // The face a line, the beam round its corner a short segment of its own.
                one_segment(pass, i, e, a, b, config.min_points);
                let (end, start) = if fa > i { (i, fa) } else { (fb, e) };
                pass.set(end, END);
                pass.set(start, START);
                pass.stats.segments += 1;
                pass.stats.short_segments += 1;
                if out.push(line) {
                    pass.stats.features += 1;
                    added = true;
                } else {
                    pass.stats.dropped += 1;
                }
            } else if let Some(o) = object(pass, i, e, config) {
                one_segment(pass, i, e, a, b, config.min_points);
                if out.push(Feature::Object(o)) {
                    pass.stats.features += 1;
                    pass.stats.objects += 1;
                    added = true;
                } else {
                    pass.stats.dropped += 1;
                }
            }
        }
        i = e + 1;
    }
    if added {
        in_scan_order(out.features_mut());
    }
    pass.stats.veils = pass.flags.iter().filter(|&&f| f & VEIL != 0).count();
}

/// The line `f` when it is not reported: the scanner cannot have seen it, or it is a line of
/// undetermined direction over a small object.
pub(crate) fn unreported(pass: &Pass<'_>, f: &Feature) -> Option<LineFeature> {
    match f {
        Feature::Line(l) if !seen(l) || undetermined_object(pass, l) => Some(*l),
        _ => None,
    }
}

/// Frees the points of the line `l`, not reported: flagged as veils (until an object takes
/// them), its segment counted as one whose fit failed.
pub(crate) fn free(pass: &mut Pass<'_>, l: &LineFeature) {
    for i in usize::from(l.first)..=usize::from(l.last) {
        if pass.valid(i) {
            pass.set(i, VEIL);
        }
    }
    pass.stats.features = pass.stats.features.saturating_sub(1);
    pass.stats.degenerate += 1;
}

/// Sorts `features` by first beam (an insertion sort: they are in order but for the objects
/// appended; no panic path, unlike the library's sorts).
fn in_scan_order(features: &mut [Feature]) {
    for i in 1..features.len() {
        let Some(&f) = features.get(i) else { break };
        let mut j = i;
        while j > 0 {
            let Some(&p) = features.get(j - 1) else {
                break;
            };
            if p.first() <= f.first() {
                break;
            }
            if let Some(slot) = features.get_mut(j) {
                *slot = p;
            }
            j -= 1;
        }
        if let Some(slot) = features.get_mut(j) {
            *slot = f;
        }
    }
}

/// True when the scanner can have seen `l` as a surface: at most 85° incidence at its
/// midpoint, and at least 10 mm long.
pub(crate) fn seen(l: &LineFeature) -> bool {
    let m = Point::new(0.5 * (l.start.x + l.end.x), 0.5 * (l.start.y + l.end.y));
    let d = m.norm();
    let (sin, cos) = math::sin_cos(l.alpha);
    let along = math::abs(m.x * cos + m.y * sin);
    d > 0.0 && along >= COS_MAX_INCIDENCE * d && l.start.distance(&l.end) >= MIN_LINE_MM
}

/// True when `l` has an undetermined direction and lies on a small object.
fn undetermined_object(pass: &Pass<'_>, l: &LineFeature) -> bool {
    if !(l.var_alpha > MAX_SIGMA_ALPHA * MAX_SIGMA_ALPHA) {
        return false;
    }
    let (first, last) = (usize::from(l.first), usize::from(l.last));
    // The run around the line, without a jump. A point farther than twice the widest object
    // from the line's first point makes the run wider than an object (the triangle
    // inequality through either end of the run): the walks stop there.
    let a = pass.point(first);
    let far = |k: usize| pass.point(k).distance(&a) > 2.0 * OBJECT_MAX_MM;
    let mut s = first;
    while s > 0 && pass.valid(s - 1) && !jump(pass, s - 1) {
        s -= 1;
        if far(s) {
            return false;
        }
    }
    let mut e = first;
    while e + 1 < pass.len() && pass.valid(e + 1) && !jump(pass, e) {
        e += 1;
        if far(e) {
            return false;
        }
    }
    e >= last && e + 1 - s >= OBJECT_MIN_POINTS && extent(pass, s, e, OBJECT_MAX_MM).is_some()
}

/// The first and last point of the segments that hold the run `s..=e`, when the run can be
/// made a segment of its own: a segment that reaches over the jump at either end (the paired
/// marks of a short segment across it) keeps fewer than `min_points` points outside the run,
/// so that it stays a short segment without a feature.
fn segment_bounds(
    pass: &Pass<'_>,
    s: usize,
    e: usize,
    min_points: usize,
) -> Option<(usize, usize)> {
    let mut a = s;
    while pass.flag(a) & START == 0 {
        let prev = a.checked_sub(1)?;
        if !pass.valid(prev) || s - prev >= min_points {
            return None;
        }
        if pass.flag(prev) & END != 0 {
            break;
        }
        a = prev;
    }
    let mut b = e;
    while pass.flag(b) & END == 0 && pass.valid(b + 1) && pass.flag(b + 1) & START == 0 {
        b += 1;
        if b - e >= min_points {
            return None;
        }
    }
    (s - a < min_points && b - e < min_points).then_some((a, b))
}

/// Makes the segments of the run `s..=e` (short, or without a feature) one segment, the
/// object's: its marks at `s` and `e` only, the statistics counting it once. The segments
/// that hold it span `a..=b`; what lies of them outside the run (fewer than `min_points`
/// points, see [`segment_bounds`]) stays a short segment.
fn one_segment(pass: &mut Pass<'_>, s: usize, e: usize, a: usize, b: usize, min_points: usize) {
    let mut from = a;
    let mut undone = 0usize;
    while from <= e {
        let mut to = from;
        while to < b && pass.flag(to + 1) & START == 0 {
            to += 1;
        }
        undone += 1;
        let stats = &mut *pass.stats;
        if to + 1 - from < min_points {
            stats.short_segments = stats.short_segments.saturating_sub(1);
        } else {
            stats.degenerate = stats.degenerate.saturating_sub(1);
        }
        from = to + 1;
    }
    let kept = usize::from(a < s) + usize::from(b > e);
    pass.stats.short_segments += kept;
    pass.stats.segments = (pass.stats.segments + 1 + kept).saturating_sub(undone);
    for k in s..=e {
        pass.clear(k, START | END | VEIL);
    }
    pass.set(s, START);
    pass.set(e, END);
    if a < s {
        pass.set(s - 1, END);
    }
    if b > e {
        pass.set(e + 1, START);
    }
}

/// True when the range jumps by at least [`OBJECT_JUMP_MM`] from point `i` to `i + 1`.
fn jump(pass: &Pass<'_>, i: usize) -> bool {
    !(math::abs(pass.range(i + 1) - pass.range(i)) < OBJECT_JUMP_MM)
}

/// Whether the run `s..=e` has a range jump (or no return, or the scan's end) on both sides,
/// as a small object has.
pub(crate) fn isolated(pass: &Pass<'_>, s: usize, e: usize) -> bool {
    jump_before(pass, s) && jump_after(pass, e)
}

/// Whether the run `s..=e` has a range jump (or no return, or the scan's end) on at least one
/// side: a post standing in front of a wall, or partly hidden behind a nearer object, has it
/// on one side only.
pub(crate) fn detached(pass: &Pass<'_>, s: usize, e: usize) -> bool {
    jump_before(pass, s) || jump_after(pass, e)
}

/// Whether a range jump, no return or the scan's start comes before the valid point `s`.
fn jump_before(pass: &Pass<'_>, s: usize) -> bool {
    s == 0 || !pass.valid(s - 1) || jump(pass, s - 1)
}

/// Whether a range jump, no return or the scan's end comes after the valid point `e`.
fn jump_after(pass: &Pass<'_>, e: usize) -> bool {
    e + 1 >= pass.len() || !pass.valid(e + 1) || jump(pass, e)
}

/// The last point of the run of returns from the valid point `s` without a jump.
fn run_end(pass: &Pass<'_>, s: usize) -> usize {
    // Each next point's flag beside its range and the one before: one bounds test a scan.
    let (Some(flags), Some(ranges)) = (pass.flags.get(s + 1..), pass.ranges.get(s..)) else {
        return s;
    };
    let joined = |(&f, r): (&u8, &[f32])| {
        f & VALID != 0 && matches!(r, [a, b] if math::abs(b - a) < OBJECT_JUMP_MM)
    };
    s + flags
        .iter()
        .zip(ranges.windows(2))
        .take_while(|&step| joined(step))
        .count()
}

/// True when a feature holds a point of `s..=e`.
fn held(features: &[Feature], s: usize, e: usize) -> bool {
    features.iter().any(|f| f.first() <= e && f.last() >= s)
}

/// The widest distance from either end of the run `s..=e` to its points, mm (its extent),
/// when it is at most `max` mm (`None` from the first point farther: no need to go on).
fn extent(pass: &Pass<'_>, s: usize, e: usize, max: f32) -> Option<f32> {
    let (a, b) = (pass.point(s), pass.point(e));
    let mut w = 0.0f32;
    for k in (s..=e).filter(|&k| pass.valid(k)) {
        let p = pass.point(k);
        let d = p.distance(&a).max(p.distance(&b));
        if d > max {
            return None;
        }
        w = w.max(d);
    }
    (w <= max).then_some(w)
}

/// The object of the run `s..=e`, when it is one (at most [`OBJECT_MAX_MM`] across).
///
/// Its centre is the mean of its points. The centre's covariance adds: the points' scatter
/// over their number; the range noise along the beam to the centre (σ_r² over the points, and
/// the systematic σ_sys², shared by them); and, along that beam, the variance of where on an
/// object as deep as it is wide its surface lies (w²/12: the points show its near side, which
/// moves against the centre as it is seen from elsewhere).
pub(crate) fn object(
    pass: &Pass<'_>,
    s: usize,
    e: usize,
    config: &Config,
) -> Option<ObjectFeature> {
    let w = extent(pass, s, e, OBJECT_MAX_MM)?;
    let (mut n, mut sx, mut sy) = (0usize, 0.0f32, 0.0f32);
    for k in (s..=e).filter(|&k| pass.valid(k)) {
        let p = pass.point(k);
        n += 1;
        sx += p.x;
        sy += p.y;
    }
    if n < OBJECT_MIN_POINTS {
        return None;
    }
    let nf = n as f32;
    let c = Point::new(sx / nf, sy / nf);
    let (mut xx, mut xy, mut yy) = (0.0f32, 0.0f32, 0.0f32);
    for k in (s..=e).filter(|&k| pass.valid(k)) {
        let p = pass.point(k);
        let (dx, dy) = (p.x - c.x, p.y - c.y);
        xx += dx * dx;
        xy += dx * dy;
        yy += dy * dy;
    }
    let scatter = 1.0 / ((nf - 1.0) * nf);
    let d = c.norm();
    if !(d > 0.0) {
        return None;
    }
    let (ux, uy) = (c.x / d, c.y / d);
    let depth =
        config.sigma_r * config.sigma_r / nf + config.sigma_sys * config.sigma_sys + w * w / 12.0;
    let cxx = xx * scatter + depth * ux * ux;
    let cxy = xy * scatter + depth * ux * uy;
    let cyy = yy * scatter + depth * uy * uy;
    let o = ObjectFeature::new(
        u16::try_from(s).ok()?,
        u16::try_from(e).ok()?,
        u16::try_from(n).ok()?,
        c,
        [[cxx, cxy], [cxy, cyy]],
        w,
    );
    Feature::Object(o).is_well_formed().then_some(o)
}

/// For the run `s..=e` between range jumps (a small object's): the face `a..=b` without one
/// end beam and its line, when that beam lies off the line of the others (beyond [`OFF_CHI2`]
/// of its residual's variance: the range noise's and the line's own there), the others, at
/// least `min_points`, are straight (typed a line, not [`classify::curved`], one this step
/// reports: seen within 85°), and their line fits them better than a circle fits the whole
/// run, by [`CIRCLE_CHI2`] σ_r². At a door jamb or a box's corner the walk may keep the beam
/// that hit the surface round the corner with the face's few beams; the run, bent at that
/// beam, is then no object but a face.
fn corner_face(
    pass: &Pass<'_>,
    s: usize,
    e: usize,
    config: &Config,
) -> Option<(usize, usize, Feature)> {
    if e < s + config.min_points || !(s..=e).all(|k| pass.valid(k)) {
        return None;
    }
    let var_r = config.sigma_r * config.sigma_r;
    let all = pass.points.get(s..=e)?;
    let (_, sse_c) = fit_circle(all, config.circle_method).ok().and_then(|c| {
        refine_from(all, c, NormalEquations::at(all, &c), config.circle_refine).ok()
    })?;
    [(s + 1, e, s), (s, e - 1, e)]
        .into_iter()
        .find_map(|(a, b, k)| {
            let pts = pass.points.get(a..=b)?;
            let f = fit_line(pts).ok()?;
            // The face's own end beams lie on the line of its other points.
            if !(off_line(pass, a + 1, b, a, var_r)? <= ON_CHI2)
                || !(off_line(pass, a, b - 1, b, var_r)? <= ON_CHI2)
                || !(f.sse() <= FACE_SSE * var_r * f.n.saturating_sub(2) as f32)
                || !(off_line(pass, a, b, k, var_r)? > OFF_CHI2)
                || !(sse_c - f.sse() > CIRCLE_CHI2 * var_r)
                || classify::curved(pass, a, pts, config)
            {
                return None;
            }
            match classify::feature::<true>(pass, a, b, config) {
                Some(line @ Feature::Line(_)) if unreported(pass, &line).is_none() => {
                    Some((a, b, line))
                }
                _ => None,
            }
        })
}

/// How far the valid beam `k` lies from the line of the points `a..=b`, in its residual's
/// variance: the range noise's (`var_r`) and the line's own there, σ_r² (1/n + u²/Σu²), u its
/// position along the line (`None` when the fit fails).
fn off_line(pass: &Pass<'_>, a: usize, b: usize, k: usize, var_r: f32) -> Option<f32> {
    let f = fit_line(pass.points.get(a..=b)?).ok()?;
    let p = pass.point(k);
    let u = (p.y - f.centroid.y) * f.cos_alpha - (p.x - f.centroid.x) * f.sin_alpha;
    let (sn, cs) = (f.sin_alpha, f.cos_alpha);
    let suu = sn * sn * f.sxx + cs * cs * f.syy - 2.0 * sn * cs * f.sxy;
    let d = f.signed_distance(&p);
    Some(d * d / (var_r * (1.0 + 1.0 / f.n as f32 + u * u / suu)))
}

#[cfg(test)]
#[cfg(feature = "libm")]
#[path = "sift_tests.rs"]
mod tests;
