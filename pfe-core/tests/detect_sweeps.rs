//! `interleave::detect` against truth: rooms (`common::room`, cast in f64) seen by one sweep
//! are never declared interleaved, at any noise; seen by 2 sweeps (0.5°) or 4 (0.25°) of a
//! scanner moving 8 mm / 6 mrad a mirror turn they are; garbage never panics.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: a panic fails the test
#![allow(clippy::indexing_slicing)]

mod common;

use common::{cast, room, seen_from, Noise, Prim};
use pfe_core::interleave::detect;
use pfe_core::{Scan, ScanGeometry};
use proptest::prelude::*;

/// A scan of `prims` at `step_deg` over 180°, beam `i` from the pose of sweep `i mod sweeps`
/// (sweep `s`: `s` times `(dx mm, dθ rad)` forward and turned), rounded to mm, with noise `sigma`.
fn scan_of(
    prims: &[Prim],
    step_deg: f64,
    sweeps: usize,
    (dx, dth): (f64, f64),
    sigma: f64,
    noise: &mut Noise,
) -> (ScanGeometry, Vec<f32>) {
    let n = (180.0 / step_deg) as usize + 1;
    let g = ScanGeometry::lms200(180.0, step_deg as f32);
    let views: Vec<Vec<Prim>> = (0..sweeps)
        .map(|s| seen_from(prims, (dx * s as f64, 0.0, dth * s as f64)))
        .collect();
    let ranges = (0..n)
        .map(|i| {
            let b = -std::f64::consts::FRAC_PI_2 + (step_deg * i as f64).to_radians();
            match cast(&views[i % sweeps], b) {
                Some((t, _)) if t <= 8000.0 => (t + sigma * noise.gauss()).round().max(1.0) as f32,
                _ => f32::NAN,
            }
        })
        .collect();
    (g, ranges)
}

fn detected(g: ScanGeometry, ranges: &[f32]) -> u8 {
    detect(&Scan::from_mm(g, ranges).with_quantum(1.0)).sweeps
}

#[test]
fn one_sweep_is_never_declared_interleaved() {
    let mut rooms = Noise::new(7);
    for k in 0..40 {
        let prims = room(&mut rooms);
        for sigma in [0.0, 1.0, 2.0, 5.0, 10.0] {
            let mut noise = Noise::new(1000 + k);
            for step in [1.0, 0.5, 0.25] {
                let (g, r) = scan_of(&prims, step, 1, (0.0, 0.0), sigma, &mut noise);
                let d = detect(&Scan::from_mm(g, &r).with_quantum(1.0));
                assert_eq!(d.sweeps, 1, "room {k} σ {sigma} step {step}: {d:?}");
                assert!(d.evidence2.is_finite() && d.evidence4.is_finite());
            }
        }
    }
}

#[test]
fn sweeps_of_a_moving_scanner_are_found() {
    let mut rooms = Noise::new(8);
    let (mut found2, mut found4, n) = (0usize, 0usize, 40u64);
    for k in 0..n {
        let prims = room(&mut rooms);
        let mut noise = Noise::new(2000 + k);
        let (g, r) = scan_of(&prims, 0.5, 2, (8.0, 0.006), 5.0, &mut noise);
        let d2 = detected(g, &r);
        assert_ne!(d2, 4, "room {k}: 2 sweeps taken for 4");
        found2 += usize::from(d2 == 2);
        let (g, r) = scan_of(&prims, 0.25, 4, (8.0, 0.006), 5.0, &mut noise);
        let d4 = detected(g, &r);
        assert_ne!(d4, 2, "room {k}: 4 sweeps taken for 2");
        found4 += usize::from(d4 == 4);
    }
    eprintln!("found: 2 sweeps {found2}/{n}, 4 sweeps {found4}/{n}");
    assert!(
        found2 as u64 >= n * 9 / 10,
        "2 sweeps found in {found2} of {n}"
    );
    assert!(
        found4 as u64 >= n * 9 / 10,
        "4 sweeps found in {found4} of {n}"
    );
}

#[test]
fn a_scanner_standing_still_shows_one_sweep() {
    // Interleaved, but every sweep from the same pose: nothing to see, nothing to align.
    let mut rooms = Noise::new(9);
    for k in 0..20 {
        let prims = room(&mut rooms);
        let mut noise = Noise::new(3000 + k);
        let (g, r) = scan_of(&prims, 0.5, 2, (0.0, 0.0), 2.0, &mut noise);
        assert_eq!(detected(g, &r), 1, "room {k}");
    }
}

#[test]
fn too_little_scan_is_one_sweep() {
    let g = ScanGeometry::LMS200_180_050;
    assert_eq!(detected(g, &[]), 1);
    // 20 returns with an 8 mm zigzag: too few chunks to tell.
    let r: Vec<f32> = (0..20).map(|i| 2000.0 + 8.0 * (i % 2) as f32).collect();
    assert_eq!(detected(g, &r), 1);
    let nan = [f32::NAN; 361];
    assert_eq!(detected(g, &nan), 1);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    #[test]
    fn garbage_never_panics(
        ranges in proptest::collection::vec(
            prop_oneof![
                Just(f32::NAN), Just(f32::INFINITY), Just(-1.0f32), Just(0.0f32), Just(f32::MAX),
                1.0f32..8000.0, -1e30f32..1e30,
            ],
            0..800,
        ),
        start in -10.0f32..10.0,
        step in prop_oneof![Just(0.0f32), Just(f32::NAN), -0.1f32..0.1],
        r_max in prop_oneof![Just(f32::INFINITY), Just(8000.0f32), Just(f32::MAX), 0.0f32..1e6],
        quantum in prop_oneof![Just(f32::NAN), Just(0.0f32), Just(-1.0f32), 0.0f32..100.0],
    ) {
        let g = ScanGeometry::new(start, step, r_max);
        let d = detect(&Scan::from_mm(g, &ranges).with_quantum(quantum));
        prop_assert!(matches!(d.sweeps, 1 | 2 | 4));
        let raw: Vec<u16> = ranges.iter().map(|r| if r.is_finite() { r.abs().min(65535.0) as u16 } else { 0 }).collect();
        let d = detect(&Scan::from_lms(g, &raw, 1.0));
        prop_assert!(matches!(d.sweeps, 1 | 2 | 4));
    }

    #[test]
    fn a_zigzag_on_a_smooth_surface_is_two_sweeps(
        rho in 1000.0f32..6000.0, offset in 15.0f32..40.0, seed in 0u64..1000,
    ) {
        // A wall ahead, noise 2 mm; the odd beams `offset` mm further.
        let g = ScanGeometry::LMS200_180_050;
        let mut noise = Noise::new(seed);
        let r: Vec<f32> = (0..361)
            .map(|i| {
                let c = g.bearing(i).cos();
                if c > 0.4 {
                    rho / c + offset * (i % 2) as f32 + 2.0 * noise.gauss() as f32
                } else {
                    f32::NAN
                }
            })
            .collect();
        prop_assert_eq!(detected(g, &r), 2);
    }
}
