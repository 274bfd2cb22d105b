//! Monte Carlo: the predicted line and circle covariances match the empirical spread of the
//! fitted parameters (σ_r = 5 mm), for range noise (what the features carry) and
//! for isotropic Cartesian noise (the paper's formulas, Jensfelt & Christensen and
//! Al-Sharadqah & Chernov).
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

mod common;

use common::{wall_ranges, Noise};
use pfe_core::{
    circle_covariance, circle_covariance_range, fit_circle, fit_line, refine_circle, Circle,
    CircleMethod, Config, Extractor, Feature, Point, Scan, ScanGeometry,
};

const TRIALS: usize = 2000;
const SIGMA: f64 = 5.0;

fn var(xs: &[f64]) -> f64 {
    let m = xs.iter().sum::<f64>() / xs.len() as f64;
    xs.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (xs.len() - 1) as f64
}

fn cov(xs: &[f64], ys: &[f64]) -> f64 {
    let mx = xs.iter().sum::<f64>() / xs.len() as f64;
    let my = ys.iter().sum::<f64>() / ys.len() as f64;
    xs.iter()
        .zip(ys)
        .map(|(x, y)| (x - mx) * (y - my))
        .sum::<f64>()
        / (xs.len() - 1) as f64
}

/// How many standard deviations of the sampling distribution a statistic may be off.
const Z: f64 = 3.0;

/// The sample variance of `n` Gaussian draws is σ² χ²_{n−1}/(n−1): its relative standard
/// deviation is √(2/(n−1)) (3.2 % for 2 000 trials), so a predicted variance is accepted when
/// the empirical one is within `Z` of those (±9.5 % at 3σ), not within a fixed 15 %.
fn within(name: &str, predicted: f64, empirical: f64, n: usize) {
    let tol = Z * (2.0 / (n - 1) as f64).sqrt();
    let rel = empirical / predicted - 1.0;
    eprintln!(
        "{name}: empirical/predicted − 1 = {:+.2}% (±{:.1}%)",
        rel * 100.0,
        tol * 100.0
    );
    assert!(
        rel.abs() <= tol,
        "{name}: predicted {predicted:.4e}, empirical {empirical:.4e} ({:+.1}%, allowed ±{:.1}% over {n} trials)",
        rel * 100.0,
        tol * 100.0
    );
}

/// A sample correlation of `n` draws has a standard deviation of about (1 − ρ²)/√(n − 1).
fn within_corr(name: &str, predicted: f64, empirical: f64, n: usize) {
    let tol = Z * (1.0 - predicted * predicted) / ((n - 1) as f64).sqrt();
    assert!(
        (predicted - empirical).abs() <= tol + 1e-3,
        "{name}: predicted correlation {predicted:.4}, empirical {empirical:.4} (allowed ±{tol:.4})"
    );
}

#[test]
fn the_tolerances_reject_a_formula_ten_percent_off() {
    // 2 000 trials: a variance 10 % too small or too large is caught, one 5 % off is not.
    let caught = |ratio: f64| std::panic::catch_unwind(|| within("x", 1.0, ratio, TRIALS)).is_err();
    assert!(caught(1.10) && caught(0.90) && !caught(1.05) && !caught(0.95));
    let caught =
        |p: f64, e: f64| std::panic::catch_unwind(|| within_corr("c", p, e, TRIALS)).is_err();
    assert!(caught(0.5, 0.56) && !caught(0.5, 0.52));
}

/// Range-noise scan of a wall `x cos α + y sin α = ρ` through the extractor: the line
/// feature's σ_α², σ_ρ², cov(α, ρ) against the spread over trials.
fn line_through_extractor(alpha: f64, rho: f64) {
    let g = ScanGeometry::LMS200_180_050;
    let mut noise = Noise::new(7);
    let (mut al, mut rh) = (Vec::new(), Vec::new());
    let mut predicted = (0.0, 0.0, 0.0);
    let mut ex = Extractor::<361, 16>::new();
    let mut split = 0;
    for _ in 0..TRIALS {
        // The wall between ±35° of its normal.
        let ranges = wall_ranges(g, (alpha, rho), 35f64.to_radians(), |on| {
            if on {
                SIGMA * noise.gauss()
            } else {
                0.0
            }
        });
        ex.extract(&Scan::from_mm(g, &ranges), &Config::default())
            .unwrap();
        let [Feature::Line(l)] = ex.features() else {
            // A 4σ false split happens about once in 50 scans of 140 points: count it.
            split += 1;
            continue;
        };
        al.push(l.alpha as f64);
        rh.push(l.rho as f64);
        predicted.0 += l.var_alpha as f64;
        predicted.1 += l.var_rho as f64;
        predicted.2 += l.cov_alpha_rho as f64;
    }
    assert!(split * 20 < TRIALS, "{split} of {TRIALS} walls split");
    // The mean prediction over the trials against the spread.
    let n = al.len();
    let predicted = (
        predicted.0 / n as f64,
        predicted.1 / n as f64,
        predicted.2 / n as f64,
    );
    within("var_alpha", predicted.0, var(&al), n);
    within("var_rho", predicted.1, var(&rh), n);
    let corr_pred = predicted.2 / (predicted.0 * predicted.1).sqrt();
    let corr_emp = cov(&al, &rh) / (var(&al) * var(&rh)).sqrt();
    within_corr("corr(alpha, rho)", corr_pred, corr_emp, n);
}

#[test]
fn line_covariance_head_on_wall() {
    line_through_extractor(0.0, 2000.0);
}

#[test]
fn line_covariance_oblique_wall() {
    // Off-centre wall: α and ρ are strongly correlated.
    line_through_extractor(0.7, 1500.0);
}

#[test]
fn line_covariance_jensfelt_christensen_isotropic() {
    let mut noise = Noise::new(11);
    let truth: Vec<(f64, f64)> = (0..80)
        .map(|i| (1000.0 + 10.0 * i as f64, 500.0 + 4.0 * i as f64))
        .collect();
    let (mut al, mut rh) = (Vec::new(), Vec::new());
    let mut predicted = (0.0, 0.0, 0.0);
    for _ in 0..TRIALS {
        let pts = jitter(&truth, &mut noise);
        let l = fit_line(&pts).unwrap();
        let c = l.covariance_jc(25.0, 25.0, 0.0);
        al.push(l.alpha as f64);
        rh.push(l.rho as f64);
        predicted.0 += c.var_alpha as f64 / TRIALS as f64;
        predicted.1 += c.var_rho as f64 / TRIALS as f64;
        predicted.2 += c.cov_alpha_rho as f64 / TRIALS as f64;
    }
    within("J&C var_alpha", predicted.0, var(&al), TRIALS);
    within("J&C var_rho", predicted.1, var(&rh), TRIALS);
    within_corr(
        "J&C corr(alpha, rho)",
        predicted.2 / (predicted.0 * predicted.1).sqrt(),
        cov(&al, &rh) / (var(&al) * var(&rh)).sqrt(),
        TRIALS,
    );
}

/// `truth` with independent Gaussian noise of σ = `SIGMA` on x and on y.
fn jitter(truth: &[(f64, f64)], noise: &mut Noise) -> Vec<Point> {
    truth
        .iter()
        .map(|&(x, y)| {
            Point::new(
                (x + SIGMA * noise.gauss()) as f32,
                (y + SIGMA * noise.gauss()) as f32,
            )
        })
        .collect()
}

fn circle_points(c: (f64, f64, f64), from: f64, to: f64, n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            let t = from + (to - from) * i as f64 / (n - 1) as f64;
            (c.0 + c.2 * t.cos(), c.1 + c.2 * t.sin())
        })
        .collect()
}

/// The full empirical covariance of (cx, cy, R) against the mean predicted one: variances by
/// [`within`], the three correlations by [`within_corr`].
fn check_circle_spread(samples: &[[f64; 3]], predicted: [[f64; 3]; 3], label: &str) {
    let n = samples.len();
    let col = |k: usize| samples.iter().map(|s| s[k]).collect::<Vec<f64>>();
    for (k, row) in predicted.iter().enumerate() {
        within(&format!("{label} var[{k}]"), row[k], var(&col(k)), n);
    }
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        let (xi, xj) = (col(i), col(j));
        within_corr(
            &format!("{label} corr[{i}][{j}]"),
            predicted[i][j] / (predicted[i][i] * predicted[j][j]).sqrt(),
            cov(&xi, &xj) / (var(&xi) * var(&xj)).sqrt(),
            n,
        );
    }
}

/// Adds `c / count` to the running mean `acc`.
fn accumulate(acc: &mut [[f64; 3]; 3], c: [[f32; 3]; 3], count: usize) {
    for i in 0..3 {
        for j in 0..3 {
            acc[i][j] += c[i][j] as f64 / count as f64;
        }
    }
}

#[test]
fn circle_covariance_isotropic_noise() {
    // Half of a pillar of radius 300 mm: σ²(WᵀW)⁻¹ against the spread of the Hyper fit.
    let truth = circle_points((1500.0, 200.0, 300.0), 1.8, 4.5, 60);
    let mut noise = Noise::new(3);
    let mut samples = Vec::new();
    let mut predicted = [[0.0; 3]; 3];
    for _ in 0..TRIALS {
        let pts = jitter(&truth, &mut noise);
        let c = refine_circle(&pts, fit_circle(&pts, CircleMethod::Hyper).unwrap(), 10).unwrap();
        samples.push([c.center.x as f64, c.center.y as f64, c.radius as f64]);
        accumulate(
            &mut predicted,
            circle_covariance(&pts, &c, SIGMA as f32).unwrap(),
            TRIALS,
        );
    }
    check_circle_spread(&samples, predicted, "isotropic");
}

#[test]
fn circle_covariance_range_noise_through_extractor() {
    // A free pillar (radius 250 mm, 2 m ahead) seen by the LMS200 with range noise.
    let g = ScanGeometry::LMS200_180_050;
    let (cx, cy, r) = (2000.0f64, 300.0f64, 250.0f64);
    let mut noise = Noise::new(5);
    let mut samples = Vec::new();
    let mut covs = Vec::new();
    let mut ex = Extractor::<361, 16>::new();
    let mut split = 0;
    // The beams that hit the pillar.
    let hit = |i: usize| {
        let b = g.bearing(i) as f64;
        let bb = b.cos() * cx + b.sin() * cy;
        bb * bb - (cx * cx + cy * cy - r * r) > 0.0
    };
    let first = (0..361).find(|&i| hit(i)).unwrap();
    let last = (0..361).rev().find(|&i| hit(i)).unwrap();
    for _ in 0..TRIALS {
        let ranges: Vec<f32> = (0..361)
            .map(|i| {
                let b = g.bearing(i) as f64;
                let (dx, dy) = (b.cos(), b.sin());
                let bb = dx * cx + dy * cy;
                let disc = bb * bb - (cx * cx + cy * cy - r * r);
                if disc > 0.0 {
                    ((bb - disc.sqrt()) + SIGMA * noise.gauss()) as f32
                } else {
                    f32::NAN
                }
            })
            .collect();
        ex.extract(&Scan::from_mm(g, &ranges), &Config::default())
            .unwrap();
        let circles: Vec<_> = ex
            .features()
            .iter()
            .filter(|f| matches!(f, Feature::Circle(_)))
            .collect();
        let [c] = circles[..] else {
            split += 1;
            continue;
        };
        if (c.first(), c.last()) != (first, last) {
            split += 1;
            continue;
        }
        let Feature::Circle(c) = c else {
            unreachable!()
        };
        samples.push([c.center.x as f64, c.center.y as f64, c.radius as f64]);
        covs.push(c.cov);
    }
    let mut predicted = [[0.0f64; 3]; 3];
    for c in &covs {
        accumulate(&mut predicted, *c, covs.len());
    }
    assert!(
        split * 50 < TRIALS,
        "{split} of {TRIALS} pillars not one whole circle"
    );
    check_circle_spread(&samples, predicted, "range");
    // And the sandwich formula equals σ²(WᵀW)⁻¹ when every beam meets the circle head on
    // (scanner at the centre of a round room).
    let pts: Vec<Point> = circle_points((0.0, 0.0, 3000.0), -1.0, 1.0, 50)
        .into_iter()
        .map(|(x, y)| Point::new(x as f32, y as f32))
        .collect();
    let room = Circle {
        center: Point::new(0.0, 0.0),
        radius: 3000.0,
    };
    let a = circle_covariance(&pts, &room, 5.0).unwrap();
    let b = circle_covariance_range(&pts, &room, Point::new(0.0, 0.0), 5.0).unwrap();
    for k in 0..3 {
        assert!(
            (a[k][k] - b[k][k]).abs() <= 1e-3 * a[k][k].abs(),
            "{a:?} vs {b:?}"
        );
    }
}
