//! Joins two neighbouring lines that are one arc ([`join_arcs`]): a pillar standing in a wall
//! (no range jump at its edges) that the walk cut in two, each piece too flat for a circle,
//! their union a clear one. The pillar's far side meets the wall in a kink, and the walk may
//! keep a beam or two of the wall in the arc's last piece (or first, seen the other way):
//! those are left out when the circle passes them by and they lie on the wall beyond (the
//! neighbouring line, or the next one past a nearer object that hides the wall, such as another
//! pillar), not on a straight leg of a convex corner that ends there. When beams are left
//! out on a wall seen past a nearer object, a union the typing leaves a line is a circle
//! when it is curved beyond the noise ([`classify::curved_circle`]).

use crate::arc::arc_fit;
use crate::classify;
use crate::config::Config;
use crate::feature::{CircleFeature, Feature};
use crate::flags::{END, JUMP, START};
use crate::geometry::Point;
use crate::math;
use crate::output::FeatureSink;
use crate::pass::Pass;
use crate::rule::NoiseRule;

use super::MERGE_SIZES;

/// Most joins of two lines into an arc a scan: the work they take is bounded.
const ARC_JOINS_MAX: usize = 4;
/// The beams left out of the union at its first and last end, tried in this order.
const DROPS: [(usize, usize); 5] = [(0, 0), (0, 1), (1, 0), (0, 2), (2, 0)];
/// How far from the union's circle (in σ_r) a beam left out must lie: another surface's.
const OFF_SIGMAS: f32 = 3.0;
/// Largest standard deviation of the circle's radius, as a fraction of it: the beams must
/// determine the radius.
const RADIUS_SPREAD: f32 = 0.1;
/// [`RADIUS_SPREAD`] where the join leaves beams out on a wall seen past a nearer object (the
/// kink a pillar makes with it shows the union ends there).
const KINK_RADIUS_SPREAD: f32 = 0.2;
/// Fewest points of the join's circle.
const JOIN_MIN_POINTS: usize = 10;
/// Largest radius of a pillar the join makes, mm.
const PILLAR_MAX_RADIUS: f32 = 1000.0;

/// Makes each pair of neighbouring stored lines (no beam and no range jump between them)
/// whose union, less at most two beams at one end that lie off its circle and on the wall
/// beyond ([`wall`], [`occluded_wall`]), the typing makes a circle ([`classify::feature`]), or
/// that is curved ([`classify::curved_circle`]) when beams are left out on a wall seen past a
/// nearer object, that circle; the beams left out become a segment of their own, too short
/// for a feature.
#[inline(never)]
pub(super) fn join_arcs(
    pass: &mut Pass<'_>,
    rule: &NoiseRule,
    config: &Config,
    out: &mut dyn FeatureSink,
) {
    let mut joins = ARC_JOINS_MAX;
    let mut i = 0usize;
    while joins > 0 {
        let (a, b, bulge) = match out.features_mut().get(i..i + 2) {
            Some([Feature::Line(a), Feature::Line(b)]) => (
                (usize::from(a.first), usize::from(a.last)),
                (usize::from(b.first), usize::from(b.last)),
                [a.start, a.end, b.start, b.end],
            ),
            Some(_) => {
                i += 1;
                continue;
            }
            None => break,
        };
        let (s, e) = (a.0, b.1);
        if a.1 + 1 == b.0
            && pass.flag(b.0) & JUMP == 0
            && MERGE_SIZES.contains(&(e + 1 - s))
            && bulges(bulge, pass.origin(b.0))
            && spans_pillar(bulge)
        {
            // Each end's wall, and whether it was seen past a nearer object.
            let near = [
                wall(pass, out, i.checked_sub(1), s),
                wall(pass, out, Some(i + 2), e + 1),
            ];
            let hidden = [
                near[0].is_none().then(|| {
                    let k = [i.checked_sub(2), i.checked_sub(1)];
                    occluded_wall(pass, out, k, s, config.sigma_r)
                }),
                near[1].is_none().then(|| {
                    let k = [Some(i + 3), Some(i + 2)];
                    occluded_wall(pass, out, k, e + 1, config.sigma_r)
                }),
            ]
            .map(Option::flatten);
            let walls = [near[0].or(hidden[0]), near[1].or(hidden[1])];
            let past = [hidden[0].is_some(), hidden[1].is_some()];
            if let Some((f, lead, trail)) = arc_of(pass, s, e, (walls, past), rule, config) {
                joins -= 1;
                replace_pair(pass, out, i, f, (s, e), (a.1, b.0), (lead, trail));
            }
        }
        i += 1;
    }
}

/// The line (normal angle, distance) of the stored feature `k` when it is a line whose first
/// or last beam is `edge` with no range jump between it and the join's: the wall the join's
/// pillar stands in, on which any beam the join leaves out at that end must lie.
fn wall(
    pass: &Pass<'_>,
    out: &mut dyn FeatureSink,
    k: Option<usize>,
    edge: usize,
) -> Option<(f32, f32)> {
    let Some(Feature::Line(l)) = out.features_mut().get(k?) else {
        return None;
    };
    let (first, last) = (usize::from(l.first), usize::from(l.last));
    let next = if last + 1 == edge {
        edge
    } else if first == edge {
        first
    } else {
        return None;
    };
    (pass.flag(next) & JUMP == 0).then_some((l.alpha, l.rho))
}

/// The line (normal angle, distance) of the stored line `k[0]` (or else `k[1]`) beyond a
/// nearer object that hides the wall from `edge` (the join's first or last beam's neighbour)
/// on: a range jump at `edge`'s side of the join, and every beam between the join and the
/// line on the scanner's side of it. The wall a pillar stands in, its next stretch seen past
/// another pillar in front of it, on which any beam the join leaves out at that end must lie.
fn occluded_wall(
    pass: &Pass<'_>,
    out: &mut dyn FeatureSink,
    k: [Option<usize>; 2],
    edge: usize,
    sigma_r: f32,
) -> Option<(f32, f32)> {
    let mut line = |k: Option<usize>| match out.features_mut().get(k?) {
        Some(Feature::Line(l)) => {
            let (first, last) = (usize::from(l.first), usize::from(l.last));
            Some((first, last, l.alpha, l.rho))
        }
        _ => None,
    };
    let (first, last, alpha, rho) = line(k[0]).or_else(|| line(k[1]))?;
    // The beams between the join and the line (the nearer object).
    let (lo, hi) = if first >= edge {
        (edge, first.checked_sub(1)?)
    } else if last < edge {
        (last + 1, edge.checked_sub(1)?)
    } else {
        return None;
    };
    if lo > hi || pass.flag(edge) & JUMP == 0 {
        return None;
    }
    let (sn, cn) = math::sin_cos(alpha);
    let off = |p: Point| p.x * cn + p.y * sn - rho;
    // Towards the scanner, each within the noise of the wall or nearer.
    let side = if off(pass.origin(edge)) > 0.0 {
        1.0
    } else {
        -1.0
    };
    (lo..=hi)
        .all(|b| !pass.valid(b) || side * off(pass.point(b)) >= -OFF_SIGMAS * sigma_r)
        .then_some((alpha, rho))
}

/// Whether the two lines from `p[0]` to `p[1]` and from `p[2]` to `p[3]` bulge towards the
/// scanner at `origin`: their meeting point lies on its side of the chord between their far
/// ends, as on a pillar's face (a cheap screen before any fit: a circle that faces the scanner,
/// [`faces`], needs it).
fn bulges(p: [Point; 4], origin: Point) -> bool {
    let [a, j0, j1, b] = p;
    let j = Point::new(0.5 * (j0.x + j1.x), 0.5 * (j0.y + j1.y));
    let (cx, cy) = (b.x - a.x, b.y - a.y);
    let side = |q: Point| cx * (q.y - a.y) - cy * (q.x - a.x);
    side(j) * side(origin) > 0.0
}

/// Whether the chord from `p[0]` to `p[3]` (the two lines' far ends) is short enough for an
/// arc of at most 120° of a circle of at most [`PILLAR_MAX_RADIUS`] (√3 R, with a tenth more
/// for the beams the join may leave out): a cheap screen, as two long walls meeting in a
/// corner fail it.
fn spans_pillar(p: [Point; 4]) -> bool {
    let (dx, dy) = (p[3].x - p[0].x, p[3].y - p[0].y);
    let most = 1.1 * PILLAR_MAX_RADIUS;
    dx * dx + dy * dy <= 3.0 * most * most
}

/// The circle of the segment `s..=e` less `lead` beams at its start and `trail` at its end
/// (the first of [`DROPS`] the typing makes a circle, or that is curved, whose left-out beams
/// are off it and that can be a pillar, [`pillar`]).
fn arc_of(
    pass: &Pass<'_>,
    s: usize,
    e: usize,
    (walls, past): ([Option<(f32, f32)>; 2], [bool; 2]),
    rule: &NoiseRule,
    config: &Config,
) -> Option<(Feature, usize, usize)> {
    DROPS.iter().find_map(|&(lead, trail)| {
        let (cs, ce) = (s + lead, e.checked_sub(trail)?);
        if ce < cs + config.min_points.max(JOIN_MIN_POINTS) - 1 {
            return None;
        }
        // A beam left out lies on the wall beyond it, not on the far end of a straight leg.
        let on = |w: Option<(f32, f32)>, k: usize| {
            pass.valid(k)
                && w.is_some_and(|(alpha, rho)| {
                    let (sn, cn) = math::sin_cos(alpha);
                    let p = pass.point(k);
                    math::abs(p.x * cn + p.y * sn - rho) <= OFF_SIGMAS * config.sigma_r
                })
        };
        if !((s..cs).all(|k| on(walls[0], k)) && (ce + 1..=e).all(|k| on(walls[1], k))) {
            return None;
        }
        // Beams left out on a wall seen past a nearer object (another pillar, say): the curved
        // run is enough, its radius known more loosely.
        let kink = (lead > 0 && past[0]) || (trail > 0 && past[1]);
        // The walk's one-pass arc test screens the candidates before the typing.
        arc_fit(pass.points.get(cs..=ce)?, rule)?;
        let Some(Feature::Circle(c)) = classify::feature::<true>(pass, cs, ce, config)
            .filter(|f| matches!(f, Feature::Circle(_)))
            .or_else(|| kink.then(|| classify::curved_circle(pass, cs, ce, config))?)
        else {
            return None;
        };
        let pts = pass.points.get(cs..=ce)?;
        let spread = if kink {
            KINK_RADIUS_SPREAD
        } else {
            RADIUS_SPREAD
        };
        if !pillar(pts, pass.origin((cs + ce) / 2), &c, spread) {
            return None;
        }
        let off = |k: usize| {
            pass.valid(k)
                && math::abs(pass.point(k).distance(&c.center) - c.radius)
                    > OFF_SIGMAS * config.sigma_r
        };
        ((s..cs).all(off) && (ce + 1..=e).all(off)).then_some((Feature::Circle(c), lead, trail))
    })
}

/// Whether the circle `c` of the points `pts` can be a pillar standing in a wall, seen from
/// `origin`: its points face the scanner ([`faces`]), its arc spans at most 120° ([`narrow`]),
/// the beams determine its radius (a standard deviation of at most `spread` of it),
/// which is at most [`PILLAR_MAX_RADIUS`].
fn pillar(pts: &[Point], origin: Point, c: &CircleFeature, spread: f32) -> bool {
    let spread = spread * c.radius;
    faces(pts, origin, c)
        && narrow(pts, c)
        && c.cov[2][2] <= spread * spread
        && c.radius <= PILLAR_MAX_RADIUS
}

/// Whether every point of `pts` lies on the side of the circle `c` that faces the scanner at
/// `origin`: nearer than the tangent range √(d² − R²) (`d` the centre's distance), as every
/// point of a pillar's visible face is. A hollow's circle (a corner's or a bay's seen from
/// inside: the scanner inside the circle, or the points on its far side) is not.
fn faces(pts: &[Point], origin: Point, c: &CircleFeature) -> bool {
    let (dx, dy) = (c.center.x - origin.x, c.center.y - origin.y);
    let (d2, r2) = (dx * dx + dy * dy, c.radius * c.radius);
    if !(d2 > r2) {
        return false;
    }
    let reach = math::sqrt(d2 - r2);
    pts.iter().all(|p| p.distance(&origin) <= reach)
}

/// Whether the arc of `pts` about the centre of `c` spans at most 120° between its ends: the
/// cap of a pillar standing in a wall; two short lines meeting in a corner fit a circle of
/// 130–170° (their legs its tangents).
fn narrow(pts: &[Point], c: &CircleFeature) -> bool {
    let (Some(a), Some(b)) = (pts.first(), pts.last()) else {
        return false;
    };
    let o = c.center;
    let (ax, ay, bx, by) = (a.x - o.x, a.y - o.y, b.x - o.x, b.y - o.y);
    let (dot, cross) = (ax * bx + ay * by, ax * by - ay * bx);
    // cos ≥ −1/2.
    dot >= 0.0 || 3.0 * dot * dot <= cross * cross
}

/// Puts `f` (over `s + lead..=e - trail`) in place of the stored features `i` and `i + 1`
/// (the segments `s..=a_last` and `b_first..=e`), the beams left out a short segment each.
fn replace_pair(
    pass: &mut Pass<'_>,
    out: &mut dyn FeatureSink,
    i: usize,
    f: Feature,
    (s, e): (usize, usize),
    (a_last, b_first): (usize, usize),
    (lead, trail): (usize, usize),
) {
    if let Some(slot) = out.features_mut().get_mut(i) {
        *slot = f;
    }
    let mut k = 0usize;
    out.retain(&mut |_| {
        k += 1;
        k != i + 2
    });
    pass.clear(a_last, END);
    pass.clear(b_first, START);
    let stats = &mut *pass.stats;
    stats.features = stats.features.saturating_sub(1);
    stats.segments = stats.segments.saturating_sub(1);
    if lead > 0 {
        pass.set(s + lead - 1, END);
        pass.set(s + lead, START);
    }
    if trail > 0 {
        pass.set(e - trail, END);
        pass.set(e - trail + 1, START);
    }
    let short = usize::from(lead > 0) + usize::from(trail > 0);
    let stats = &mut *pass.stats;
    stats.segments += short;
    stats.short_segments += short;
}

#[cfg(test)]
#[cfg(feature = "libm")]
#[path = "arcs_tests.rs"]
mod tests;
