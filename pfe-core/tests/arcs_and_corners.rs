//! A pillar's arc against a corner of two walls, with the default configuration against
//! analytic ray casting (`common`):
//! - a pillar (radius 300 mm, 1.5 m away, σ_r 5 mm as in the evaluation) seen through a
//!   doorway, only 50° of its arc between the door's jambs (a pillar cut by marks), is a
//!   circle in at least 220 of 300 scans, though two lines meeting at its middle fit its
//!   points nearly as well: the circle may leave two noise variances more than that split;
//! - a wide (150°) corner of two 0.4 m walls 3 m away in front of open space or a far wall
//!   (σ_r 10 mm, 1° beams), which a circle fits about as well as two lines, gets no circle
//!   from the allowance: the beams just past the walls' ends see through where that circle
//!   would be (at most 1 in 30 scans, those whose circle beats the split outright);
//! - a curved wall (a 400 mm arc of ±40°) in front of open space, whose circle beats the
//!   split outright, stays a circle though those beams see through its whole circle.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

mod common;

use common::{scan, Noise, Prim};
use pfe_core::{Config, Extractor, Feature, Scan, ScanGeometry};
use std::f64::consts::PI;

fn noisy(exact: &[f32], sigma: f64, noise: &mut Noise) -> Vec<f32> {
    exact
        .iter()
        .map(|&x| (f64::from(x) + sigma * noise.gauss()) as f32)
        .collect()
}

fn circles(features: &[Feature]) -> impl Iterator<Item = &pfe_core::CircleFeature> {
    features.iter().filter_map(|f| match f {
        Feature::Circle(c) => Some(c),
        _ => None,
    })
}

#[test]
fn a_pillar_seen_through_a_doorway_stays_a_circle() {
    let g = ScanGeometry::LMS200_180_050;
    let (start, step) = (f64::from(g.start_angle), f64::from(g.angle_step));
    let config = Config::default();
    let mut ex = Extractor::<361, 64>::new();
    let (r, dist, wall) = (300.0f64, 1500.0f64, 1000.0f64);
    let (mut found, mut cases) = (0, 0);
    for (bi, bearing) in [-0.5f64, 0.1, 0.6].into_iter().enumerate() {
        let (cx, cy) = (dist * bearing.cos(), dist * bearing.sin());
        // The pillar's point at polar angle `a` from the direction back to the scanner, and
        // its bearing: the jambs leave ±25° of the arc in view.
        let at = |a: f64| (cx - r * (bearing + a).cos(), cy - r * (bearing + a).sin());
        let bear = |p: (f64, f64)| p.1.atan2(p.0);
        let (lo, hi) = (bear(at(0.25 * PI / 1.8)), bear(at(-0.25 * PI / 1.8)));
        let (lo, hi) = (lo.min(hi), lo.max(hi));
        let jamb = |from: f64, to: f64| {
            Prim::Seg(
                wall * from.cos(),
                wall * from.sin(),
                wall * to.cos(),
                wall * to.sin(),
            )
        };
        let prims = [
            Prim::Circle(cx, cy, r),
            jamb(lo - 0.3, lo),
            jamb(hi, hi + 0.3),
            Prim::Seg(7900.0, -8000.0, 7900.0, 8000.0),
        ];
        let (exact, hits) = scan(&prims, start, step, 361, 8000.0);
        let on: Vec<usize> = (0..361).filter(|&i| hits[i] == Some(0)).collect();
        let (a, z) = (on[0], *on.last().unwrap());
        assert!((22..=26).contains(&(z + 1 - a)), "pillar beams {a}..={z}");
        for t in 0..100u64 {
            cases += 1;
            let mut noise = Noise::new(3000 + 100 * bi as u64 + t);
            let ranges = noisy(&exact, 5.0, &mut noise);
            ex.extract(&Scan::from_mm(g, &ranges), &config).unwrap();
            found += usize::from(circles(ex.features()).any(|c| {
                (c.radius - 300.0).abs() < 60.0
                    && usize::from(c.first) <= a + 1
                    && usize::from(c.last) + 1 >= z
            }));
        }
    }
    assert!(
        found >= 220,
        "{found} of {cases} pillars in a doorway a circle"
    );
}

#[test]
fn a_wide_corner_in_front_of_open_space_is_no_circle() {
    let g = ScanGeometry::lms200(180.0, 1.0);
    let (start, step) = (f64::from(g.start_angle), f64::from(g.angle_step));
    let config = Config::default().with_sigma_r(10.0);
    let mut ex = Extractor::<181, 64>::new();
    let (dist, len, out) = (3000.0f64, 400.0f64, 75f64.to_radians());
    let (mut found, mut cases) = (0, 0);
    // Behind the corner: nothing within the scanner's 8 m, or a wall 6 m away.
    for (wi, far) in [9000.0f64, 6000.0].into_iter().enumerate() {
        for (bi, bearing) in [-0.4f64, 0.0, 0.5].into_iter().enumerate() {
            // Apex towards the scanner, each wall leaving it 75° off the line of sight.
            let (ax, ay) = (dist * bearing.cos(), dist * bearing.sin());
            let leg = |side: f64| {
                let d = bearing + side * out;
                Prim::Seg(ax, ay, ax + len * d.cos(), ay + len * d.sin())
            };
            let prims = [leg(1.0), leg(-1.0), Prim::Seg(far, -9000.0, far, 9000.0)];
            let (exact, _) = scan(&prims, start, step, 181, 8000.0);
            for t in 0..100u64 {
                cases += 1;
                let mut noise = Noise::new(5000 + 1000 * wi as u64 + 100 * bi as u64 + t);
                let ranges = noisy(&exact, 10.0, &mut noise);
                ex.extract(&Scan::from_mm(g, &ranges), &config).unwrap();
                found += circles(ex.features())
                    .filter(|c| f64::from(c.center.x) < far - 500.0)
                    .count();
            }
        }
    }
    // 16 of these 600 circles beat the two-line split outright (main's typing gives them
    // too); those only the split allowance let through the see-through check removes (42 in
    // all without it).
    assert!(
        found * 30 <= cases,
        "{found} circles in {cases} scans of wide corners"
    );
}

/// A quarter-round bay, an arc of a wall (radius 400 mm, 2 m away, ±40° of it facing the
/// scanner, σ_r 5 mm) in front of a far wall: its circle beats two lines outright, so it stays
/// a circle although the beams just past its ends cross where the whole circle would be and
/// see the wall behind (the see-through check is for circles only the allowance let through).
#[test]
fn a_curved_wall_in_front_of_open_space_stays_a_circle() {
    let g = ScanGeometry::LMS200_180_050;
    let (start, step) = (f64::from(g.start_angle), f64::from(g.angle_step));
    let config = Config::default();
    let mut ex = Extractor::<361, 64>::new();
    let (r, dist) = (400.0f64, 2000.0f64);
    let (mut found, mut cases) = (0, 0);
    for (bi, bearing) in [-0.6f64, 0.0, 0.4].into_iter().enumerate() {
        let (cx, cy) = (dist * bearing.cos(), dist * bearing.sin());
        // The arc's points from polar angle −40° to 40° about the direction back to the scanner.
        let at = |a: f64| {
            let t = bearing + PI + a.to_radians();
            (cx + r * t.cos(), cy + r * t.sin())
        };
        let prims: Vec<Prim> = (-40..40)
            .map(|a| {
                let (p, q) = (at(f64::from(a)), at(f64::from(a + 1)));
                Prim::Seg(p.0, p.1, q.0, q.1)
            })
            .chain([Prim::Seg(5000.0, -8000.0, 5000.0, 8000.0)])
            .collect();
        let (exact, hits) = scan(&prims, start, step, 361, 8000.0);
        let on: Vec<usize> = (0..361)
            .filter(|&i| hits[i].is_some_and(|h| h < 80))
            .collect();
        let (a, z) = (on[0], *on.last().unwrap());
        // The beams past the arc's ends see the far wall, inside the whole circle's outline.
        assert!(
            exact[a - 1] > 4000.0 && exact[z + 1] > 4000.0,
            "beams {a}..={z}"
        );
        for t in 0..100u64 {
            cases += 1;
            let mut noise = Noise::new(7000 + 100 * bi as u64 + t);
            let ranges = noisy(&exact, 5.0, &mut noise);
            ex.extract(&Scan::from_mm(g, &ranges), &config).unwrap();
            found += usize::from(circles(ex.features()).any(|c| {
                (c.radius - 400.0).abs() < 40.0
                    && usize::from(c.first) <= a + 1
                    && usize::from(c.last) + 1 >= z
            }));
        }
    }
    assert!(found >= 285, "{found} of {cases} curved walls a circle");
}
