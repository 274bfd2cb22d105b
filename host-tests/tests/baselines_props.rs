//! Property tests: the baselines never panic and always return well-formed output.

use pfe_core::ScanGeometry;
use pfe_eval::methods::baselines::{Abd, Acf, SplitMerge};
use pfe_eval::methods::{Extraction, Method};
use proptest::prelude::*;

/// Ranges mixing ordinary values with every kind of invalid reading.
fn reading() -> impl Strategy<Value = f32> {
    prop_oneof![
        6 => 1.0f32..9000.0,
        1 => Just(f32::NAN),
        1 => Just(0.0f32),
        1 => Just(f32::INFINITY),
        1 => Just(f32::NEG_INFINITY),
        1 => Just(-5.0f32),
        1 => Just(f32::MAX),
        1 => Just(f32::MIN_POSITIVE),
    ]
}

/// Smooth-ish ranges (random walk) so that segments, corners and arcs actually occur.
fn walk() -> impl Strategy<Value = Vec<f32>> {
    (
        500.0f32..7000.0,
        prop::collection::vec(-60.0f32..60.0, 0..400),
    )
        .prop_map(|(start, steps)| {
            steps
                .iter()
                .scan(start, |r, d| {
                    *r = (*r + d).clamp(1.0, 9000.0);
                    Some(*r)
                })
                .collect()
        })
}

fn check(e: &Extraction, n: usize) -> Result<(), TestCaseError> {
    for f in &e.features {
        prop_assert!(f.is_well_formed(), "{f:?}");
        prop_assert!(f.first() <= f.last() && f.last() < n, "{f:?} n={n}");
        prop_assert!(f.last() + 1 - f.first() >= 4, "{f:?}");
    }
    for w in e.features.windows(2) {
        prop_assert!(w[0].last() < w[1].first(), "overlap {w:?}");
    }
    for w in e.marks.windows(2) {
        prop_assert!(w[0] < w[1]);
    }
    prop_assert!(e.marks.iter().all(|m| *m < n));
    // Every feature's ends are marks.
    for f in &e.features {
        prop_assert!(e.marks.contains(&f.first()) && e.marks.contains(&f.last()));
    }
    Ok(())
}

fn geometry() -> impl Strategy<Value = ScanGeometry> {
    prop_oneof![
        3 => Just(ScanGeometry::LMS200_180_050),
        1 => Just(ScanGeometry::lms200(180.0, 1.0)),
        1 => Just(ScanGeometry::lms200(100.0, 0.25)),
        1 => (-4.0f32..4.0, -0.2f32..0.2, 1.0f32..90000.0).prop_map(|(s, d, r)| ScanGeometry::new(s, d, r)),
        1 => Just(ScanGeometry::new(f32::NAN, 0.0, f32::INFINITY)),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn arbitrary_ranges_never_panic(g in geometry(), r in prop::collection::vec(reading(), 0..400)) {
        for mut m in [Box::new(SplitMerge::new()) as Box<dyn Method>, Box::new(Acf::new())] {
            let e = m.extract(&g, &r);
            check(&e, r.len())?;
        }
    }

    #[test]
    fn random_walk_scans_are_well_formed(g in geometry(), r in walk()) {
        for mut m in [Box::new(SplitMerge::new()) as Box<dyn Method>, Box::new(Acf::new())] {
            let e = m.extract(&g, &r);
            check(&e, r.len())?;
        }
    }

    #[test]
    fn odd_parameters_never_panic(r in walk(), sigma in prop_oneof![Just(f32::NAN), Just(0.0f32), Just(-1.0f32), 0.1f32..100.0], lambda in -1.0f32..2.0) {
        let g = ScanGeometry::LMS200_180_050;
        let mut sm = SplitMerge::new().with_sigma_r(sigma);
        sm.abd.lambda = lambda;
        let mut acf = Acf::new().with_sigma_r(sigma);
        acf.abd.lambda = lambda;
        acf.k_min = 0;
        check(&sm.extract(&g, &r), r.len())?;
        check(&acf.extract(&g, &r), r.len())?;
    }
}

#[test]
fn degenerate_inputs() {
    let g = ScanGeometry::LMS200_180_050;
    let cases: Vec<Vec<f32>> = vec![
        vec![],
        vec![1000.0],
        vec![f32::NAN; 361],
        vec![0.0; 361],
        vec![f32::INFINITY; 361],
        vec![1000.0, 1000.0],
        vec![1000.0; 3],
    ];
    for r in &cases {
        for mut m in [
            Box::new(SplitMerge::new()) as Box<dyn Method>,
            Box::new(Acf::new()),
        ] {
            let e = m.extract(&g, r);
            assert!(e.features.is_empty(), "{}: {r:?}", m.name());
            assert!(e.marks.iter().all(|i| *i < r.len()));
        }
    }
}

#[test]
fn abd_threshold_follows_borges_aldon() {
    let abd = Abd::default();
    let step = 0.5f32.to_radians();
    // D_max = r sin Δφ / sin(λ − Δφ) + 3σ_r, λ = 10°, σ_r = 5 mm.
    for r in [500.0f32, 2000.0, 8000.0] {
        let want = r * step.sin() / (10f32.to_radians() - step).sin() + 15.0;
        assert!((abd.d_max(r, step) - want).abs() < 1e-3 * want);
    }
    // Two points on a wall at 2 m seen head on are ~17 mm apart: no break; 200 mm: a break.
    let g = ScanGeometry::LMS200_180_050;
    let pts = pfe_eval::methods::baselines::scan_points(&g, &[2000.0, 2000.0, 2200.0, 2200.0]);
    assert_eq!(abd.segments(&g, &pts), vec![(0, 1), (2, 3)]);
}
