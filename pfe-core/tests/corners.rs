//! Corners the walk can follow without a mark: a room corner rounded over a few beams (as in
//! the real logs) bends the walls' points by so little from one beam to the next that the walk
//! predicts through it (as through an arc). One line over both walls would be garbage; the
//! default mode must give the two walls, each on its wall. Truth is the analytic ray casting
//! of `common`.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

mod common;

use common::{scan, Noise, Prim};
use pfe_core::{Config, Extractor, Feature, Scan, ScanGeometry};

/// Wall A: y = −1350 mm (normal angle −π/2, ρ 1350); wall B: x = 1440 mm (normal angle 0,
/// ρ 1440); the concave corner between them rounded with radius `r` (a polyline of 12 chords).
fn room(r: f64) -> Vec<Prim> {
    let (cx, cy) = (1440.0 - r, -1350.0 + r);
    let mut prims = vec![
        Prim::Seg(-500.0, -1350.0, cx, -1350.0),
        Prim::Seg(1440.0, cy, 1440.0, 800.0),
    ];
    let arc = |k: usize| {
        let a = -core::f64::consts::FRAC_PI_2 + core::f64::consts::FRAC_PI_2 * k as f64 / 12.0;
        (cx + r * a.cos(), cy + r * a.sin())
    };
    for k in 0..12 {
        let ((x0, y0), (x1, y1)) = (arc(k), arc(k + 1));
        prims.push(Prim::Seg(x0, y0, x1, y1));
    }
    prims
}

/// Wall A's and wall B's (α, ρ).
const WALLS: [(f32, f32); 2] = [(-core::f32::consts::FRAC_PI_2, 1350.0), (0.0, 1440.0)];

#[test]
fn a_rounded_corner_gives_the_two_walls() {
    let g = ScanGeometry::LMS200_180_050;
    let mut ex = Extractor::<361, 64>::new();
    let config = Config::default().with_sigma_r(10.0);
    let (mut garbage, mut found) = (0, [0usize; 2]);
    for (t, r) in [60.0, 100.0, 150.0].into_iter().enumerate() {
        let (exact, hits) = scan(
            &room(r),
            f64::from(g.start_angle),
            f64::from(g.angle_step),
            361,
            f64::from(g.r_max),
        );
        for seed in 0..20u64 {
            let mut noise = Noise::new(100 * t as u64 + seed);
            // σ 3 mm, rounded to the cm as the CARMEN logs are.
            let ranges: Vec<f32> = exact
                .iter()
                .map(|&x| ((f64::from(x) + 3.0 * noise.gauss()) / 10.0).round() as f32 * 10.0)
                .collect();
            ex.extract(&Scan::from_mm(g, &ranges), &config).unwrap();
            // The pieces of a split segment neither overlap nor leave a point out of order.
            for (a, b) in ex.features().iter().zip(ex.features().iter().skip(1)) {
                assert!(a.last() < b.first(), "r {r} seed {seed}: {a:?} then {b:?}");
            }
            for f in ex.features() {
                let Feature::Line(l) = f else { continue };
                if l.points < 10 {
                    continue;
                }
                // Beams of the line on wall A, on wall B.
                let on = |w: usize| {
                    hits[f.first()..=f.last()]
                        .iter()
                        .filter(|h| **h == Some(w))
                        .count()
                };
                let (a, b) = (on(0), on(1));
                if a >= 3 && b >= 3 {
                    garbage += 1;
                    eprintln!("r {r} seed {seed}: one line over both walls: {l:?}");
                    continue;
                }
                // Mostly on one wall: on it, normal within 0.03 rad and distance within 15 mm.
                for (w, n) in [a, b].into_iter().enumerate() {
                    if 5 * n >= 4 * l.points as usize {
                        let (alpha, rho) = WALLS[w];
                        assert!(
                            (l.alpha - alpha).abs() < 0.03 && (l.rho - rho).abs() < 15.0,
                            "r {r} seed {seed}: {l:?} off wall {w}"
                        );
                        found[w] += 1;
                    }
                }
            }
        }
    }
    assert_eq!(garbage, 0, "lines of ≥ 10 points over both walls");
    // Every scan gives each wall (60 scans).
    assert!(found.iter().all(|&n| n >= 60), "{found:?}");
}
