//! The build without the `scrutiny` feature (the firmware's: `cargo test -p pfe-core
//! --no-default-features --features libm --test lean`, a step of `cargo xtask test`): a
//! configuration with `Config::scrutiny` on is refused rather than run without its checks, and
//! the board's configuration runs. In the default build this file has no tests.
#![cfg(not(feature = "scrutiny"))]
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

use pfe_core::{Config, ExtractError, Extractor, Feature, Scan, ScanGeometry};

/// A wall 2 m ahead over ±57°.
fn wall() -> Vec<f32> {
    let g = ScanGeometry::LMS200_180_050;
    (0..361)
        .map(|i| {
            let b = g.bearing(i);
            if b.abs() < 1.0 {
                2000.0 / b.cos()
            } else {
                f32::NAN
            }
        })
        .collect()
}

#[test]
fn scrutiny_is_refused_and_the_boards_configuration_runs() {
    let ranges = wall();
    let scan = Scan::from_mm(ScanGeometry::LMS200_180_050, &ranges);
    let mut ex = Extractor::<361, 32>::new();
    assert!(!Config::default().is_valid());
    assert_eq!(
        ex.extract(&scan, &Config::default()),
        Err(ExtractError::InvalidConfig)
    );
    for config in [Config::default().with_scrutiny(false), Config::paper()] {
        assert!(config.is_valid());
        ex.extract(&scan, &config).unwrap();
        let [Feature::Line(l)] = ex.features() else {
            panic!("{:?}", ex.features());
        };
        assert!(
            (l.rho - 2000.0).abs() < 0.5 && l.alpha.abs() < 1e-3,
            "{l:?}"
        );
    }
}
