//! The typing's decisions at their bounds and the covariance additions, against values worked
//! out by hand (exact in f32) or in f64.
#![allow(clippy::indexing_slicing)]

use super::*;
use crate::feature::{CircleFeature, LineFeature};
use crate::fit::run::best_split_sse;

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

/// The AR(1) variance factor of a mean against its sum written out in f64: 1 without
/// correlation or with one value, 1 + φ for two values, the sum's value for twenty.
#[test]
fn ar1_factor_is_the_variance_of_a_mean_of_correlated_values() {
    use super::covariance::ar1_factor;
    assert_eq!(ar1_factor(0.0, 20), 1.0);
    assert_eq!(ar1_factor(0.7, 1), 1.0);
    assert!((ar1_factor(0.5, 2) - 1.5).abs() < 1e-6);
    for (phi, n) in [(0.3f64, 7usize), (0.9, 20), (0.5, 140)] {
        let sum = 1.0
            + 2.0
                * (1..n)
                    .map(|k| (1.0 - k as f64 / n as f64) * phi.powi(k as i32))
                    .sum::<f64>();
        let got = f64::from(ar1_factor(phi as f32, n));
        assert!(
            (got / sum - 1.0).abs() < 1e-5,
            "φ {phi} n {n}: {got} vs {sum}"
        );
    }
}

/// A bend (six residuals +1, six −1): lag-one autocorrelation 9/12 > 2/√12, its excess τ² =
/// 12/10 − var and φ = (9/11)/τ² (taken at most 0.9) give 1 + (τ²/var) f(φ, 12). Alternating
/// residuals, a scatter the noise explains, too few or non-finite residuals: not correlated.
#[test]
fn correlated_scale_takes_the_excess_and_its_correlation() {
    use super::covariance::ar1_factor;
    let bend = [
        1.0f32, 1.0, 1.0, 1.0, 1.0, 1.0, -1.0, -1.0, -1.0, -1.0, -1.0, -1.0,
    ];
    for var in [0.25f32, 0.5] {
        let tau2 = 1.2 - f64::from(var);
        let phi = (9.0 / 11.0 / tau2).min(0.9);
        let want = 1.0 + tau2 / f64::from(var) * f64::from(ar1_factor(phi as f32, 12));
        let got = f64::from(correlated_scale(bend.iter().copied(), var, 10.0).unwrap());
        assert!(
            (got / want - 1.0).abs() < 1e-5,
            "var {var}: {got} vs {want}"
        );
    }
    // τ² ≤ 0: the noise explains the scatter.
    assert_eq!(correlated_scale(bend.iter().copied(), 1.2, 10.0), None);
    let alternating = bend
        .iter()
        .enumerate()
        .map(|(i, _)| if i % 2 == 0 { 1.0 } else { -1.0 });
    assert_eq!(correlated_scale(alternating, 0.25, 10.0), None);
    // Lag-one autocorrelation exactly 2/√n (1/2, n = 16): not beyond.
    let step = [1.0f32, 1.0].into_iter().chain([0.0; 14]);
    assert_eq!(correlated_scale(step, 0.1, 14.0), None);
    // Lag-one autocorrelation 5/8 below 2/√8.
    assert_eq!(
        correlated_scale(bend[2..10].iter().copied(), 0.25, 6.0),
        None
    );
    assert_eq!(correlated_scale(core::iter::empty(), 0.25, 1.0), None);
    assert_eq!(
        correlated_scale([f32::NAN; 12].into_iter(), 0.25, 10.0),
        None
    );
    assert_eq!(correlated_scale(bend.iter().copied(), 0.0, 10.0), None);
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

/// The split allowance: −2 σ_r² for an arc of at most 120° between its ends (around a centre
/// away from the origin, either way round), none beyond, nor without points.
#[test]
fn an_arc_up_to_120_degrees_gets_the_split_allowance() {
    let (c, r) = ((3000.0, -1200.0), 400.0);
    let circle = Circle {
        center: Point::new(c.0, c.1),
        radius: r,
    };
    let deg = core::f32::consts::PI / 180.0;
    for dir in [1.0f32, -1.0] {
        for (span, want) in [(31.0, -50.0), (119.0, -50.0), (121.0, 0.0), (200.0, 0.0)] {
            let pts = arc(8, c, r, 1.0, dir * span * deg);
            assert_eq!(arc::allowance(&pts, &circle, 25.0), want, "{span}° {dir}");
        }
    }
    assert_eq!(arc::allowance(&[], &circle, 25.0), 0.0);
    // Fewer than eight points: none.
    let seven = arc(7, c, r, 1.0, 60.0 * deg);
    assert_eq!(arc::allowance(&seven, &circle, 25.0), 0.0);
}

/// `arc_test` tells a circle that beats the best split outright (`Some(false)`) from one
/// only within the allowance (`Some(true)`) and from no arc (`None`), by its residual sum
/// against the split's, on eight points of a 60° arc.
#[test]
fn arc_test_tells_an_outright_arc_from_an_allowed_one() {
    let (c, r) = ((3000.0, -1200.0), 400.0);
    let circle = Circle {
        center: Point::new(c.0, c.1),
        radius: r,
    };
    let deg = core::f32::consts::PI / 180.0;
    let pts = arc(8, c, r, 1.0, 60.0 * deg);
    let split = best_split_sse(&pts).unwrap();
    let var = 25.0;
    assert_eq!(arc::arc_test(&pts, &circle, split - 1.0, var), Some(false));
    assert_eq!(arc::arc_test(&pts, &circle, split + 1.0, var), Some(true));
    assert_eq!(arc::arc_test(&pts, &circle, split + 49.0, var), Some(true));
    assert_eq!(arc::arc_test(&pts, &circle, split + 51.0, var), None);
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

/// The line's residual sum of `pts` in f64: the smaller eigenvalue of their centred scatter.
fn line_sse64(pts: &[Point]) -> f64 {
    let n = pts.len() as f64;
    let (mx, my) = (
        pts.iter().map(|p| f64::from(p.x)).sum::<f64>() / n,
        pts.iter().map(|p| f64::from(p.y)).sum::<f64>() / n,
    );
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for p in pts {
        let (dx, dy) = (f64::from(p.x) - mx, f64::from(p.y) - my);
        sxx += dx * dx;
        syy += dy * dy;
        sxy += dx * dy;
    }
    0.5 * (sxx + syy - libm::sqrt((sxx - syy) * (sxx - syy) + 4.0 * sxy * sxy))
}

/// `n` points on an arc of radius `r` over 40° at 3 m, every other one `d` mm further out.
fn bumpy_arc(n: usize, r: f32, d: f32) -> heapless::Vec<Point, 64> {
    let deg = core::f32::consts::PI / 180.0;
    let c = (3000.0 + r, 0.0);
    arc(n, c, r, 160.0 * deg, 40.0 * deg)
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let s = if i % 2 == 1 { (r + d) / r } else { 1.0 };
            Point::new(c.0 + (p.x - c.0) * s, c.1 + (p.y - c.1) * s)
        })
        .collect()
}

/// Whether the fit comparison (default configuration, told `sigma` mm) types `pts` a circle.
fn circle_at(pts: &[Point], sigma: f32) -> bool {
    let config = Config::default().with_sigma_r(sigma);
    let line = fit_line(pts).ok();
    circle_of::<false>(pts, line.as_ref(), &config).is_some()
}

/// The fit comparison on points of an exact arc (circle residual ≈ 0, the line's `S` worked
/// out in f64) turns from circle to line where σ_r² reaches S / max(χ², 1.5 n) (χ² = 25): the
/// circle must beat the line by χ² σ_r² and the line must leave more than 1.5 σ_r² a point
/// (n = 20: 1.5 n binds; n = 10: χ² does); within ±3 % of σ_r.
#[test]
fn an_exact_arc_is_a_circle_until_the_line_explains_it_within_the_noise() {
    for n in [10usize, 20] {
        let pts = bumpy_arc(n, 1000.0, 0.0);
        let s = line_sse64(&pts);
        let flip = libm::sqrt(s / f64::max(25.0, 1.5 * n as f64)) as f32;
        assert!(circle_at(&pts, 0.97 * flip), "n {n}: S {s}, flip σ {flip}");
        assert!(!circle_at(&pts, 1.03 * flip), "n {n}: S {s}, flip σ {flip}");
    }
}

/// The screen before the algebraic fit (the line must leave more than χ² σ_r² and 1.5 σ_r² a
/// point) is no stricter than the tests after it, also for σ_r below 1 mm, where χ² σ_r² is
/// smaller than χ² + σ_r²: a flat exact arc whose line leaves 7.5–25 mm² over 20 points is a
/// circle at σ_r = 0.5 mm.
#[test]
fn a_flat_arc_is_a_circle_for_a_scanner_of_half_a_millimetre() {
    let pts = arc(20, (0.0, 0.0), 1000.0, 0.0, 0.152);
    let s = line_sse64(&pts);
    assert!(s > 7.5 && s < 25.0, "S {s}");
    assert!(circle_at(&pts, 0.5), "S {s}");
}

/// The circle must explain the points within 2σ_r RMS (its residual sum ≤ 4 σ_r² n) and leave
/// less than half the line's: an arc whose every other point lies `d` mm out leaves ±d/2 a
/// point, a circle residual sum of about n d²/4, and the line's S + n d²/4 (S the exact arc's).
/// So it is a circle for σ_r above d/4 and for n d²/4 below S (within ±20 %), and no circle
/// is larger than 2 m.
#[test]
fn a_circle_must_explain_its_points_and_halve_the_lines_residual() {
    let n = 20;
    // RMS: the alternation d leaves ≈ d²/4 a point (d = 12 mm: 36 mm², σ_r ≥ 3 mm).
    let pts = bumpy_arc(n, 1000.0, 12.0);
    assert!(circle_at(&pts, 3.5));
    assert!(!circle_at(&pts, 2.5));
    // Ratio: the arc's own S ≈ 6 500 mm² against n d²/4 (σ_r 12 mm: both other tests pass).
    let s = line_sse64(&bumpy_arc(n, 1000.0, 0.0));
    let d_flip = libm::sqrt(4.0 * s / n as f64) as f32;
    assert!(
        circle_at(&bumpy_arc(n, 1000.0, 0.8 * d_flip), 12.0),
        "S {s}"
    );
    assert!(
        !circle_at(&bumpy_arc(n, 1000.0, 1.2 * d_flip), 12.0),
        "S {s}"
    );
    // The largest radius, 2 m.
    let big = |r: f32| {
        let deg = core::f32::consts::PI / 180.0;
        arc(n, (3000.0 + r, 0.0), r, 170.0 * deg, 20.0 * deg)
    };
    assert!(circle_at(&big(1900.0), 1.0));
    assert!(!circle_at(&big(2100.0), 1.0));
}

/// With a circle residual of its own (every other point 20 mm out, n = 10), the circle must
/// still beat the line by χ² σ_r² after it: the comparison turns at σ_r² = (S_line − S_circle)
/// / 25 (S_line in f64, S_circle as fitted), within ±3 % of σ_r.
#[test]
fn a_circle_must_beat_the_line_by_chi2_noise_variances() {
    let pts = bumpy_arc(10, 1000.0, 20.0);
    let config = Config::default().with_sigma_r(6.0);
    let line = fit_line(&pts).ok();
    let (_, sse_c, _) = circle_of::<false>(&pts, line.as_ref(), &config).unwrap();
    let s = line_sse64(&pts);
    assert!(f64::from(sse_c) > 0.15 * s, "{sse_c} vs {s}");
    let flip = libm::sqrt((s - f64::from(sse_c)) / 25.0) as f32;
    assert!(circle_at(&pts, 0.97 * flip), "flip σ {flip}");
    assert!(!circle_at(&pts, 1.03 * flip), "flip σ {flip}");
}

/// The default's circle is the algebraic (Hyper) fit refined to the geometric optimum: on an
/// arc with uneven residuals the gradient of its residual sum is 1 % of the Hyper circle's
/// at most, its residual sum no larger, and the sum returned is the circle's own.
#[test]
fn the_default_circle_is_refined_to_the_geometric_optimum() {
    let deg = core::f32::consts::PI / 180.0;
    let c = (3500.0, 200.0);
    let pts: heapless::Vec<Point, 64> = arc(16, c, 500.0, 150.0 * deg, 70.0 * deg)
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let s = 1.0 + [0.0, 0.03, -0.01, 0.05, 0.0, -0.04, 0.02, 0.06][i % 8];
            Point::new(c.0 + (p.x - c.0) * s, c.1 + (p.y - c.1) * s)
        })
        .collect();
    let config = Config::default().with_sigma_r(12.0);
    let line = fit_line(&pts).ok();
    let (circle, sse, _) = circle_of::<false>(&pts, line.as_ref(), &config).unwrap();
    let hyper = NormalEquations::at(&pts, &fit_circle(&pts, config.circle_method).unwrap());
    let own = NormalEquations::at(&pts, &circle);
    let norm = |g: [f32; 3]| libm::sqrtf(g.iter().map(|v| v * v).sum());
    assert!(
        norm(own.jtr) <= 0.01 * norm(hyper.jtr),
        "gradient {:?} vs Hyper's {:?}",
        own.jtr,
        hyper.jtr
    );
    assert!(sse <= hyper.sse, "{sse} vs Hyper's {}", hyper.sse);
    assert!((own.sse - sse).abs() <= 1e-3 * sse, "{} vs {sse}", own.sse);
}

/// The mean share of range noise along the normal, one point at a time as before the blocks:
/// the reference [`covariance::mean_cos2_still`] must equal bit for bit.
fn mean_cos2_one_by_one(pts: &[Point], normal: impl Fn(Point) -> Point) -> f32 {
    let (mut sum, mut n) = (0.0f32, 0usize);
    for &p in pts {
        let m = normal(p);
        let c2 = (p.x * m.x + p.y * m.y) * (p.x * m.x + p.y * m.y)
            / ((p.x * p.x + p.y * p.y) * (m.x * m.x + m.y * m.y));
        if c2.is_finite() {
            sum += c2;
            n += 1;
        }
    }
    if n > 0 {
        sum / n as f32
    } else {
        1.0
    }
}

/// Beams along the normal share all the noise, at 60° to it a quarter; points that tell
/// nothing (at the scanner, not finite) are left out, and none at all gives 1. In blocks the
/// mean is the one-by-one mean bit for bit, for every length around the block's and a normal
/// that depends on the point (a circle's).
#[test]
fn mean_cos2_takes_the_finite_shares_in_order() {
    use covariance::mean_cos2_still;
    let x = |_: Point| Point::new(2.0, 0.0);
    assert_eq!(mean_cos2_still(&[Point::new(3.0, 0.0); 11], x), 1.0);
    let at60 = Point::new(1.0, 3.0f32.sqrt());
    let c2 = mean_cos2_still(&[at60; 9], x);
    assert!((c2 - 0.25).abs() < 1e-6, "{c2}");
    let blind = [
        Point::new(0.0, 0.0),
        Point::new(f32::NAN, 1.0),
        Point::INVALID,
    ];
    assert_eq!(mean_cos2_still(&blind, x), 1.0);
    assert_eq!(mean_cos2_still(&[], x), 1.0);
    let mut pts: heapless::Vec<Point, 40> = (0..40)
        .map(|i| {
            let t = 0.37 * i as f32;
            Point::new(1000.0 + 300.0 * t.cos(), 200.0 * t.sin() - 50.0 * i as f32)
        })
        .collect();
    pts[5] = Point::new(0.0, 0.0);
    pts[17] = Point::INVALID;
    pts[26] = Point::new(f32::INFINITY, 3.0);
    let centre = |p: Point| Point::new(p.x - 1100.0, p.y + 40.0);
    let tilted = |_: Point| Point::new(0.6, 0.8);
    for n in 0..=pts.len() {
        let p = &pts[..n];
        for (a, b) in [
            (mean_cos2_still(p, centre), mean_cos2_one_by_one(p, centre)),
            (mean_cos2_still(p, tilted), mean_cos2_one_by_one(p, tilted)),
        ] {
            assert_eq!(a.to_bits(), b.to_bits(), "{n} points: {a} against {b}");
        }
    }
}

/// On the move (3 m/s, 2 rad/s: beams tens of millimetres apart in pose), each point's share
/// of noise along a wall's normal is taken from the pose of its own beam: `mean_cos2` over
/// the points of beams `s..s + n` equals the mean worked out in f64 from beam `s + i`'s pose,
/// for runs from the scan's first beam and from later ones.
#[test]
fn mean_cos2_on_the_move_takes_each_beam_from_its_own_pose() {
    use crate::extractor::Extractor;
    use crate::motion::{BeamTiming, Motion};
    use crate::output::Stats;
    use crate::scan::{Scan, ScanGeometry};
    let g = ScanGeometry::LMS200_180_050;
    let motion = Motion {
        v: 3000.0,
        omega: 2.0,
        timing: BeamTiming::lms2xx(0.5),
    };
    // The wall x cos α + y sin α = ρ, α = −45°, each point cast from its beam's pose.
    let (alpha, rho) = (-core::f64::consts::FRAC_PI_4, 1800.0f64);
    let (sa, ca) = (alpha.sin(), alpha.cos());
    let (mut points, mut ranges) = ([Point::INVALID; 361], [f32::NAN; 361]);
    for i in 0..361 {
        let pose = motion.pose(i);
        let b = f64::from(g.bearing(i) + pose.theta);
        let (ox, oy) = (f64::from(pose.origin.x), f64::from(pose.origin.y));
        let dn = b.cos() * ca + b.sin() * sa;
        if dn > 0.3 {
            let r = (rho - ox * ca - oy * sa) / dn;
            points[i] = Point::new((ox + r * b.cos()) as f32, (oy + r * b.sin()) as f32);
            ranges[i] = r as f32;
        }
    }
    let mut flags: [u8; 361] = core::array::from_fn(|i| match ranges[i].is_finite() {
        true => crate::flags::VALID,
        false => 0,
    });
    let normal = Point::new(ca as f32, sa as f32);
    let mut ex = Extractor::<361, 8>::new();
    let loading = [1000.0f32; 361];
    let mut tested = 0;
    ex.with_pass(
        &Scan::from_mm(g, &loading),
        &Config::default(),
        |loaded, _| {
            let mut stats = Stats::default();
            let pass = Pass::over(
                loaded.beams,
                (&points, &ranges, &mut flags),
                Some(motion),
                &mut stats,
            );
            for s in [0usize, 1, 2, 40, 100] {
                let n = 60;
                let pts = &points[s..s + n];
                if pts.iter().any(|p| !p.x.is_finite()) {
                    continue;
                }
                let mut sum = 0.0f64;
                for (i, p) in pts.iter().enumerate() {
                    let o = motion.pose(s + i).origin;
                    let (dx, dy) = (f64::from(p.x - o.x), f64::from(p.y - o.y));
                    let c = (dx * ca + dy * sa) / dx.hypot(dy);
                    sum += c * c;
                }
                let want = sum / n as f64;
                let got = f64::from(mean_cos2(&pass, s, pts, |_| normal));
                assert!(
                    (got - want).abs() < 1e-5,
                    "beams {s}..: {got} against {want}"
                );
                tested += 1;
            }
        },
    );
    assert_eq!(tested, 5);
}
