//! Where a segment boundary lies (default mode): after a detection, [`locate`] moves it back
//! over the points that already left the old segment's line; a few points later,
//! [`refine_boundary`] settles it between two fixed lines.

use crate::config::NP;
use crate::fit::line::{fit_axis, LineAxis};
use crate::geometry::Point;
use crate::math;
use crate::pass::Pass;
use crate::predict::Prediction;
use crate::rule::NoiseRule;

/// Points of the new segment seen before its boundary is refined (its line in the refinement
/// is fitted to the points after the candidates).
pub(crate) const REFINE_AFTER: usize = 6;
/// Points each side used to refine a boundary.
const REFINE_SPAN: usize = 6;

/// The earliest of the (up to 4) points before `k` that, with `k`, deviate on the same side
/// from the line through the points of the segment starting at `s` before them. `at_k`: `k`'s
/// prediction from its own window.
pub(crate) fn locate(
    pass: &mut Pass<'_>,
    s: usize,
    k: usize,
    at_k: Option<Prediction>,
    rule: &NoiseRule,
) -> usize {
    const BACK: usize = 4;
    let m = &rule.model;
    let c = k - s;
    let back = BACK.min(c.saturating_sub(NP));
    if back == 0 {
        return k;
    }
    let ref_end = k - back;
    let ref_start = ref_end.saturating_sub(m.window).max(s);
    let Some(side) = at_k.map(|p| p.signed) else {
        return k;
    };
    // Predictions from the reference line. Without de-skewing every beam sees it from the
    // same origin: k's fit serves them all (each still counts as a prediction).
    let fixed = pass
        .motion
        .is_none()
        .then(|| pass.window_line(ref_start, ref_end, k));
    let k_from_ref = match fixed {
        Some(line) => line.and_then(|l| pass.predict_with(&l, k)),
        None => pass.predict(ref_start, ref_end, k),
    };
    let predict = |pass: &mut Pass<'_>, j: usize| match fixed {
        Some(line) => {
            pass.stats.predictions += 1;
            line.and_then(|l| pass.predict_with(&l, j))
        }
        None => pass.predict(ref_start, ref_end, j),
    };
    // Sign of k's deviation from the reference line (not from its own window).
    let side = match k_from_ref {
        Some(p) if math::finite(p.signed) => p.signed,
        _ => side,
    };
    let mut b = k;
    for j in (ref_end..k).rev() {
        match predict(pass, j) {
            Some(p) if p.signed * side > 0.0 && p.exceeds(m.k_locate, rule.sigma_r, m.floor) => {
                b = j
            }
            _ => break,
        }
    }
    // Each point moved to the new segment must lie on the line through the ones after it (a
    // reference line through an arc's end also "sees" the arc's own last points deviate).
    while b + 2 <= k {
        let tol = rule.k_sigma + m.floor;
        let consistent = match (pass.points.get(b + 1..=k), pass.points.get(b)) {
            (Some(rest), Some(p)) => {
                fit_axis(rest).is_ok_and(|l| math::abs(l.signed_distance(p)) <= tol)
            }
            _ => true,
        };
        if consistent {
            break;
        }
        b += 1;
    }
    b
}

/// Best split between a segment starting at `old` and one starting near `b` and running to
/// `end` (exclusive): the candidate in `b − 3 ..= b + 1` that puts the points between them on
/// the nearer of two fixed lines, the left one fitted to up to `REFINE_SPAN` points before the
/// candidates (the old segment's), the right one to up to `REFINE_SPAN` from the last candidate
/// on (the new segment's): least sum of squared distances, one fit each side, not two fits per
/// candidate. Where both lines are full ([`REFINE_SPAN`] points each), straight (every point
/// within [`STRAIGHT_SIGMAS`] σ_r of its line) and meet at a corner between the candidates,
/// the corner's bearing splits them instead ([`corner_split`]). `sigma_r`: the walk's σ_r.
#[inline(never)]
pub(crate) fn refine_boundary(
    points: &[Point],
    old: usize,
    b: usize,
    end: usize,
    sigma_r: f32,
) -> usize {
    let lo = b.saturating_sub(3).max(old + NP);
    let hi = (b + 1).min(end.saturating_sub(NP));
    if lo >= hi {
        return b;
    }
    let (Some(left_pts), Some(right_pts)) = (
        points.get(lo.saturating_sub(REFINE_SPAN).max(old)..lo),
        points.get(hi..end.min(hi + REFINE_SPAN)),
    ) else {
        return b;
    };
    let (Ok(left), Ok(right)) = (fit_axis(left_pts), fit_axis(right_pts)) else {
        return b;
    };
    let Some(contested) = points.get(lo..hi) else {
        return b;
    };
    let tol = STRAIGHT_SIGMAS * sigma_r;
    let straight =
        |l: &LineAxis, pts: &[Point]| pts.iter().all(|p| math::abs(l.signed_distance(p)) <= tol);
    let full = left_pts.len() == REFINE_SPAN && right_pts.len() == REFINE_SPAN;
    if full && straight(&left, left_pts) && straight(&right, right_pts) {
        if let Some(split) =
            corner_split(&left, &right, points, (lo, hi), CONTESTED_SIGMAS * sigma_r)
        {
            return split;
        }
    }
    // Split j: points lo..j on the left line, j..hi on the right one.
    let mut sse: f32 = contested.iter().map(|p| sq(right.signed_distance(p))).sum();
    let (mut best, mut best_sse) = (lo, sse);
    for (j, p) in (lo + 1..).zip(contested) {
        sse += sq(left.signed_distance(p)) - sq(right.signed_distance(p));
        // Ties keep the detected boundary.
        if sse < best_sse || (sse == best_sse && j == b) {
            best = j;
            best_sse = sse;
        }
    }
    best
}

/// Where the corner of `left` and `right` splits the contested points `lo..hi` by bearing: the
/// points whose beam passes before the corner lie on the left line, the others on the right
/// one, whatever their ranges say (a beam's bearing is exact, its range is not). `None` (the
/// squared distances decide) when the lines meet at less than [`CORNER_SIN`], not between the
/// beams of points `lo − 1` and `hi`, within [`CORNER_MARGIN`] of a contested beam, or when a
/// contested point lies more than `tol` from the line of its side.
fn corner_split(
    left: &LineAxis,
    right: &LineAxis,
    points: &[Point],
    (lo, hi): (usize, usize),
    tol: f32,
) -> Option<usize> {
    let (before, after) = (points.get(lo.checked_sub(1)?)?, points.get(hi)?);
    // The normals from the signed distances (the lines are linear in the point), about the
    // point before the contested ones to keep the rounding small.
    let q = *before;
    let normal = |l: &LineAxis| {
        let d = l.signed_distance(&q);
        let nx = (l.signed_distance(&Point::new(q.x + 1000.0, q.y)) - d) / 1000.0;
        let ny = (l.signed_distance(&Point::new(q.x, q.y + 1000.0)) - d) / 1000.0;
        (nx, ny, d)
    };
    let ((ax, ay, da), (bx, by, db)) = (normal(left), normal(right));
    let det = ax * by - ay * bx;
    if !(math::abs(det) >= CORNER_SIN) {
        return None;
    }
    let corner = Point::new(
        q.x + (by * -da - ay * -db) / det,
        q.y + (ax * -db - bx * -da) / det,
    );
    let cross = |p: &Point, c: &Point| p.x * c.y - p.y * c.x;
    // The scan's turning sense, from the beams either side.
    let sense = cross(before, after);
    let (from, to) = (
        cross(before, &corner) * sense,
        cross(&corner, after) * sense,
    );
    let ahead = corner.x * q.x + corner.y * q.y > 0.0;
    if !(from > 0.0 && to > 0.0 && ahead) {
        return None;
    }
    let contested = points.get(lo..hi)?;
    // Too close to a beam to tell which side it passes: the distances decide.
    let norm = |p: &Point| math::sqrt(p.x * p.x + p.y * p.y);
    let step = sense.abs() / (norm(before) * norm(after) * (hi - lo + 1) as f32);
    let near = contested
        .iter()
        .any(|p| math::abs(cross(p, &corner)) < CORNER_MARGIN * step * norm(p) * norm(&corner));
    if near {
        return None;
    }
    let on_left = contested
        .iter()
        .take_while(|p| cross(p, &corner) * sense > 0.0)
        .count();
    // Each contested point lies on the line of its side (an arc's chord, extrapolated,
    // leaves the arc's points).
    let (l, r) = contested.split_at(on_left.min(contested.len()));
    let on = |line: &LineAxis, pts: &[Point]| {
        pts.iter()
            .all(|p| math::abs(line.signed_distance(p)) <= tol)
    };
    (on(left, l) && on(right, r)).then_some(lo + on_left)
}

/// How far (in σ_r) each contested point may lie from the line of its side for
/// [`corner_split`].
const CONTESTED_SIGMAS: f32 = 2.5;

/// How close (in beam steps) the corner may lie to a contested beam for [`corner_split`].
const CORNER_MARGIN: f32 = 0.3;

/// The sine of the least angle between two lines for [`corner_split`] to place their corner.
const CORNER_SIN: f32 = 0.5;

/// How far (in σ_r) every point of both lines lies from its line at most for [`corner_split`]
/// to place their corner.
const STRAIGHT_SIGMAS: f32 = 3.0;

/// `x²`.
fn sq(x: f32) -> f32 {
    x * x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 40 points: the wall y = 0 (x = 100 i) to point `at − 1`, then the wall x = `corner_x`
    /// (y = 100 (i − at + 1)) from point `at`.
    fn corner_at(corner_x: f32, at: usize) -> [Point; 40] {
        core::array::from_fn(|i| {
            if i < at {
                Point::new(100.0 * i as f32, 0.0)
            } else {
                Point::new(corner_x, 100.0 * (i as f32 - at as f32 + 1.0))
            }
        })
    }

    fn corner(corner_x: f32) -> [Point; 40] {
        corner_at(corner_x, 20)
    }

    /// [`locate`] on the wall x = 1024 mm (y = 16 i − 512) with point i `off(i)` mm behind
    /// it, its segment from 0, a break detected at 20: the boundary, and the predictions it
    /// counted.
    fn located_on_wall(off: &dyn Fn(usize) -> f32) -> Option<(usize, usize)> {
        use crate::extractor::Extractor;
        use crate::flags::VALID;
        use crate::output::Stats;
        use crate::scan::{Scan, ScanGeometry};
        let at = |i: usize| Point::new(1024.0 + off(i), 16.0 * i as f32 - 512.0);
        let points: [Point; 361] = core::array::from_fn(at);
        let ranges: [f32; 361] = core::array::from_fn(|i| {
            let p = at(i);
            math::sqrt(p.x * p.x + p.y * p.y)
        });
        let mut flags = [VALID; 361];
        let mut ex = Extractor::<361, 8>::new();
        let config = crate::config::Config::default();
        let loading = [1000.0f32; 361];
        ex.with_pass(
            &Scan::from_mm(ScanGeometry::LMS200_180_050, &loading),
            &config,
            |loaded, rule| {
                let mut stats = Stats::default();
                let mut pass = Pass::over(
                    loaded.beams,
                    (&points, &ranges, &mut flags),
                    None,
                    &mut stats,
                );
                let at_k = pass.predict(10, 20, 20);
                let before = pass.stats.predictions;
                let b = locate(&mut pass, 0, 20, at_k, rule.noise()?);
                Some((b, pass.stats.predictions - before))
            },
        )
    }

    /// The boundary only of [`located_on_wall`].
    fn located(off: &dyn Fn(usize) -> f32) -> Option<usize> {
        located_on_wall(off).map(|(b, _)| b)
    }

    /// [`locate`] on the wall of [`located_on_wall`]: the points before 20 that lie, as 20
    /// does, 128 mm behind the reference line (the wall through points 6 to 15; about 130 mm
    /// along the beam, far beyond 2.5 σ_r) join the new segment; one in front of it does not;
    /// and when point 20 lies on the reference line (exactly: on x = 1024 every prediction from
    /// it is exact in f32), it has no side and none does.
    #[test]
    fn points_before_a_break_join_it_only_on_its_side() {
        let behind =
            |set: &'static [usize]| move |i: usize| f32::from(u8::from(set.contains(&i))) * 128.0;
        assert_eq!(located(&behind(&[19, 20])), Some(19));
        assert_eq!(located(&behind(&[18, 19, 20])), Some(18));
        assert_eq!(located(&behind(&[16, 17, 18, 19, 20])), Some(16));
        // 19 in front of the wall, 20 behind it.
        let zig = |i: usize| match i {
            19 => -128.0,
            20 => 128.0,
            _ => 0.0,
        };
        assert_eq!(located(&zig), Some(20));
        // 20 back on the wall: no side to share.
        assert_eq!(located(&behind(&[19])), Some(20));
        assert_eq!(located(&behind(&[17, 18, 19])), Some(20));
    }

    /// Every point [`locate`] predicts counts as a prediction, and so does its reference line:
    /// with 19 and 18 behind the wall it predicts 19, 18 and 17 (which stops it), with 16 to 19
    /// all four points it may reach back to; with 20 on the wall (no side), 19, which stops it.
    #[test]
    fn each_point_located_counts_a_prediction() {
        let behind =
            |set: &'static [usize]| move |i: usize| f32::from(u8::from(set.contains(&i))) * 128.0;
        assert_eq!(located_on_wall(&behind(&[18, 19, 20])), Some((18, 4)));
        assert_eq!(
            located_on_wall(&behind(&[16, 17, 18, 19, 20])),
            Some((16, 5))
        );
        assert_eq!(located_on_wall(&behind(&[19])), Some((20, 2)));
    }

    /// The boundary settles where the two fixed lines split the contested points best: at 20
    /// from a detection 1 or 2 points late or 1 early. Where a point lies on both lines (the
    /// apex, here point 19 on x = 1900 too), the split before and after it tie and the detected
    /// boundary is kept when it is one of them, the earlier one otherwise.
    #[test]
    fn a_boundary_settles_between_two_fixed_lines() {
        let pts = corner(1950.0);
        for b in [19, 20, 21, 22] {
            assert_eq!(refine_boundary(&pts, 0, b, 40, 5.0), 20, "detected at {b}");
        }
        let apex = corner(1900.0);
        assert_eq!(refine_boundary(&apex, 0, 20, 40, 5.0), 20);
        assert_eq!(refine_boundary(&apex, 0, 19, 40, 5.0), 19);
        assert_eq!(refine_boundary(&apex, 0, 22, 40, 5.0), 19);
        // A segment that began too close before it (fewer than NP points to the left of the
        // candidates): the detection stands. NP points after the segment's start, the
        // boundary can settle right there (a corner at 5 of a segment from 2, detected at 8).
        assert_eq!(refine_boundary(&pts, 19, 21, 40, 5.0), 21);
        assert_eq!(refine_boundary(&corner_at(550.0, 5), 2, 8, 40, 5.0), 5);
    }

    /// A room's corner 4 m ahead (walls x − y = 4000 and x + y = 4000), beams 0.5° apart, the
    /// corner 0.35 beam after beam 20 or before beam 21: that beam lies on the wall its
    /// bearing meets even when its range is 15 mm long (3 σ_r of 5 mm: nearer the other
    /// wall's line than its own), and the boundary falls where the walls change.
    #[test]
    fn a_beam_goes_with_the_wall_its_bearing_meets() {
        let step = 0.5f32.to_radians();
        let scan = |corner: f32, long: usize| -> [Point; 40] {
            core::array::from_fn(|i| {
                let t = (i as f32 - corner) * step;
                let (s, c) = math::sin_cos(t);
                let r = 4000.0 / if t < 0.0 { c - s } else { c + s };
                let r = r + if i == long { 15.0 } else { 0.0 };
                Point::new(r * c, r * s)
            })
        };
        for b in [20, 21, 22] {
            for corner in [20.35, 20.65] {
                assert_eq!(refine_boundary(&scan(corner, 99), 0, b, 40, 5.0), 21);
                for long in [20, 21] {
                    let pts = scan(corner, long);
                    assert_eq!(
                        refine_boundary(&pts, 0, b, 40, 5.0),
                        21,
                        "{corner} {long} {b}"
                    );
                }
            }
        }
    }

    /// [`corner_split`] leaves the split to the squared distances (`None`) when the corner lies
    /// within [`CORNER_MARGIN`] (0.3) of a contested beam's bearing, and splits by bearing
    /// otherwise: the room's corner of [`a_beam_goes_with_the_wall_its_bearing_meets`] (no
    /// noise) `at` beams 19.5..=20.9 (its bearing known from the construction), contested
    /// beams 17..=20, the lines fitted to 11..=16 and 21..=26, turned about the scanner (0,
    /// 0.8 rad, ±π/2, π). Off the margin the split is the first beam past the corner.
    #[test]
    fn a_corner_within_the_margin_of_a_beam_is_not_split_by_bearing() {
        let step = 0.5f32.to_radians();
        let (half, pi) = (core::f32::consts::FRAC_PI_2, core::f32::consts::PI);
        for turn in [0.0f32, 0.8, half, -half, pi] {
            for at in [19.5f32, 19.65, 19.9, 20.1, 20.2, 20.4, 20.5, 20.8, 20.9] {
                let pts: [Point; 40] = core::array::from_fn(|i| {
                    let t = (i as f32 - at) * step;
                    let (s, c) = math::sin_cos(t);
                    let r = 4000.0 / if t < 0.0 { c - s } else { c + s };
                    let (s, c) = math::sin_cos(t + turn);
                    Point::new(r * c, r * s)
                });
                let (Ok(left), Ok(right)) = (fit_axis(&pts[11..17]), fit_axis(&pts[21..27])) else {
                    panic!("two walls")
                };
                // The contested beam nearest the corner, in beams.
                let off = (17..=20)
                    .map(|k| (k as f32 - at).abs())
                    .fold(f32::INFINITY, f32::min);
                let expected =
                    (off >= 0.3).then(|| 17 + (17..=20).filter(|&k| (k as f32) < at).count());
                assert_eq!(
                    corner_split(&left, &right, &pts, (17, 21), 12.5),
                    expected,
                    "turn {turn}, corner at {at}"
                );
            }
        }
    }

    /// The room's corner of [`a_beam_goes_with_the_wall_its_bearing_meets`], 0.35 beam after
    /// beam 20, turned about the scanner (0, 0.8 rad, ±π/2, π: the corner's x, then y, across
    /// the beams), beam 21 15 mm long and the point before the contested ones (its left line's
    /// last, about which the corner is solved) 15 mm short, both 3 σ_r: detected at 20, 21 or
    /// 22, the boundary falls where the walls change.
    #[test]
    fn the_corner_is_solved_about_a_point_off_its_line() {
        let step = 0.5f32.to_radians();
        let (half, pi) = (core::f32::consts::FRAC_PI_2, core::f32::consts::PI);
        for turn in [0.0f32, 0.8, half, -half, pi] {
            for b in [20usize, 21, 22] {
                // The point before the contested ones `b − 3..=b`.
                let q = b - 4;
                let pts: [Point; 40] = core::array::from_fn(|i| {
                    let t = (i as f32 - 20.35) * step;
                    let (s, c) = math::sin_cos(t);
                    let r = 4000.0 / if t < 0.0 { c - s } else { c + s };
                    let r = r + match i {
                        21 => 15.0,
                        _ if i == q => -15.0,
                        _ => 0.0,
                    };
                    let (s, c) = math::sin_cos(t + turn);
                    Point::new(r * c, r * s)
                });
                assert_eq!(refine_boundary(&pts, 0, b, 40, 5.0), 21, "{turn} {b}");
            }
        }
    }
}
