//! Small geometric and fitting contracts at their edges, each against exact values or an f64
//! reference (how they were found: docs/TESTING.md, "Mutation testing"): points and rays,
//! window lines and predictions, the paper's threshold, a sweep's rigid offset, the circle and
//! line fits at their edges.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

use pfe_core::predict::WindowLine;
use pfe_core::Point;

/// `Point` and `[x, y]` convert both ways without changing a coordinate; a point is valid only
/// when both coordinates are finite.
#[test]
fn points_convert_to_and_from_pairs_and_need_both_coordinates_finite() {
    let p = Point::from([1.5, -2.25]);
    assert_eq!((p.x, p.y), (1.5, -2.25));
    assert_eq!(<[f32; 2]>::from(Point::new(3.0, 4.5)), [3.0, 4.5]);
    assert!(Point::new(1.0, 2.0).is_valid());
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        assert!(!Point::new(bad, 2.0).is_valid(), "x = {bad}");
        assert!(!Point::new(1.0, bad).is_valid(), "y = {bad}");
    }
}

/// The ray–circle intersection at its edges, where every value is exact in f32: from a point
/// on the circle looking in, the far side (2r along the diameter); looking out or along the
/// tangent, nothing; from outside, the near side.
#[test]
fn a_ray_meets_a_circle_at_its_nearest_point_ahead() {
    use pfe_core::geometry::ray_circle_intersection as hit;
    let o = Point::new(0.0, 0.0);
    // On the circle, into it: b = r, disc = r², b − √disc = 0 exactly.
    assert_eq!(hit(o, 1.0, 0.0, Point::new(2.0, 0.0), 2.0), Some(4.0));
    // On the circle, out of it.
    assert_eq!(hit(o, -1.0, 0.0, Point::new(2.0, 0.0), 2.0), None);
    // On the circle, along its tangent: the only meeting is at t = 0, not ahead.
    assert_eq!(hit(o, 1.0, 0.0, Point::new(0.0, 2.0), 2.0), None);
    // From outside: the near side, 3 along the ray; from a moved origin the same.
    assert_eq!(hit(o, 1.0, 0.0, Point::new(5.0, 0.0), 2.0), Some(3.0));
    assert_eq!(
        hit(Point::new(1.0, 1.0), 0.0, 1.0, Point::new(1.0, 6.0), 2.0),
        Some(3.0)
    );
    // Behind the origin: nothing ahead.
    assert_eq!(hit(o, -1.0, 0.0, Point::new(5.0, 0.0), 2.0), None);
}

/// A window whose points coincide has no direction: no line, from two points or more.
#[test]
fn a_window_of_one_repeated_point_has_no_line() {
    let p = Point::new(1500.0, -250.0);
    let o = Point::new(0.0, 0.0);
    assert!(WindowLine::fit(&[p, p], o).is_none());
    assert!(WindowLine::fit(&[p, p, p], o).is_none());
    assert!(WindowLine::fit(&[p, p, p, p, p], o).is_none());
    assert!(WindowLine::fit(&[p, Point::new(1500.0, -240.0), p], o).is_some());
}

/// A window's line through the scanner meets every other beam at the scanner itself (t = 0,
/// exactly here: points on y = x): no prediction ahead, an infinite error, as behind it.
#[test]
fn a_line_through_the_scanner_predicts_nothing_ahead() {
    let w = [
        Point::new(1000.0, 1000.0),
        Point::new(1100.0, 1100.0),
        Point::new(1200.0, 1200.0),
    ];
    let o = Point::new(0.0, 0.0);
    let line = WindowLine::fit(&w, o).unwrap();
    let r = 2000.0f32;
    let p = line.predict(o, r, 0.0, r);
    assert!(p.error.is_infinite() && p.signed.is_infinite(), "{p:?}");
    // A line 10 mm off the scanner is met ahead, close to it.
    let off: Vec<Point> = w.iter().map(|q| Point::new(q.x + 10.0, q.y)).collect();
    let p = WindowLine::fit(&off, o).unwrap().predict(o, r, 0.0, r);
    assert!((p.error - (r - 10.0)).abs() < 1e-2, "{p:?}");
}

/// A sweep offset moves a point by its rotation about the scanner, then its translation: the
/// exact rigid motion (f64), for both turn directions and points on every side.
#[test]
fn a_sweep_offset_is_a_rotation_then_a_translation() {
    for dtheta in [0.02f32, -0.3] {
        let off = pfe_core::sweeps::SweepOffset {
            dx: 8.0,
            dy: -5.0,
            dtheta,
            sd: [1.0; 3],
            sigma: 1.0,
            chi2: 100.0,
            rows: 100,
            max_shift: 50.0,
        };
        for p in [
            Point::new(3000.0, 0.0),
            Point::new(-1000.0, 2500.0),
            Point::new(700.0, -4000.0),
        ] {
            let (s, c) = f64::from(dtheta).sin_cos();
            let (x, y) = (f64::from(p.x), f64::from(p.y));
            let want = (c * x - s * y + 8.0, s * x + c * y - 5.0);
            let got = off.apply(p);
            assert!(
                (f64::from(got.x) - want.0).abs() < 1e-3
                    && (f64::from(got.y) - want.1).abs() < 1e-3,
                "{got:?} vs {want:?}"
            );
        }
    }
}

/// A prediction needs a beam: none towards the scanner itself or towards a point at infinity.
#[test]
fn no_prediction_without_a_finite_beam() {
    use pfe_core::predict::predict;
    let w = [
        Point::new(1000.0, 0.0),
        Point::new(1000.0, 100.0),
        Point::new(1000.0, 200.0),
    ];
    let o = Point::new(0.0, 0.0);
    assert!(predict(&w, Point::new(1000.0, 300.0), o).is_some());
    assert!(predict(&w, o, o).is_none());
    let moved = Point::new(50.0, -20.0);
    assert!(predict(&w, moved, moved).is_none());
    assert!(predict(&w, Point::new(f32::INFINITY, 300.0), o).is_none());
    assert!(predict(&w, Point::new(1000.0, f32::NAN), o).is_none());
}

/// The paper's threshold `d_m = (d_0/λ)(r/r_max + (π − ϕ)/π)` at worked values (d_0 = 50 mm,
/// λ = 2, r_max = 8 m), with r/r_max clamped to [0, 1] and ϕ to [0, π/2].
#[test]
fn the_papers_threshold_at_worked_values() {
    use core::f32::consts::{FRAC_PI_2, FRAC_PI_4};
    use pfe_core::predict::paper_threshold;
    let d = |r: f32, phi: f32| paper_threshold(50.0, 2.0, r, 8000.0, phi);
    let close = |a: f32, b: f32| (a - b).abs() < 1e-3;
    assert!(close(d(8000.0, FRAC_PI_2), 37.5));
    assert!(close(d(4000.0, FRAC_PI_2), 25.0));
    assert!(close(d(2000.0, FRAC_PI_4), 25.0 * (0.25 + 0.75)));
    assert!(close(d(0.0, 0.0), 25.0));
    assert!(close(d(16_000.0, 2.0), 37.5));
    assert!(close(
        paper_threshold(30.0, 3.0, 4000.0, 8000.0, FRAC_PI_2),
        10.0
    ));
}

/// A point that is not finite makes a circle fit fail as such (not as a degenerate set).
#[test]
fn a_circle_fit_of_a_non_finite_point_says_so() {
    use pfe_core::{fit_circle, CircleMethod, FitError};
    let mut pts: Vec<Point> = (0..8)
        .map(|i| {
            let t = 0.2 * i as f32;
            Point::new(2000.0 + 300.0 * t.cos(), 300.0 * t.sin())
        })
        .collect();
    assert!(fit_circle(&pts, CircleMethod::Hyper).is_ok());
    for bad in [f32::NAN, f32::INFINITY] {
        for k in [0usize, 1] {
            let mut p = pts.clone();
            if k == 0 {
                p[3].x = bad;
            } else {
                p[5].y = bad;
            }
            for m in [CircleMethod::Kasa, CircleMethod::Hyper] {
                assert_eq!(
                    fit_circle(&p, m),
                    Err(FitError::NonFinite),
                    "{bad} {k} {m:?}"
                );
            }
        }
    }
    pts.truncate(2);
    assert!(matches!(
        fit_circle(&pts, CircleMethod::Hyper),
        Err(FitError::TooFewPoints { got: 2, need: 3 })
    ));
}

/// Three points fix a circle, and its covariance: σ² (WᵀW)⁻¹ exists for three points (here on
/// a quarter circle, where W's rows are independent), not for two.
#[test]
fn three_points_have_a_circle_covariance() {
    use pfe_core::{circle_covariance, Circle};
    let circle = Circle {
        center: Point::new(2000.0, 500.0),
        radius: 300.0,
    };
    let on = |a: f32| Point::new(2000.0 + 300.0 * a.cos(), 500.0 + 300.0 * a.sin());
    let three = [on(2.0), on(2.8), on(3.6)];
    let cov = circle_covariance(&three, &circle, 5.0).unwrap();
    assert!(
        cov.iter().flatten().all(|v| v.is_finite()) && cov[2][2] > 0.0,
        "{cov:?}"
    );
    assert!(circle_covariance(&three[..2], &circle, 5.0).is_err());
}

/// `fit_line_iter` (two passes over any re-iterable points) fits the line `fit_line` fits and
/// the f64 principal axis gives: a wall at 30° with ±4 mm of zig-zag, 40 points.
#[test]
fn fit_line_iter_is_the_least_squares_line() {
    use pfe_core::fit::line::fit_line_iter;
    use pfe_core::fit_line;
    let (a, rho) = (std::f64::consts::FRAC_PI_6, 2500.0f64);
    let pts: Vec<Point> = (0..40)
        .map(|i| {
            let t = -1000.0 + 50.0 * f64::from(i);
            let off = if i % 3 == 0 { 4.0 } else { -2.0 };
            let (s, c) = a.sin_cos();
            Point::new(
                ((rho + off) * c - t * s) as f32,
                ((rho + off) * s + t * c) as f32,
            )
        })
        .collect();
    // f64: the normal is the smaller principal axis of the centred scatter.
    let n = pts.len() as f64;
    let (mx, my) = (
        pts.iter().map(|p| f64::from(p.x)).sum::<f64>() / n,
        pts.iter().map(|p| f64::from(p.y)).sum::<f64>() / n,
    );
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for p in &pts {
        let (dx, dy) = (f64::from(p.x) - mx, f64::from(p.y) - my);
        sxx += dx * dx;
        syy += dy * dy;
        sxy += dx * dy;
    }
    let alpha = 0.5 * (-2.0 * sxy).atan2(syy - sxx);
    let rho64 = mx * alpha.cos() + my * alpha.sin();
    for l in [
        fit_line_iter(pts.iter().copied()).unwrap(),
        fit_line(&pts).unwrap(),
    ] {
        assert!(
            (f64::from(l.alpha) - alpha).abs() < 1e-5 && (f64::from(l.rho) - rho64).abs() < 1e-2,
            "{} {} vs {alpha} {rho64}",
            l.alpha,
            l.rho
        );
    }
}

/// A point at the very centre of the circle being refined (distance 0: no direction) adds its
/// residual but nothing to the normal equations: the refinement still steps, and lowers the
/// residual sum, from a start centred on one of the points.
#[test]
fn a_point_at_the_centre_does_not_stop_the_refinement() {
    use pfe_core::fit::circle::geometric_sse;
    use pfe_core::{refine_circle, Circle};
    let pts: Vec<Point> = (0..12)
        .map(|i| {
            let a = 2.4 + 0.12 * i as f32;
            Point::new(2000.0 + 300.0 * a.cos(), 300.0 * a.sin())
        })
        .collect();
    let start = Circle {
        center: pts[6],
        radius: 300.0,
    };
    let refined = refine_circle(&pts, start, 3).unwrap();
    let (before, after) = (geometric_sse(&pts, &start), geometric_sse(&pts, &refined));
    assert!(after < 0.5 * before, "{before} -> {after}");
}
