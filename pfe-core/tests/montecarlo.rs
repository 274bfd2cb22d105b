//! Monte Carlo: the predicted line and circle covariances match the empirical spread of the
//! fitted parameters within 15% (σ_r = 5 mm), for range noise (what the features carry) and
//! for isotropic Cartesian noise (the paper's formulas, Jensfelt & Christensen and
//! Al-Sharadqah & Chernov).
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

mod common;

use common::Noise;
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

fn within(name: &str, predicted: f64, empirical: f64, tol: f64) {
    let rel = (predicted - empirical).abs() / empirical;
    assert!(
        rel <= tol,
        "{name}: predicted {predicted:.4e}, empirical {empirical:.4e} ({:.1}%)",
        rel * 100.0
    );
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
        let ranges: Vec<f32> = (0..361)
            .map(|i| {
                let b = g.bearing(i) as f64;
                let den = (b - alpha).cos();
                // The wall between ±35° of its normal.
                if (b - alpha).abs() < 35f64.to_radians() && den > 0.0 {
                    (rho / den + SIGMA * noise.gauss()) as f32
                } else {
                    f32::NAN
                }
            })
            .collect();
        ex.extract(&Scan::from_mm(g, &ranges), &Config::default())
            .unwrap();
        let [Feature::Line(l)] = ex.features() else {
            // A 4σ false split happens about once in 50 scans of 140 points: count it.
            split += 1;
            continue;
        };
        al.push(l.alpha as f64);
        rh.push(l.rho as f64);
        predicted = (l.var_alpha as f64, l.var_rho as f64, l.cov_alpha_rho as f64);
    }
    assert!(split * 20 < TRIALS, "{split} of {TRIALS} walls split");
    within("var_alpha", predicted.0, var(&al), 0.15);
    within("var_rho", predicted.1, var(&rh), 0.15);
    let corr_pred = predicted.2 / (predicted.0 * predicted.1).sqrt();
    let corr_emp = cov(&al, &rh) / (var(&al) * var(&rh)).sqrt();
    assert!(
        (corr_pred - corr_emp).abs() < 0.1,
        "corr {corr_pred} vs {corr_emp}"
    );
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
    let mut predicted = (0.0, 0.0);
    for _ in 0..TRIALS {
        let pts: Vec<Point> = truth
            .iter()
            .map(|&(x, y)| {
                Point::new(
                    (x + SIGMA * noise.gauss()) as f32,
                    (y + SIGMA * noise.gauss()) as f32,
                )
            })
            .collect();
        let l = fit_line(&pts).unwrap();
        let c = l.covariance_jc(25.0, 25.0, 0.0);
        al.push(l.alpha as f64);
        rh.push(l.rho as f64);
        predicted = (c.var_alpha as f64, c.var_rho as f64);
    }
    within("J&C var_alpha", predicted.0, var(&al), 0.15);
    within("J&C var_rho", predicted.1, var(&rh), 0.15);
}

fn circle_points(c: (f64, f64, f64), from: f64, to: f64, n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            let t = from + (to - from) * i as f64 / (n - 1) as f64;
            (c.0 + c.2 * t.cos(), c.1 + c.2 * t.sin())
        })
        .collect()
}

fn check_circle_spread(samples: &[[f64; 3]], predicted: [[f32; 3]; 3], label: &str) {
    for k in 0..3 {
        let xs: Vec<f64> = samples.iter().map(|s| s[k]).collect();
        within(
            &format!("{label} var[{k}]"),
            predicted[k][k] as f64,
            var(&xs),
            0.15,
        );
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
        let pts: Vec<Point> = truth
            .iter()
            .map(|&(x, y)| {
                Point::new(
                    (x + SIGMA * noise.gauss()) as f32,
                    (y + SIGMA * noise.gauss()) as f32,
                )
            })
            .collect();
        let c = refine_circle(&pts, fit_circle(&pts, CircleMethod::Hyper).unwrap(), 10).unwrap();
        samples.push([c.center.x as f64, c.center.y as f64, c.radius as f64]);
        predicted = circle_covariance(&pts, &c, SIGMA as f32).unwrap();
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
    let mut predicted = [[0.0f32; 3]; 3];
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
        let circles: Vec<_> = ex.features().iter().filter(|f| !f.is_line()).collect();
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
        predicted = c.cov;
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
