//! A door jamb's face seen with one beam of the wall round its corner: a line, not an object.
#![allow(clippy::indexing_slicing)]

use crate::extractor::Extractor;
use crate::feature::Feature;
use crate::geometry::{ray_circle_intersection, Point};
use crate::scan::{Scan, ScanGeometry};
use crate::Config;

/// Range along the beam of bearing (cos, sin) = (`c`, `s`) to the segment `p`–`q`.
fn ray_segment(c: f32, s: f32, p: Point, q: Point) -> Option<f32> {
    let (ex, ey) = (q.x - p.x, q.y - p.y);
    let det = c * -ey + s * ex;
    if det == 0.0 {
        return None;
    }
    // t (c, s) = p + u e.
    let t = (p.x * -ey + p.y * ex) / det;
    let u = (c * p.y - s * p.x) / det;
    (t > 0.0 && (0.0..=1.0).contains(&u)).then_some(t)
}

/// `f` on a pass over hand-made `points`, `ranges` and `flags` (LMS200 180° at 0.5°, no
/// motion): the beams of a loaded scan, the points the test placed.
fn on_hand_made<R>(
    points: &[Point; 361],
    ranges: &[f32; 361],
    flags: &mut [u8; 361],
    f: impl FnOnce(&crate::pass::Pass<'_>) -> R,
) -> R {
    let mut ex = Extractor::<361, 8>::new();
    let loading = [1000.0f32; 361];
    ex.with_pass(
        &Scan::from_mm(ScanGeometry::LMS200_180_050, &loading),
        &Config::default(),
        |loaded, _| {
            let mut stats = crate::output::Stats::default();
            let pass =
                crate::pass::Pass::over(loaded.beams, (points, ranges, flags), None, &mut stats);
            f(&pass)
        },
    )
}

/// A door jamb 5.3 m ahead (corridor seed 1, scan 21 of `pfe eval`'s simulator): its face,
/// 275 mm wide, seen head-on over beams 200–204, the wall it turns into running away from the
/// scanner at grazing incidence (beam 199, no return before it), a pillar 1.4 m behind the
/// face's far edge (beam 205), then the corridor's other wall. Ranges from the geometry, those
/// of beams 199–204 the simulator's noisy draw (σ_r = 5 mm): the wall's beam lies 26 mm off
/// the face's line. The run 199–205 between range jumps was a small object on a surface the
/// truth lists as a line; the face is its line (within 3 σ of the true one), beam 199 in no
/// feature.
#[test]
fn a_jamb_face_with_a_beam_of_the_wall_is_a_line() {
    let g = ScanGeometry::LMS200_180_050;
    let config = Config::default();
    let corner = Point::new(5225.7, 876.9);
    let face = (Point::new(5212.7, 1151.4), corner);
    let wall = (corner, Point::new(5438.8, 887.0));
    // Beyond the face's far edge: a pillar 1.4 m behind it, then the corridor's other wall.
    let far_wall = (Point::new(5025.4, 1142.5), Point::new(-2239.1, 796.7));
    let (pillar, radius) = (Point::new(6771.0, 1366.8), 243.0);
    let hit = |i: usize| {
        let (s, c) = crate::math::sin_cos(g.bearing(i));
        let f = ray_segment(c, s, face.0, face.1).unwrap_or(f32::INFINITY);
        let w = ray_segment(c, s, wall.0, wall.1).unwrap_or(f32::INFINITY);
        let o = ray_segment(c, s, far_wall.0, far_wall.1).unwrap_or(f32::INFINITY);
        let p = ray_circle_intersection(Point::new(0.0, 0.0), c, s, pillar, radius)
            .unwrap_or(f32::INFINITY);
        (f.min(w).min(o).min(p), f < w.min(o).min(p))
    };
    let on_face: heapless::Vec<usize, 361> = (0..361).filter(|&i| hit(i).1).collect();
    assert_eq!(on_face.as_slice(), &[200, 201, 202, 203, 204]);
    assert!(hit(199).0.is_finite() && !hit(198).0.is_finite());
    let draw = [5331.0, 5305.0, 5300.0, 5321.0, 5327.0, 5339.0];
    let ranges: [f32; 361] = core::array::from_fn(|i| match i {
        199..=204 => draw[i - 199],
        _ if hit(i).0.is_finite() => libm::roundf(hit(i).0),
        _ => 0.0,
    });
    let mut ex = Extractor::<361, 16>::new();
    assert!(ex.extract(&Scan::from_mm(g, &ranges), &config).is_ok());
    let f = ex.features();
    assert!(
        !f.iter()
            .any(|f| !f.is_line() && f.first() <= 204 && f.last() >= 199),
        "{f:?}"
    );
    let Some(Feature::Line(l)) = f.iter().find(|f| f.first() <= 204 && f.last() >= 200) else {
        panic!("no line on the face: {f:?}")
    };
    assert_eq!((l.first, l.last), (200, 204));
    // The face's true line: normal along the face's perpendicular, ρ its distance.
    let (ex_, ey) = (face.1.x - face.0.x, face.1.y - face.0.y);
    let len = libm::sqrtf(ex_ * ex_ + ey * ey);
    let (nx, ny) = (ey / len, -ex_ / len);
    let (nx, ny) = if nx * face.0.x + ny * face.0.y < 0.0 {
        (-nx, -ny)
    } else {
        (nx, ny)
    };
    let (rho, alpha) = (nx * face.0.x + ny * face.0.y, libm::atan2f(ny, nx));
    let (sa, ca) = crate::math::sin_cos(l.alpha - alpha);
    let da = libm::atan2f(sa, ca);
    let dr = if ca > 0.0 { l.rho - rho } else { l.rho + rho };
    assert!(
        da * da <= 9.0 * l.var_alpha && dr * dr <= 9.0 * l.var_rho,
        "Δα {da}, Δρ {dr}, σ {} {}",
        libm::sqrtf(l.var_alpha),
        libm::sqrtf(l.var_rho)
    );
}

/// [`super::one_segment`] counts the run as one segment and what lies outside it of the segment
/// that held it as a short segment of its own: a degenerate segment over beams 3..=10 (8 points,
/// `min_points` 4) whose run 5..=10 becomes the object's keeps beams 3..=4 as a short segment.
/// Before: one segment, degenerate; after: two segments, one short, none degenerate, marked
/// 3..=4 and 5..=10.
#[test]
fn the_segment_s_points_before_the_run_stay_a_short_segment() {
    use crate::flags::{END, START};
    let g = ScanGeometry::LMS200_180_050;
    let ranges = [3000.0f32; 361];
    let mut ex = Extractor::<361, 16>::new();
    ex.with_pass(&Scan::from_mm(g, &ranges), &Config::default(), |pass, _| {
        for k in 0..20 {
            pass.clear(k, START | END);
        }
        pass.set(3, START);
        pass.set(10, END);
        *pass.stats = crate::output::Stats::default();
        pass.stats.segments = 1;
        pass.stats.degenerate = 1;
        super::one_segment(pass, 5, 10, 3, 10, 4);
        let s = &*pass.stats;
        assert_eq!(
            (s.segments, s.short_segments, s.degenerate),
            (2, 1, 0),
            "{s:?}"
        );
        let marks: heapless::Vec<(usize, u8), 8> = (0..20)
            .filter(|&k| pass.flag(k) & (START | END) != 0)
            .map(|k| (k, pass.flag(k) & (START | END)))
            .collect();
        assert_eq!(
            marks.as_slice(),
            &[(3, START), (4, END), (5, START), (10, END)]
        );
    });
}

/// `off_line` of a beam beyond the end of a tilted wall's points is its squared distance from
/// their line over the variance of its residual, σ_r² (1 + 1/n + u²/Σu²), u its position along
/// the line from the points' centroid and Σu² the points' spread along it: all computed here
/// in f64 from the points (total-least-squares line through them).
#[test]
fn off_line_weighs_the_distance_by_the_lines_spread_along_it() {
    // A wall y = 0.5 x + 2000 (mm), beams 100..=109 with ±4 mm alternating offsets across
    // it, and beam 115 30 mm off it, 150 mm beyond its last point along it.
    let (tx, ty) = (2.0 / libm::sqrt(5.0), 1.0 / libm::sqrt(5.0));
    let (nx, ny) = (-ty, tx);
    let at = |t: f64, off: f64| (1000.0 * tx + t * tx + off * nx, 2500.0 + t * ty + off * ny);
    let mut points = [Point::INVALID; 361];
    let mut ranges = [f32::NAN; 361];
    for k in 0u32..10 {
        let (x, y) = at(50.0 * f64::from(k), if k % 2 == 0 { 4.0 } else { -4.0 });
        points[100 + k as usize] = Point::new(x as f32, y as f32);
    }
    let (x, y) = at(600.0, 30.0);
    points[115] = Point::new(x as f32, y as f32);
    for (p, r) in points.iter().zip(ranges.iter_mut()) {
        if p.x.is_finite() {
            *r = libm::hypotf(p.x, p.y);
        }
    }
    let mut flags: [u8; 361] = core::array::from_fn(|i| match ranges[i].is_finite() {
        true => crate::flags::VALID,
        false => 0,
    });
    // The reference, in f64.
    let pts: [(f64, f64); 10] =
        core::array::from_fn(|i| (f64::from(points[100 + i].x), f64::from(points[100 + i].y)));
    let n = pts.len() as f64;
    let (cx, cy) = (
        pts.iter().map(|p| p.0).sum::<f64>() / n,
        pts.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let (mut sxx, mut syy, mut sxy) = (0.0f64, 0.0f64, 0.0f64);
    for p in &pts {
        sxx += (p.0 - cx) * (p.0 - cx);
        syy += (p.1 - cy) * (p.1 - cy);
        sxy += (p.0 - cx) * (p.1 - cy);
    }
    // Direction of the line: the principal axis of the scatter.
    let theta = 0.5 * libm::atan2(2.0 * sxy, sxx - syy);
    let (dx, dy) = (libm::cos(theta), libm::sin(theta));
    let suu: f64 = pts
        .iter()
        .map(|p| ((p.0 - cx) * dx + (p.1 - cy) * dy).powi(2))
        .sum();
    let (px, py) = (f64::from(points[115].x), f64::from(points[115].y));
    let u = (px - cx) * dx + (py - cy) * dy;
    let d = -(px - cx) * dy + (py - cy) * dx;
    let var_r = 25.0f64;
    let want = d * d / (var_r * (1.0 + 1.0 / n + u * u / suu));
    // The line's own variance there is a sizeable part of the residual's.
    assert!(u * u / suu > 0.5, "{}", u * u / suu);
    let got = on_hand_made(&points, &ranges, &mut flags, |pass| {
        super::off_line(pass, 100, 109, 115, var_r as f32)
    });
    let got = f64::from(got.expect("the points fit a line"));
    assert!((got - want).abs() <= 1e-3 * want, "{got} vs {want}");
}

/// `segment_bounds` of a run inside one segment (beams 10..=20, marked START at 10 and END at
/// 20) that starts two beams after the segment's first point: the bounds are the segment's own
/// first and last points, (10, 20), the segment keeping 2 < `min_points` points outside the run.
#[test]
fn segment_bounds_walk_back_to_the_segments_start() {
    use crate::flags::{END, START, VALID};
    let mut points = [Point::INVALID; 361];
    let mut ranges = [f32::NAN; 361];
    let mut flags = [0u8; 361];
    for i in 10..=20 {
        points[i] = Point::new(3000.0, 100.0 * (i as f32 - 15.0));
        ranges[i] = libm::hypotf(points[i].x, points[i].y);
        flags[i] = VALID;
    }
    flags[10] |= START;
    flags[20] |= END;
    let got = on_hand_made(&points, &ranges, &mut flags, |pass| {
        super::segment_bounds(pass, 12, 20, 5)
    });
    assert_eq!(got, Some((10, 20)));
}
