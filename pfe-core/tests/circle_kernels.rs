//! The circle kernels, each against a reference computed here in f64, independently of
//! pfe-core (how they were found: docs/TESTING.md, "Mutation testing"): the geometric
//! residual sum, the Levenberg–Marquardt refinement step by step, the covariance
//! `σ² (WᵀW)⁻¹` and its range-noise sandwich by Gauss–Jordan inversion, and the Taubin and
//! Hyper fits as the smallest non-negative root of `det(M − ηN)` found by bisection.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]
// Matrix code by index reads as the formulas do.
#![allow(clippy::needless_range_loop)]

mod common;

use common::Noise;
use pfe_core::fit::circle::geometric_sse;
use pfe_core::{
    circle_covariance, circle_covariance_range, fit_circle, refine_circle, Circle, CircleMethod,
    FitError, Point,
};

type P64 = (f64, f64);

/// `n` points on the arc of centre `c`, radius `r`, angles `from..=to`, radial noise σ.
fn arc(c: P64, r: f64, (from, to): P64, n: usize, sigma: f64, noise: &mut Noise) -> Vec<P64> {
    (0..n)
        .map(|i| {
            let t = from + (to - from) * i as f64 / (n - 1) as f64;
            let rr = r + sigma * noise.gauss();
            (c.0 + rr * t.cos(), c.1 + rr * t.sin())
        })
        .collect()
}

fn f32s(pts: &[P64]) -> Vec<Point> {
    pts.iter()
        .map(|p| Point::new(p.0 as f32, p.1 as f32))
        .collect()
}

/// The f32 points back in f64 (what pfe-core sees).
fn f64s(pts: &[Point]) -> Vec<P64> {
    pts.iter()
        .map(|p| (f64::from(p.x), f64::from(p.y)))
        .collect()
}

fn circle(a: f64, b: f64, r: f64) -> Circle {
    Circle {
        center: Point::new(a as f32, b as f32),
        radius: r as f32,
    }
}

fn c64(c: &Circle) -> (f64, f64, f64) {
    (
        f64::from(c.center.x),
        f64::from(c.center.y),
        f64::from(c.radius),
    )
}

/// Σ (|p − c| − R)² in f64.
fn sse64(pts: &[P64], (a, b, r): (f64, f64, f64)) -> f64 {
    pts.iter()
        .map(|p| ((p.0 - a).hypot(p.1 - b) - r).powi(2))
        .sum()
}

/// Inverse of an n×n matrix by Gauss–Jordan with partial pivoting, f64.
fn inverse<const N: usize>(m: [[f64; N]; N]) -> [[f64; N]; N] {
    let mut a = m;
    let mut inv = [[0.0f64; N]; N];
    for (i, row) in inv.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    for col in 0..N {
        let piv = (col..N)
            .max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs()))
            .unwrap();
        a.swap(col, piv);
        inv.swap(col, piv);
        let d = a[col][col];
        for k in 0..N {
            a[col][k] /= d;
            inv[col][k] /= d;
        }
        for r in 0..N {
            if r != col {
                let f = a[r][col];
                for k in 0..N {
                    a[r][k] -= f * a[col][k];
                    inv[r][k] -= f * inv[col][k];
                }
            }
        }
    }
    inv
}

fn mul3(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

/// Every entry of `got` within `rel` of the largest |entry| of `want`.
fn close3(got: &[[f32; 3]; 3], want: &[[f64; 3]; 3], rel: f64, what: &str) {
    let scale = want.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    for i in 0..3 {
        for j in 0..3 {
            let (g, w) = (f64::from(got[i][j]), want[i][j]);
            assert!(
                (g - w).abs() <= rel * scale,
                "{what}[{i}][{j}]: got {g}, want {w} (scale {scale})\n{got:?}\n{want:?}"
            );
        }
    }
}

#[test]
fn geometric_sse_is_the_sum_of_squared_distances() {
    let mut noise = Noise::new(41);
    let pts = f32s(&arc(
        (1500.0, -700.0),
        350.0,
        (0.2, 2.9),
        31,
        8.0,
        &mut noise,
    ));
    for c in [
        circle(1500.0, -700.0, 350.0),
        circle(1520.0, -690.0, 340.0),
        circle(0.0, 0.0, 10.0),
    ] {
        let want = sse64(&f64s(&pts), c64(&c));
        let got = f64::from(geometric_sse(&pts, &c));
        assert!((got - want).abs() <= 1e-4 * want, "{got} vs {want}");
    }
    // Points exactly on the circle (a right-angle grid of it), and no points at all.
    let on = [
        Point::new(300.0, 0.0),
        Point::new(0.0, 300.0),
        Point::new(-300.0, 0.0),
    ];
    assert_eq!(geometric_sse(&on, &circle(0.0, 0.0, 300.0)), 0.0);
    assert_eq!(geometric_sse(&[], &circle(0.0, 0.0, 300.0)), 0.0);
}

/// One damped Gauss–Newton step of the documented refinement in f64: the normal equations of
/// the residuals `|P − c| − R` (Jacobian rows `(−dx/d, −dy/d, −1)`), the diagonal scaled by
/// `1 + λ`, the step subtracted.
fn lm_step(pts: &[P64], c: (f64, f64, f64), lambda: f64) -> (f64, f64, f64) {
    let mut jtj = [[0.0f64; 3]; 3];
    let mut jtr = [0.0f64; 3];
    for p in pts {
        let (dx, dy) = (p.0 - c.0, p.1 - c.1);
        let d = dx.hypot(dy);
        let r = d - c.2;
        let j = [-dx / d, -dy / d, -1.0];
        for i in 0..3 {
            for k in 0..3 {
                jtj[i][k] += j[i] * j[k];
            }
            jtr[i] += j[i] * r;
        }
    }
    for (i, row) in jtj.iter_mut().enumerate() {
        row[i] *= 1.0 + lambda;
    }
    let inv = inverse(jtj);
    let step: Vec<f64> = (0..3)
        .map(|i| (0..3).map(|k| inv[i][k] * jtr[k]).sum())
        .collect();
    (c.0 - step[0], c.1 - step[1], c.2 - step[2])
}

/// The documented refinement in f64, `iterations` outer steps from `start`: λ starts at 10⁻³;
/// up to four tries a step, each with λ ten times the last; a step below 0.01 mm ends it; an
/// accepted step (lower residual sum, positive radius) lowers λ to 0.3 λ (not below 10⁻⁷) and
/// ends the refinement when it gained less than 10⁻⁵ of the sum.
fn refine64(pts: &[P64], start: (f64, f64, f64), iterations: usize) -> (f64, f64, f64) {
    refine64_counted(pts, start, iterations).0
}

/// [`refine64`] with the number of rejected tries (λ raised) and the length of the last
/// accepted step.
fn refine64_counted(
    pts: &[P64],
    start: (f64, f64, f64),
    iterations: usize,
) -> ((f64, f64, f64), usize, f64) {
    let (mut best, mut lambda) = (start, 1e-3f64);
    let (mut rejected, mut last) = (0usize, 0.0f64);
    for _ in 0..iterations {
        let mut improved = false;
        for _ in 0..4 {
            let cand = lm_step(pts, best, lambda);
            let step = (cand.0 - best.0)
                .hypot(cand.1 - best.1)
                .hypot(cand.2 - best.2);
            if step < 1e-2 {
                break;
            }
            let (old, new) = (sse64(pts, best), sse64(pts, cand));
            if new < old && cand.2 > 0.0 {
                best = cand;
                last = step;
                lambda = (0.3 * lambda).max(1e-7);
                improved = old - new > new * 1e-5;
                break;
            }
            rejected += 1;
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    (best, rejected, last)
}

fn max_err(a: (f64, f64, f64), b: (f64, f64, f64)) -> f64 {
    (a.0 - b.0)
        .abs()
        .max((a.1 - b.1).abs())
        .max((a.2 - b.2).abs())
}

#[test]
fn refinement_takes_levenberg_marquardt_steps() {
    let mut noise = Noise::new(43);
    // A long arc (well-conditioned) and a short one (the damping matters: the centre and the
    // radius are nearly one unknown along the arc's axis).
    for (span, start, tol) in [
        ((2.2, 3.9), (2560.0, 760.0, 430.0), 0.01),
        ((2.9, 3.4), (2450.0, 830.0, 380.0), 0.05),
    ] {
        let pts = f32s(&arc((2500.0, 800.0), 400.0, span, 40, 6.0, &mut noise));
        let p64 = f64s(&pts);
        let initial = circle(start.0, start.1, start.2);
        // No iteration: the initial circle itself.
        assert_eq!(refine_circle(&pts, initial, 0).unwrap(), initial);
        // One iteration: the first damped step (λ = 10⁻³), which lowers the residual sum.
        let one = c64(&refine_circle(&pts, initial, 1).unwrap());
        let want = lm_step(&p64, start, 1e-3);
        assert!(
            max_err(one, want) < tol,
            "{span:?} one step {one:?}, want {want:?}"
        );
        assert!(sse64(&p64, one) < sse64(&p64, start));
        // Then step by step as documented, until the gain stop ends it.
        for it in (2..=6).chain([10, 20]) {
            let got = c64(&refine_circle(&pts, initial, it).unwrap());
            let want = refine64(&p64, start, it);
            assert!(
                max_err(got, want) < tol,
                "{span:?} {it} steps {got:?}, want {want:?}"
            );
        }
    }
    // Many: the geometric least-squares circle (undamped Gauss–Newton to convergence in f64),
    // with its residual sum, which no nearby circle beats.
    let pts = f32s(&arc(
        (2500.0, 800.0),
        400.0,
        (2.2, 3.9),
        40,
        6.0,
        &mut noise,
    ));
    let p64 = f64s(&pts);
    let start = (2560.0, 760.0, 430.0);
    let mut g = start;
    for _ in 0..50 {
        g = lm_step(&p64, g, 0.0);
    }
    let refined = refine_circle(&pts, circle(start.0, start.1, start.2), 20).unwrap();
    let r = c64(&refined);
    assert!(max_err(r, g) < 0.02, "{r:?} vs {g:?}");
    let best = sse64(&p64, g);
    assert!(f64::from(geometric_sse(&pts, &refined)) <= best * (1.0 + 1e-4) + 1e-3);
    for d in [(0.5, 0.0, 0.0), (0.0, -0.5, 0.0), (0.0, 0.0, 0.5)] {
        assert!(sse64(&p64, (g.0 + d.0, g.1 + d.1, g.2 + d.2)) > best);
    }
}

/// Starts from which the first Gauss–Newton step overshoots (the residual sum grows): the
/// refinement must raise λ tenfold and try again, as the f64 reference does; and a scatter so
/// large (σ = 50 mm, residual sum ~10⁵ mm²) that a gain measured as a ratio instead of a
/// difference would stop it after one step.
#[test]
fn refinement_damps_a_failed_step_and_measures_its_gain() {
    let mut noise = Noise::new(67);
    let pts = f32s(&arc(
        (3000.0, -400.0),
        300.0,
        (2.6, 3.4),
        30,
        2.0,
        &mut noise,
    ));
    let p64 = f64s(&pts);
    let mut damped = 0;
    for start in [
        (2800.0, -700.0, 200.0),
        (2900.0, -700.0, 400.0),
        (2800.0, -100.0, 400.0),
        (3200.0, -700.0, 600.0),
        (2900.0, -100.0, 200.0),
        (3100.0, -100.0, 400.0),
    ] {
        let initial = circle(start.0, start.1, start.2);
        for it in 1..=4 {
            let (want, rejected, _) = refine64_counted(&p64, start, it);
            damped += usize::from(it == 4 && rejected > 0);
            let got = c64(&refine_circle(&pts, initial, it).unwrap());
            assert!(
                max_err(got, want) < 0.05,
                "from {start:?}, {it} steps: {got:?}, want {want:?} ({rejected} rejected)"
            );
        }
    }
    assert!(damped >= 4, "{damped} starts made the reference raise λ");
    let pts = f32s(&arc(
        (1000.0, 2500.0),
        1500.0,
        (-2.0, -1.0),
        60,
        50.0,
        &mut noise,
    ));
    let p64 = f64s(&pts);
    let start = (1100.0, 2400.0, 1400.0);
    assert!(sse64(&p64, start) > 1.5e5);
    let (_, _, second) = refine64_counted(&p64, start, 2);
    assert!(second > 0.1, "the second step moves {second} mm");
    for it in 1..=4 {
        let got = c64(&refine_circle(&pts, circle(start.0, start.1, start.2), it).unwrap());
        let want = refine64(&p64, start, it);
        assert!(
            max_err(got, want) < 0.02,
            "{it} steps: {got:?}, want {want:?}"
        );
    }
}

#[test]
fn refinement_recovers_an_exact_circle_and_keeps_a_converged_one() {
    let mut noise = Noise::new(47);
    let truth = (-900.0, 3100.0, 250.0);
    let pts = f32s(&arc(
        (truth.0, truth.1),
        truth.2,
        (-2.0, -0.7),
        25,
        0.0,
        &mut noise,
    ));
    for start in [(-870.0, 3080.0, 270.0), (-930.0, 3130.0, 200.0)] {
        let c = c64(&refine_circle(&pts, circle(start.0, start.1, start.2), 30).unwrap());
        assert!(
            (c.0 - truth.0).abs() < 0.02
                && (c.1 - truth.1).abs() < 0.02
                && (c.2 - truth.2).abs() < 0.02,
            "from {start:?}: {c:?}"
        );
    }
    // From the circle itself nothing moves (the step is below the 0.01 mm tolerance).
    let exact = circle(truth.0, truth.1, truth.2);
    assert_eq!(refine_circle(&pts, exact, 10).unwrap(), exact);
}

#[test]
fn refinement_rejects_what_it_cannot_refine() {
    let pts = [Point::new(100.0, 0.0), Point::new(0.0, 100.0)];
    assert_eq!(
        refine_circle(&pts, circle(0.0, 0.0, 100.0), 5),
        Err(FitError::TooFewPoints { got: 2, need: 3 })
    );
    let mut three = [
        Point::new(100.0, 0.0),
        Point::new(0.0, 100.0),
        Point::new(-100.0, 0.0),
    ];
    three[1].y = f32::NAN;
    assert_eq!(
        refine_circle(&three, circle(0.0, 0.0, 100.0), 5),
        Err(FitError::NonFinite)
    );
    let nan = Circle {
        center: Point::new(f32::NAN, 0.0),
        radius: 100.0,
    };
    let ok = [
        Point::new(100.0, 0.0),
        Point::new(0.0, 100.0),
        Point::new(-100.0, 0.0),
    ];
    assert_eq!(refine_circle(&ok, nan, 5), Err(FitError::NonFinite));
}

/// `WᵀW` of the circle's W rows `(u, v, 1)`, `(u, v)` the unit vector from the centre, f64.
fn wtw(pts: &[P64], (a, b, _): (f64, f64, f64)) -> [[f64; 3]; 3] {
    let mut m = [[0.0f64; 3]; 3];
    for p in pts {
        let d = (p.0 - a).hypot(p.1 - b);
        let w = [(p.0 - a) / d, (p.1 - b) / d, 1.0];
        for i in 0..3 {
            for k in 0..3 {
                m[i][k] += w[i] * w[k];
            }
        }
    }
    m
}

#[test]
fn covariance_is_sigma_squared_times_the_inverse_of_wtw() {
    let mut noise = Noise::new(53);
    for &(c, r, span, n) in &[
        ((3000.0, 400.0), 300.0, (2.0, 4.0), 30),
        ((-1200.0, -2500.0), 900.0, (0.5, 1.4), 60),
        ((500.0, 2000.0), 120.0, (-2.5, -0.2), 12),
    ] {
        let pts = f32s(&arc(c, r, span, n, 3.0, &mut noise));
        let p64 = f64s(&pts);
        let fitted = fit_circle(&pts, CircleMethod::Hyper).unwrap();
        let sigma = 5.0f32;
        let got = circle_covariance(&pts, &fitted, sigma).unwrap();
        let inv = inverse(wtw(&p64, c64(&fitted)));
        let want = inv.map(|row| row.map(|v| v * 25.0));
        close3(&got, &want, 2e-3, "σ²(WᵀW)⁻¹");
        // The sandwich for range noise from the origin: Σ_ii = σ_r² cos² γ_i.
        let origin = (40.0, -60.0);
        let got = circle_covariance_range(
            &pts,
            &fitted,
            Point::new(origin.0 as f32, origin.1 as f32),
            sigma,
        )
        .unwrap();
        let (a, b, _) = c64(&fitted);
        let mut mid = [[0.0f64; 3]; 3];
        for p in &p64 {
            let d = (p.0 - a).hypot(p.1 - b);
            let (u, v) = ((p.0 - a) / d, (p.1 - b) / d);
            let (bx, by) = (p.0 - origin.0, p.1 - origin.1);
            let cos_g = (u * bx + v * by) / bx.hypot(by);
            let w = [u, v, 1.0];
            for i in 0..3 {
                for k in 0..3 {
                    mid[i][k] += w[i] * w[k] * 25.0 * cos_g * cos_g;
                }
            }
        }
        let want = mul3(&mul3(&inv, &mid), &inv);
        close3(&got, &want, 2e-3, "sandwich");
    }
}

#[test]
fn covariance_of_a_degenerate_geometry_is_an_error() {
    // Every point at the same place: W has rank one.
    let same = [Point::new(1000.0, 0.0); 5];
    let c = circle(0.0, 0.0, 1000.0);
    assert_eq!(circle_covariance(&same, &c, 1.0), Err(FitError::Degenerate));
    assert_eq!(
        circle_covariance_range(&same, &c, Point::new(0.0, 0.0), 1.0),
        Err(FitError::Degenerate)
    );
    // Every point at the centre: no direction at all (WᵀW = 0).
    let centre = [Point::new(0.0, 0.0); 4];
    assert_eq!(
        circle_covariance(&centre, &c, 1.0),
        Err(FitError::Degenerate)
    );
    // Two distinct points: still rank two at most.
    let two = [
        Point::new(1000.0, 0.0),
        Point::new(0.0, 1000.0),
        Point::new(1000.0, 0.0),
        Point::new(0.0, 1000.0),
    ];
    assert_eq!(circle_covariance(&two, &c, 1.0), Err(FitError::Degenerate));
    assert_eq!(
        circle_covariance(&two[..2], &c, 1.0),
        Err(FitError::TooFewPoints { got: 2, need: 3 })
    );
}

/// 4×4 determinant by elimination, f64.
fn det4(m: [[f64; 4]; 4]) -> f64 {
    let mut a = m;
    let mut det = 1.0;
    for col in 0..4 {
        let piv = (col..4)
            .max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs()))
            .unwrap();
        if piv != col {
            a.swap(col, piv);
            det = -det;
        }
        let d = a[col][col];
        if d == 0.0 {
            return 0.0;
        }
        det *= d;
        for r in col + 1..4 {
            let f = a[r][col] / d;
            for k in col..4 {
                a[r][k] -= f * a[col][k];
            }
        }
    }
    det
}

/// The Taubin or Hyper circle in f64 from its definition: with `Z = (x² + y², x, y, 1)` of the
/// centred points, `M = mean Z Zᵀ` and the constraint matrix `N` of the method, the circle
/// `A z + B x + C y + D = 0` of the generalised eigenvector of `M A = η N A` with the smallest
/// non-negative η (found by scanning `det(M − ηN)` and bisecting its first sign change).
fn algebraic_f64(pts: &[P64], hyper: bool) -> (f64, f64, f64) {
    let n = pts.len() as f64;
    let (mx, my) = (
        pts.iter().map(|p| p.0).sum::<f64>() / n,
        pts.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let c: Vec<P64> = pts.iter().map(|p| (p.0 - mx, p.1 - my)).collect();
    let mut m = [[0.0f64; 4]; 4];
    for p in &c {
        let z = [p.0 * p.0 + p.1 * p.1, p.0, p.1, 1.0];
        for i in 0..4 {
            for k in 0..4 {
                m[i][k] += z[i] * z[k] / n;
            }
        }
    }
    let zbar = m[0][3];
    // Centred: mean x = mean y = 0.
    let nmat = if hyper {
        [
            [8.0 * zbar, 0.0, 0.0, 2.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [2.0, 0.0, 0.0, 0.0],
        ]
    } else {
        [
            [4.0 * zbar, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0, 0.0],
        ]
    };
    let shifted = |eta: f64| {
        let mut k = m;
        for i in 0..4 {
            for j in 0..4 {
                k[i][j] -= eta * nmat[i][j];
            }
        }
        k
    };
    let p = |eta: f64| det4(shifted(eta));
    // Scan η on a log grid from 10⁻¹⁰ zbar: the first sign change, then bisect.
    let p0 = p(0.0);
    let (mut lo, mut hi) = (0.0f64, f64::NAN);
    let mut eta = 1e-10 * zbar;
    while eta < 10.0 * zbar {
        if p(eta).signum() != p0.signum() {
            hi = eta;
            break;
        }
        lo = eta;
        eta *= 1.01;
    }
    assert!(hi.is_finite(), "no root of det(M − ηN)");
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if p(mid).signum() == p0.signum() {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let k = shifted(0.5 * (lo + hi));
    // A = 1: rows 1..3 give B, C, D.
    let a3 = [
        [k[1][1], k[1][2], k[1][3]],
        [k[2][1], k[2][2], k[2][3]],
        [k[3][1], k[3][2], k[3][3]],
    ];
    let rhs = [-k[1][0], -k[2][0], -k[3][0]];
    let inv = inverse(a3);
    let s: Vec<f64> = (0..3)
        .map(|i| (0..3).map(|j| inv[i][j] * rhs[j]).sum())
        .collect();
    let (b, cc, d) = (s[0], s[1], s[2]);
    let (a, bb) = (-b / 2.0, -cc / 2.0);
    (mx + a, my + bb, (a * a + bb * bb - d).sqrt())
}

#[test]
fn taubin_and_hyper_are_the_generalised_eigenvectors_of_their_definitions() {
    let mut noise = Noise::new(59);
    // Short noisy arcs, where the methods differ from each other and from Kåsa by millimetres.
    for &(c, r, span, n, sigma) in &[
        ((2000.0, 300.0), 300.0, (2.3, 3.5), 25, 15.0),
        ((-500.0, 2500.0), 200.0, (-2.0, -0.6), 20, 10.0),
        ((4000.0, -1500.0), 800.0, (2.6, 3.3), 40, 20.0),
        // Noise of a tenth of the radius over 60°: the root η is far from 0.
        ((1500.0, -200.0), 150.0, (2.6, 3.65), 12, 15.0),
        ((3000.0, 800.0), 400.0, (2.9, 3.9), 10, 40.0),
    ] {
        let pts = f32s(&arc(c, r, span, n, sigma, &mut noise));
        let p64 = f64s(&pts);
        for (method, hyper) in [(CircleMethod::Taubin, false), (CircleMethod::Hyper, true)] {
            let want = algebraic_f64(&p64, hyper);
            let got = c64(&fit_circle(&pts, method).unwrap());
            let err = (got.0 - want.0)
                .abs()
                .max((got.1 - want.1).abs())
                .max((got.2 - want.2).abs());
            assert!(err < 0.05, "{method:?}: {got:?} vs {want:?}");
        }
    }
}

/// `fit_circle`'s guards name the failure: a spread whose square overflows f32 is non-finite
/// (not degenerate), points that all coincide are degenerate, for every method.
#[test]
fn circle_fit_guards_name_the_failure() {
    let methods = [
        CircleMethod::Kasa,
        CircleMethod::Taubin,
        CircleMethod::Hyper,
    ];
    // x spread 1e20: the sum of offsets is finite, the sum of their squares (1e40) is not.
    let far = [
        Point::new(1e20, 0.0),
        Point::new(0.0, 1.0),
        Point::new(1.0, 0.0),
    ];
    let same = [Point::new(1000.0, 2000.0); 4];
    for m in methods {
        assert_eq!(fit_circle(&far, m), Err(FitError::NonFinite), "{m:?}");
        assert_eq!(fit_circle(&same, m), Err(FitError::Degenerate), "{m:?}");
    }
}

/// An exact arc whose points balance about the first one (the first at the top of the arc,
/// the others in mirror pairs: their x offsets sum to exactly 0) is fitted like any other.
#[test]
fn an_arc_balanced_about_its_first_point_is_fitted() {
    let (c, r) = ((0.0f64, 3000.0f64), 400.0f64);
    let mut pts = vec![(c.0, c.1 - r)];
    for k in 1..=4 {
        let t = 0.2 * f64::from(k);
        pts.push((c.0 + r * t.sin(), c.1 - r * t.cos()));
        pts.push((c.0 - r * t.sin(), c.1 - r * t.cos()));
    }
    let pts = f32s(&pts);
    let sx: f32 = pts.iter().map(|p| p.x - pts[0].x).sum();
    assert_eq!(sx, 0.0);
    for m in [
        CircleMethod::Kasa,
        CircleMethod::Taubin,
        CircleMethod::Hyper,
    ] {
        let got = c64(&fit_circle(&pts, m).unwrap());
        assert!(max_err(got, (c.0, c.1, r)) < 0.5, "{m:?}: {got:?}");
    }
}

/// A start off along one axis only: the first step is (−20, ≈0, ≈0) mm, and its length (not
/// a product of its components, which is ≈0) decides convergence, so the refinement moves.
#[test]
fn refinement_moves_a_start_off_along_one_axis() {
    let mut noise = Noise::new(3);
    let truth = (2000.0, 0.0, 300.0);
    let pts = f32s(&arc(
        (truth.0, truth.1),
        truth.2,
        (2.4, 3.9),
        21,
        0.0,
        &mut noise,
    ));
    for start in [
        (truth.0 + 20.0, truth.1, truth.2),
        (truth.0, truth.1, truth.2 - 20.0),
    ] {
        let c = c64(&refine_circle(&pts, circle(start.0, start.1, start.2), 30).unwrap());
        assert!(max_err(c, truth) < 0.05, "from {start:?}: {c:?}");
    }
}

/// A point at the circle's centre has no direction from it: the covariances skip it (the
/// same as without it), and the range-noise sandwich skips a point at the scanner itself.
#[test]
fn covariances_skip_points_without_a_direction() {
    let c = circle(1000.0, 2000.0, 300.0);
    let ring: Vec<Point> = (0..12)
        .map(|i| {
            let t = 0.3 * f64::from(i);
            Point::new(
                (1000.0 + 300.0 * t.cos()) as f32,
                (2000.0 + 300.0 * t.sin()) as f32,
            )
        })
        .collect();
    let mut with_centre = ring.clone();
    with_centre.push(Point::new(1000.0, 2000.0));
    assert_eq!(
        circle_covariance(&with_centre, &c, 5.0).unwrap(),
        circle_covariance(&ring, &c, 5.0).unwrap()
    );
    let o = Point::new(0.0, 0.0);
    assert_eq!(
        circle_covariance_range(&with_centre, &c, o, 5.0).unwrap(),
        circle_covariance_range(&ring, &c, o, 5.0).unwrap()
    );
    // A point at the scanner (on this circle through the origin) adds to WᵀW, not to the
    // noise in the middle.
    let c0 = circle(300.0, 0.0, 300.0);
    let through: Vec<Point> = (0..12)
        .map(|i| {
            let t = 1.0 + 0.3 * f64::from(i);
            Point::new((300.0 + 300.0 * t.cos()) as f32, (300.0 * t.sin()) as f32)
        })
        .collect();
    let mut at_origin = through.clone();
    at_origin.push(o);
    let a = circle_covariance_range(&at_origin, &c0, o, 5.0).unwrap();
    let b = circle_covariance_range(&through, &c0, o, 5.0).unwrap();
    assert!(a.iter().flatten().all(|v| v.is_finite()));
    assert!(a[0][0] < b[0][0], "more W rows, same noise: {a:?} {b:?}");
}
