//! The baselines against analytic scans: ranges computed by exact ray casting against known
//! walls and pillars (independent of the extractors), with and without seeded range noise.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: a panic fails the test

use pfe_core::{Feature, ScanGeometry};
use pfe_eval::methods::baselines::{Acf, SplitMerge};
use pfe_eval::methods::{Extraction, Method};
use pfe_eval::scene::{self as sim, Shape};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

const G: ScanGeometry = ScanGeometry::LMS200_180_050;

/// A wall `x cos α + y sin α = ρ` as a simulator segment of the points whose coordinate along
/// the line (direction (−sin α, cos α)) lies in `[t0, t1]` (clamped to ±100 m).
fn wall_part(alpha: f64, rho: f64, t0: f64, t1: f64) -> Shape {
    let (c, s) = (alpha.cos(), alpha.sin());
    let at = |t: f64| [rho * c - t * s, rho * s + t * c];
    Shape::Segment {
        a: at(t0.max(-1e5)),
        b: at(t1.min(1e5)),
    }
}

fn pillar(cx: f64, cy: f64, r: f64) -> Shape {
    Shape::Circle {
        center: [cx, cy],
        radius: r,
    }
}

/// Ranges (mm) of the LMS200 beams in `scene` by the simulator's exact ray caster (NaN = no
/// return), plus seeded N(0, σ) noise.
fn cast(scene: &[Shape], sigma: f64, seed: u64) -> Vec<f32> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, sigma.max(1e-12)).unwrap();
    sim::cast(scene, &G)
        .iter()
        .map(|h| match h {
            Some((t, _)) => {
                let n = if sigma > 0.0 {
                    noise.sample(&mut rng)
                } else {
                    0.0
                };
                (t + n) as f32
            }
            None => f32::NAN,
        })
        .collect()
}

fn methods() -> Vec<Box<dyn Method>> {
    vec![Box::new(SplitMerge::new()), Box::new(Acf::new())]
}

/// What `m` extracts from `r` (noise σ = `sigma`), which must be exactly one feature.
fn one_feature(m: &mut dyn Method, r: &[f32], sigma: f64) -> Extraction {
    let e = m.extract(&G, r);
    assert_eq!(
        e.features.len(),
        1,
        "{} σ={sigma}: {:?}",
        m.name(),
        e.features
    );
    e
}

/// The extraction's lines and its circles, each in order.
fn lines_and_circles(e: &Extraction) -> (Vec<pfe_core::LineFeature>, Vec<pfe_core::CircleFeature>) {
    let (mut lines, mut circles) = (Vec::new(), Vec::new());
    for f in &e.features {
        match f {
            Feature::Line(l) => lines.push(*l),
            Feature::Circle(c) => circles.push(*c),
            _ => {}
        }
    }
    (lines, circles)
}

fn lines(e: &Extraction) -> Vec<pfe_core::LineFeature> {
    lines_and_circles(e).0
}

fn circles(e: &Extraction) -> Vec<pfe_core::CircleFeature> {
    lines_and_circles(e).1
}

fn angle_diff(a: f32, b: f32) -> f32 {
    let d = (a - b).rem_euclid(std::f32::consts::TAU);
    d.min(std::f32::consts::TAU - d)
}

fn wall(alpha: f64, rho: f64) -> Shape {
    wall_part(alpha, rho, -1e9, 1e9)
}

#[test]
fn single_wall_is_one_line_with_its_parameters() {
    for (sigma, tol_a, tol_r) in [(0.0, 1e-4, 0.5), (5.0, 5e-3, 6.0)] {
        let r = cast(&[wall(0.3, 2500.0)], sigma, 1);
        for mut m in methods() {
            let e = one_feature(&mut *m, &r, sigma);
            let l = lines(&e)[0];
            assert!(
                angle_diff(l.alpha, 0.3) < tol_a,
                "{} α {}",
                m.name(),
                l.alpha
            );
            assert!((l.rho - 2500.0).abs() < tol_r, "{} ρ {}", m.name(), l.rho);
            assert!(l.var_alpha > 0.0 && l.var_rho > 0.0);
            // The wall is seen from the first valid beam to the last one.
            let valid: Vec<usize> = (0..r.len()).filter(|i| r[*i].is_finite()).collect();
            assert_eq!(usize::from(l.first), valid[0], "{}", m.name());
            assert_eq!(usize::from(l.last), *valid.last().unwrap(), "{}", m.name());
            assert_eq!(
                e.marks,
                vec![valid[0], *valid.last().unwrap()],
                "{}",
                m.name()
            );
        }
    }
}

#[test]
fn corner_gives_two_lines_split_at_the_corner() {
    // x = 3000 for y ≤ 1000, and y = 1000 for x ≤ 3000: corner at (3000, 1000), between beams
    // 216 (bearing 18.0°) and 217 (18.5°): atan2(1000, 3000) = 18.43°.
    let scene = [
        wall_part(0.0, 3000.0, -1e9, 1000.0),
        wall_part(std::f64::consts::FRAC_PI_2, 1000.0, -3000.0, 1e9),
    ];
    for sigma in [0.0, 5.0] {
        let r = cast(&scene, sigma, 2);
        for mut m in methods() {
            let e = m.extract(&G, &r);
            let ls = lines(&e);
            assert_eq!(ls.len(), 2, "{} σ={sigma}: {:?}", m.name(), e.features);
            assert!(circles(&e).is_empty(), "{}", m.name());
            let (a, b) = (ls[0], ls[1]);
            assert!(
                angle_diff(a.alpha, 0.0) < 0.01 && (a.rho - 3000.0).abs() < 10.0,
                "{a:?}"
            );
            assert!(
                angle_diff(b.alpha, std::f32::consts::FRAC_PI_2) < 0.01
                    && (b.rho - 1000.0).abs() < 10.0,
                "{b:?}"
            );
            assert!(
                (215..=217).contains(&usize::from(a.last)),
                "{} end {}",
                m.name(),
                a.last
            );
            assert!(
                (216..=218).contains(&usize::from(b.first)),
                "{} start {}",
                m.name(),
                b.first
            );
            assert_eq!(
                usize::from(a.last) + 1,
                usize::from(b.first),
                "{}",
                m.name()
            );
        }
    }
}

#[test]
fn gaps_break_a_wall() {
    // No-return hole in a wall at x = 2000: beams 170..=190 invalid.
    let mut r = cast(&[wall(0.0, 2000.0)], 0.0, 3);
    for v in &mut r[170..=190] {
        *v = f32::NAN;
    }
    // A doorway: the wall at x = 2500 is open for |y| < 400, a back wall at x = 5000.
    let door = [
        wall_part(0.0, 2500.0, -1e9, -400.0),
        wall_part(0.0, 2500.0, 400.0, 1e9),
        wall(0.0, 5000.0),
    ];
    let rd = cast(&door, 0.0, 4);
    // Beams seeing the back wall: |tan θ| · 2500 < 400.
    let back: Vec<usize> = (0..361)
        .filter(|i| (G.bearing(*i).tan() * 2500.0).abs() < 400.0)
        .collect();
    for mut m in methods() {
        let e = m.extract(&G, &r);
        let ls = lines(&e);
        assert_eq!(ls.len(), 2, "{}: {:?}", m.name(), e.features);
        assert_eq!(usize::from(ls[0].last), 169, "{}", m.name());
        assert_eq!(usize::from(ls[1].first), 191, "{}", m.name());
        for l in &ls {
            assert!((l.rho - 2000.0).abs() < 0.5 && angle_diff(l.alpha, 0.0) < 1e-3);
        }

        let e = m.extract(&G, &rd);
        let ls = lines(&e);
        assert_eq!(ls.len(), 3, "{}: {:?}", m.name(), e.features);
        assert_eq!(usize::from(ls[1].first), back[0], "{}", m.name());
        assert_eq!(
            usize::from(ls[1].last),
            *back.last().unwrap(),
            "{}",
            m.name()
        );
        assert!((ls[1].rho - 5000.0).abs() < 1.0, "{}", m.name());
        assert!((ls[0].rho - 2500.0).abs() < 1.0 && (ls[2].rho - 2500.0).abs() < 1.0);
    }
}

#[test]
fn pillar_is_one_circle_with_its_radius() {
    for (sigma, tol) in [(0.0, 1.0), (5.0, 8.0)] {
        let r = cast(&[pillar(2000.0, 300.0, 250.0)], sigma, 5);
        for mut m in methods() {
            let e = one_feature(&mut *m, &r, sigma);
            let c = circles(&e);
            assert_eq!(c.len(), 1, "{} σ={sigma}: not a circle", m.name());
            assert!(
                (c[0].radius - 250.0).abs() < tol,
                "{} R {}",
                m.name(),
                c[0].radius
            );
            assert!(
                (c[0].center.x - 2000.0).abs() < 2.0 * tol
                    && (c[0].center.y - 300.0).abs() < 2.0 * tol
            );
        }
    }
}

#[test]
fn pillar_before_a_wall() {
    let scene = [wall(0.0, 4000.0), pillar(2000.0, 0.0, 200.0)];
    for sigma in [0.0, 5.0] {
        let r = cast(&scene, sigma, 6);
        for mut m in methods() {
            let e = m.extract(&G, &r);
            let (ls, cs) = (lines(&e), circles(&e));
            assert_eq!(cs.len(), 1, "{} σ={sigma}: {:?}", m.name(), e.features);
            assert_eq!(ls.len(), 2, "{} σ={sigma}: {:?}", m.name(), e.features);
            assert!(
                (cs[0].radius - 200.0).abs() < 8.0,
                "{} R {}",
                m.name(),
                cs[0].radius
            );
            for l in ls {
                assert!((l.rho - 4000.0).abs() < 10.0, "{} ρ {}", m.name(), l.rho);
            }
        }
    }
}

#[test]
fn names() {
    assert_eq!(SplitMerge::new().name(), "split-merge");
    assert_eq!(Acf::new().name(), "acf");
}
