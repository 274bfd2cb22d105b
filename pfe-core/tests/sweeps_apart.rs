//! `scatter::sweeps_apart` when the scatter within one sweep is within the noise: the
//! scatter across sweeps is then weighed against σ_r itself; and a scan of one sweep is never apart.

use pfe_core::geometry::Point;
use pfe_core::preprocess::scatter;

/// A noise-free wall 3 m ahead at 0.5° steps, the odd sweep `offset` mm farther.
fn wall(offset: f32) -> Vec<Point> {
    (0..181)
        .map(|i| {
            let b = (i as f32 - 90.0).to_radians() * 0.5;
            let r = 3000.0 / b.cos() + if i % 2 == 1 { offset } else { 0.0 };
            Point::new(r * b.cos(), r * b.sin())
        })
        .collect()
}

/// With a small σ_r (0.5 mm, under 1 mm where σ_r and 1/σ_r swap order) an offset of 4 σ_r
/// between the two sweeps is apart: every one-beam residual is about the offset, every
/// two-beam residual (one sweep) 0.
#[test]
fn sweeps_offset_by_four_sigma_are_apart_at_a_small_sigma() {
    for sigma_r in [0.5f32, 0.25] {
        assert!(
            scatter::sweeps_apart(&wall(4.0 * sigma_r), 2, sigma_r),
            "sigma_r {sigma_r}"
        );
        assert!(
            !scatter::sweeps_apart(&wall(0.0), 2, sigma_r),
            "sigma_r {sigma_r}"
        );
    }
}

/// A noise-free wall 3 m ahead at 0.5° steps whose ranges step by ±`offset` mm every two
/// beams (+, +, −, −, …): each one-beam residual is about `offset`, each two-beam residual
/// about twice it.
fn pairs(offset: f32) -> Vec<Point> {
    (0..181)
        .map(|i| {
            let b = (i as f32 - 90.0).to_radians() * 0.5;
            let r = 3000.0 / b.cos() + if i % 4 < 2 { offset } else { -offset };
            Point::new(r * b.cos(), r * b.sin())
        })
        .collect()
}

/// A scan of one sweep (or none) has no sweeps to be apart, however its points scatter: the
/// walls that are apart for two sweeps (every other beam 20 mm farther) and for four (ranges
/// ±10 mm in pairs of beams) are not for `sweeps` 0 or 1.
#[test]
fn one_sweep_is_never_apart() {
    let (odd, pair) = (wall(20.0), pairs(10.0));
    assert!(scatter::sweeps_apart(&odd, 2, 5.0));
    assert!(scatter::sweeps_apart(&pair, 4, 5.0));
    for sweeps in [0, 1] {
        assert!(!scatter::sweeps_apart(&odd, sweeps, 5.0), "sweeps {sweeps}");
        assert!(
            !scatter::sweeps_apart(&pair, sweeps, 5.0),
            "sweeps {sweeps}"
        );
    }
}
