//! The typing's decisions at their bounds and the covariance additions, against values worked
//! out by hand (exact in f32) or in f64.
#![allow(clippy::indexing_slicing)]

use super::*;

/// `n` points on the circle of centre `c` and radius `r` from `from` over `span` rad.
fn arc(n: usize, c: (f32, f32), r: f32, from: f32, span: f32) -> heapless::Vec<Point, 64> {
    (0..n)
        .map(|i| {
            let t = from + span * i as f32 / (n - 1) as f32;
            Point::new(c.0 + r * libm::cosf(t), c.1 + r * libm::sinf(t))
        })
        .collect()
}

/// var 1, dof 2: the expected sum is 2, scaled when (sse − 2)² · 2 > 18 · 2², i.e. beyond
/// sse = 8; dof 18: beyond twice the expected sum. Never below 1, never for dof < 1.
#[test]
fn scatter_scales_only_beyond_three_spreads_of_its_expectation() {
    assert_eq!(scatter_scale(8.0, 1.0, 2.0), 1.0);
    assert_eq!(scatter_scale(8.5, 1.0, 2.0), 4.25);
    assert_eq!(scatter_scale(35.0, 1.0, 18.0), 1.0);
    assert_eq!(scatter_scale(37.0, 1.0, 18.0), 37.0 / 18.0);
    assert_eq!(scatter_scale(100.0, 1.0, 1.0), 100.0);
    assert_eq!(scatter_scale(100.0, 1.0, 0.5), 1.0);
    assert_eq!(scatter_scale(0.1, 1.0, 18.0), 1.0);
    assert_eq!(scatter_scale(5.0, 0.0, 5.0), 1.0);
    assert_eq!(scatter_scale(f32::INFINITY, 1.0, 5.0), 1.0);
}

/// An arc is at least 6 points and 30° between its ends (here around a centre away from the
/// origin, clockwise and counter-clockwise), and beats the best two-line split by `margin`.
#[test]
fn an_arc_needs_six_points_thirty_degrees_and_the_margin() {
    let (c, r) = ((3000.0, -1200.0), 400.0);
    let circle = Circle {
        center: Point::new(c.0, c.1),
        radius: r,
    };
    let deg = core::f32::consts::PI / 180.0;
    for dir in [1.0f32, -1.0] {
        let wide = arc(8, c, r, 1.0, dir * 31.0 * deg);
        let narrow = arc(8, c, r, 1.0, dir * 29.0 * deg);
        assert!(is_arc(&wide, &circle, 0.0, 0.0));
        assert!(!is_arc(&narrow, &circle, 0.0, 0.0));
        // Beyond 90°, and beyond 180° (ends 160° apart).
        assert!(is_arc(
            &arc(8, c, r, 1.0, dir * 120.0 * deg),
            &circle,
            0.0,
            0.0
        ));
        assert!(is_arc(
            &arc(8, c, r, 1.0, dir * 200.0 * deg),
            &circle,
            0.0,
            0.0
        ));
    }
    let six = arc(6, c, r, 0.3, 60.0 * deg);
    assert!(is_arc(&six, &circle, 0.0, 0.0));
    assert!(!is_arc(&six[..5], &circle, 0.0, 0.0));
    // The margin: the split's residual sum minus the circle's must exceed it.
    let split = best_split_sse(&six).unwrap_or(0.0);
    assert!(split > 1.0, "{split}");
    let sse_c = 0.25 * split;
    let gain = split - sse_c;
    assert!(is_arc(&six, &circle, sse_c, gain * 0.99));
    assert!(!is_arc(&six, &circle, sse_c, gain));
    assert!(!is_arc(&six, &circle, split, 0.0));
}

/// σ_sys on a line of length 2 m whose middle lies 1 m along it from the foot of its normal:
/// var_ρ + s² + tilt·1000², var_α + tilt, cov + tilt·1000, tilt = 2s²/L². A line of no length
/// or no σ_sys is left as it is.
#[test]
fn systematic_line_adds_offset_and_tilt() {
    let line = |start: Point, end: Point| LineFeature {
        first: 0,
        last: 9,
        points: 10,
        alpha: 0.0,
        rho: 2000.0,
        var_alpha: 1e-6,
        var_rho: 4.0,
        cov_alpha_rho: 1e-4,
        start,
        end,
    };
    // α = 0: the line x = 2000, direction (0, 1); M = (2000, 1000).
    let mut lf = line(Point::new(2000.0, 0.0), Point::new(2000.0, 2000.0));
    systematic_line(&mut lf, 5.0);
    let tilt = 2.0 * 25.0 / 4.0e6;
    assert!((lf.var_alpha - (1e-6 + tilt)).abs() < 1e-12);
    assert!((lf.cov_alpha_rho - (1e-4 + tilt * 1000.0)).abs() < 1e-8);
    assert!((lf.var_rho - (4.0 + 25.0 + tilt * 1.0e6)).abs() < 1e-4);
    // α = 45°, from 500 mm before the foot of the normal to 1500 mm after it: M is 500 mm along.
    let (sin, cos) = (
        core::f32::consts::FRAC_1_SQRT_2,
        core::f32::consts::FRAC_1_SQRT_2,
    );
    let at = |u: f32| Point::new(2000.0 * cos - u * sin, 2000.0 * sin + u * cos);
    let mut lf = LineFeature {
        alpha: core::f32::consts::FRAC_PI_4,
        ..line(at(-500.0), at(1500.0))
    };
    systematic_line(&mut lf, 5.0);
    assert!((lf.var_alpha - (1e-6 + tilt)).abs() < 1e-10, "{lf:?}");
    assert!(
        (lf.cov_alpha_rho - (1e-4 + tilt * 500.0)).abs() < 1e-7,
        "{lf:?}"
    );
    assert!(
        (lf.var_rho - (4.0 + 25.0 + tilt * 2.5e5)).abs() < 1e-4,
        "{lf:?}"
    );
    for (s, a, b) in [
        (5.0, Point::new(2000.0, 500.0), Point::new(2000.0, 500.0)),
        (0.0, Point::new(2000.0, 0.0), Point::new(2000.0, 2000.0)),
    ] {
        let mut lf = line(a, b);
        systematic_line(&mut lf, s);
        assert_eq!(lf, line(a, b));
    }
}

/// σ_sys on a circle's centre: s² along the beam from the scanner's origin (here not the
/// frame's) to the centre; nothing when the centre is at the origin or s is 0.
#[test]
fn systematic_circle_adds_along_the_beam_from_its_origin() {
    let circle = |x: f32, y: f32| CircleFeature {
        first: 0,
        last: 9,
        points: 10,
        center: Point::new(x, y),
        radius: 150.0,
        cov: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        start_angle: 0.0,
        end_angle: 1.0,
    };
    let origin = Point::new(-300.0, 400.0);
    // Centre 3 m along x and 4 m along y from the origin: u = (0.6, 0.8).
    let mut cf = circle(2700.0, 4400.0);
    systematic_circle(&mut cf, origin, 5.0);
    let want = [
        [1.0 + 25.0 * 0.36, 25.0 * 0.48],
        [25.0 * 0.48, 1.0 + 25.0 * 0.64],
    ];
    for (i, row) in want.iter().enumerate() {
        for (j, v) in row.iter().enumerate() {
            assert!((cf.cov[i][j] - v).abs() < 1e-4, "{:?}", cf.cov);
        }
    }
    assert_eq!(cf.cov[2], [0.0, 0.0, 1.0]);
    for (s, at) in [(5.0, origin), (0.0, Point::new(2700.0, 4400.0))] {
        let mut cf = circle(at.x, at.y);
        systematic_circle(&mut cf, origin, s);
        assert_eq!(cf, circle(at.x, at.y));
    }
}
