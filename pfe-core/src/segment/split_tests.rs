//! [`bump`]'s and [`corner`]'s first tests at their bound: a line is searched for a bump, or
//! split at a corner, only when its residual sum exceeds the noise's, `σ_r² (n − 2)`; equal is
//! not enough.
#![allow(clippy::indexing_slicing)]

use super::*;
use crate::rule::Rule;

/// Points every 10 mm along a wall 2 m ahead, over 5 130 mm centred on the bearing 0, with a
/// pillar of `radius` mm standing out of it (its centre on the wall line).
fn pillar_on_wall(radius: f32) -> [Point; 514] {
    wall_with_pillar(-2565.0, radius)
}

/// `N` points every 10 mm along a wall 2 m ahead from `x0`, with a pillar of `radius` mm
/// centred on the wall line at x = 0.
fn wall_with_pillar<const N: usize>(x0: f32, radius: f32) -> [Point; N] {
    core::array::from_fn(|k| {
        let x = x0 + 10.0 * k as f32;
        let bulge = if x.abs() < radius {
            math::sqrt(radius * radius - x * x)
        } else {
            0.0
        };
        Point::new(x, 2000.0 - bulge)
    })
}

fn bump_at(pts: &[Point], line: &LineFit, sigma_r: f32) -> Option<(usize, usize)> {
    let config = Config::default().with_sigma_r(sigma_r);
    let rule = Rule::new(&config, 8000.0, 0.02);
    bump(pts, line, rule.noise()?, &config)
}

/// The σ_r near √(sse / (n − 2)) whose `σ_r² (n − 2)` is `sse` in f32, if one is.
fn tie(sse: f32, n: usize) -> Option<f32> {
    let s0 = math::sqrt(sse / (n as f32 - 2.0));
    (-8i32..=8)
        .map(|k| f32::from_bits(s0.to_bits().wrapping_add_signed(k)))
        .find(|&s| s * s * (n as f32 - 2.0) == sse)
}

/// A pillar against a wall, the σ_r set so that the noise's residual sum equals the line's
/// exactly: not searched. One f32 step lower in σ_r (the line's sum beyond the noise's), the
/// bump is found: the pillar's points (x within ±100 mm: 247 to 266) and no more than the
/// 150 mm of wall beside it that lie within 3 σ_r of its circle.
#[test]
fn a_line_whose_residual_sum_equals_the_noises_is_not_searched_for_a_bump() {
    // Radii a little apart until one gives an exact tie (the squares of f32 σ_r hit about
    // every other f32; 512 = n − 2 scales exactly).
    let found = (0..32).find_map(|k| {
        let pts = pillar_on_wall(100.0 + 0.25 * k as f32);
        let line = fit_line(&pts).ok()?;
        Some((pts, line, tie(line.sse(), pts.len())?))
    });
    let Some((pts, line, sigma_r)) = found else {
        panic!("no exact tie");
    };
    assert!(sigma_r > 10.0 && sigma_r < 40.0, "{sigma_r}");
    assert_eq!(bump_at(&pts, &line, sigma_r), None);
    let below = f32::from_bits(sigma_r.to_bits() - 1);
    let found = bump_at(&pts, &line, below);
    assert!(
        matches!(found, Some((i, j)) if i <= 247 && j >= 266 && i >= 232 && j <= 281),
        "{found:?}"
    );
}

/// An exact V of 34 points (legs ±`slope` mm a point, 100 mm apart, apex at 17).
fn v34(slope: f32) -> [Point; 34] {
    core::array::from_fn(|i| {
        let t = i as f32 - 17.0;
        Point::new(100.0 * t, slope * t.abs())
    })
}

/// [`corner`]'s first test at its bound, as [`bump`]'s above: a V whose line's residual sum
/// equals the noise's `σ_r² (n − 2)` exactly is not split; one f32 step lower in σ_r it is,
/// at its apex (two lines leave nothing there; 32 degrees of freedom > chi2 25, so the other
/// tests pass either way).
#[test]
fn a_corner_whose_line_sum_equals_the_noises_is_not_split() {
    // Slopes a little apart until one gives an exact tie (32 = n − 2 scales exactly).
    let found = (0..64).find_map(|k| {
        let pts = v34(20.0 + 0.125 * k as f32);
        let line = fit_line(&pts).ok()?;
        Some((pts, line, tie(line.sse(), pts.len())?))
    });
    let Some((pts, line, sigma_r)) = found else {
        panic!("no exact tie");
    };
    let at = |s: f32| corner(&pts, &line, &Config::default().with_sigma_r(s));
    assert_eq!(at(sigma_r), None, "σ_r {sigma_r}");
    let below = f32::from_bits(sigma_r.to_bits() - 1);
    assert_eq!(at(below), Some(17), "σ_r {sigma_r}, sse {}", line.sse());
}

/// A segment that is one arc end to end (a pillar's front, radius 300 mm, 1.5 m ahead, 40
/// points over ±60° of it) is no bump on a line: the whole run lies on the circle, and a bump
/// is a strict part of its segment (the typing, not the split, makes it a circle). A pillar on
/// a wall, the same arc with wall beside it, is one.
#[test]
fn an_arc_from_end_to_end_is_no_bump() {
    let (r, d) = (300.0f32, 1500.0f32);
    let arc: [Point; 40] = core::array::from_fn(|k| {
        let a = (-60.0 + 120.0 * k as f32 / 39.0).to_radians();
        let (s, c) = math::sin_cos(a);
        Point::new(r * s, d - r * c)
    });
    let Ok(line) = fit_line(&arc) else {
        panic!("the arc's line")
    };
    assert_eq!(bump_at(&arc, &line, 5.0), None);
    let pts = pillar_on_wall(r);
    let Ok(line) = fit_line(&pts) else {
        panic!("the wall's line")
    };
    assert!(bump_at(&pts, &line, 5.0).is_some());
}

/// [`peak`] fits the wall again from the far half of the bump's longer side, when that half
/// holds `min_points` points. A wall (y = 1000 mm, a point every 100 mm) with a bump of three
/// points 100 mm out (2..=4) and one point 15 mm out beside it (5): the fit of all the points,
/// pulled by the bump, leaves that point on its other side, so the first run is 2..=4; the
/// wall fitted again from the exact points of the far half finds 2..=5 (15 mm beyond 2 σ_r).
/// With 6 points on the longer side its far half is 3 points, too few to fit (2..=4 stays);
/// with 8, 4 points: 2..=5.
#[test]
fn a_bump_s_wall_is_fitted_again_from_the_far_half_of_its_longer_side() {
    let config = Config {
        min_points: 4,
        ..Config::default()
    }
    .with_sigma_r(5.0);
    for (n, want) in [(11usize, (2usize, 4usize)), (12, (2, 5)), (13, (2, 5))] {
        let pts: heapless::Vec<Point, 16> = (0..n)
            .map(|k| {
                let out = match k {
                    2..=4 => 100.0,
                    5 => 15.0,
                    _ => 0.0,
                };
                Point::new(100.0 * k as f32, 1000.0 - out)
            })
            .collect();
        let line = fit_line(&pts).unwrap();
        assert_eq!(peak(&pts, line, &config), Some(want), "{n} points");
    }
}

/// A segment that starts on a pillar (radius 100 mm, centre on a wall 2 m ahead) 50 mm before
/// its apex, a point every 10 mm, 20 in all: its largest residuals run from the segment's first
/// point but are not the whole arc (the line is pulled by the pillar), and the arc at that end
/// is found as one side of the segment's best two-line split. The bump holds every point of
/// the pillar (x < 100 mm: the first 15) and only points within 3 σ_r of its circle. The scene
/// seen the other way round (the pillar at the segment's end) gives the same bump reversed.
#[test]
fn a_pillar_at_the_segment_s_start_that_the_peak_misses_is_found() {
    let (r, c) = (100.0f32, Point::new(0.0, 2000.0));
    let pts: [Point; 20] = wall_with_pillar(-50.0, r);
    let Ok(line) = fit_line(&pts) else {
        panic!("the segment's line")
    };
    let Some((i, j)) = bump_at(&pts, &line, 5.0) else {
        panic!("no bump")
    };
    assert!(i == 0 && (14..19).contains(&j), "{i}..={j}");
    assert!(
        pts[i..=j]
            .iter()
            .all(|p| (p.distance(&c) - r).abs() <= 15.0),
        "{i}..={j}"
    );
    let mut rev = pts;
    rev.reverse();
    let Ok(line) = fit_line(&rev) else {
        panic!("the segment's line")
    };
    assert_eq!(bump_at(&rev, &line, 5.0), Some((19 - j, 19)));
}

/// A shallow V of 12 points (legs ±1 mm a point, 100 mm apart, apex at 6) seen with a small
/// σ_r (0.5 mm, under 1 mm where σ_r² and 1/σ_r² swap order): its line's residual sum (about
/// 36 mm²) is far beyond the noise's (`σ_r² (n − 2)` = 2.5 mm²) and beyond `chi2 σ_r²`
/// (6.25 mm², not `chi2 / σ_r²`), and two lines leave nothing: split at its apex.
#[test]
fn a_shallow_corner_at_a_small_sigma_is_split_at_its_apex() {
    let pts: [Point; 12] = core::array::from_fn(|i| {
        let t = i as f32 - 6.0;
        Point::new(100.0 * t, t.abs())
    });
    let Ok(line) = fit_line(&pts) else {
        panic!("a line fits 12 points");
    };
    // The line's residual sum from f64 sums: the band the test is about (above chi2 σ_r² =
    // 6.25, below chi2 / σ_r² = 100).
    let n = pts.len() as f64;
    let (mx, my) = pts.iter().fold((0.0, 0.0), |(x, y), p| {
        (x + f64::from(p.x) / n, y + f64::from(p.y) / n)
    });
    let (sxx, syy, sxy) = pts.iter().fold((0.0, 0.0, 0.0), |(a, b, c), p| {
        let (dx, dy) = (f64::from(p.x) - mx, f64::from(p.y) - my);
        (a + dx * dx, b + dy * dy, c + dx * dy)
    });
    let sse = 0.5 * (sxx + syy - ((sxx - syy) * (sxx - syy) + 4.0 * sxy * sxy).sqrt());
    assert!(sse > 6.25 && sse < 100.0, "{sse}");
    assert!(
        (f64::from(line.sse()) - sse).abs() < 1e-3 * sse,
        "{} {sse}",
        line.sse()
    );
    let config = Config::default().with_sigma_r(0.5);
    assert_eq!(corner(&pts, &line, &config), Some(6));
}
