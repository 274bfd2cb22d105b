//! The `micromath` build (`--no-default-features --features micromath`: atan2, sin and cos
//! from micromath's fast approximations) against exact ray casting, with the error budget the
//! approximations need. The rest of the suite asserts the exact-maths tolerances of the
//! default build and is not meant to pass here (docs/TESTING.md). Only compiled with the
//! feature: `cargo test -p pfe-core --no-default-features --features micromath --test micromath`
//! (a step of `cargo xtask test`).
#![cfg(feature = "micromath")]
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

mod common;

use common::{runs, scan, Prim};
use pfe_core::{Config, Extractor, Feature, Scan, ScanGeometry};
use std::f64::consts::PI;

/// Error budget of micromath's approximations as seen in features: positions (sin/cos of the
/// bearings) within 10⁻² of the range (measured 5·10⁻⁴ for walls' ρ, 4.6·10⁻³ of its distance
/// for the small pillar's fit); a line's angle comes from
/// micromath's atan2, whose error reaches several mrad (measured 6.9 mrad on the oblique
/// wall), so 10 mrad. The default build's α is exact to 10⁻⁴ rad (tests/analytic.rs).
const REL: f64 = 1e-2;
const ANGLE: f64 = 1e-2;

#[test]
fn micromath_extraction_is_within_its_error_budget() {
    let g = ScanGeometry::LMS200_180_050;
    let scenes: [(&str, Vec<Prim>); 3] = [
        ("wall", vec![Prim::Seg(2000.0, -3000.0, 2000.0, 3000.0)]),
        ("oblique", vec![Prim::Seg(500.0, -4000.0, 4000.0, 2500.0)]),
        (
            "pillar",
            vec![
                Prim::Seg(3000.0, -3000.0, 3000.0, 3000.0),
                Prim::Circle(1500.0, 200.0, 150.0),
            ],
        ),
    ];
    let (mut worst_rel, mut worst_angle) = (0.0f64, 0.0f64);
    for (name, prims) in &scenes {
        let (ranges, hits) = scan(prims, -PI / 2.0, PI / 360.0, 361, 8000.0);
        let truth = runs(&hits, 4);
        let mut ex = Extractor::<361, 32>::new();
        ex.extract(&Scan::from_mm(g, &ranges), &Config::default())
            .unwrap();
        let feats = ex.features();
        assert_eq!(feats.len(), truth.len(), "{name}: {feats:#?}");
        for (f, &(a, b, p)) in feats.iter().zip(&truth) {
            assert!(
                f.first().abs_diff(a) <= 1 && f.last().abs_diff(b) <= 1,
                "{name}: {f:?} vs beams {a}..={b}"
            );
            match (f, prims[p]) {
                (Feature::Line(l), Prim::Seg(x0, y0, x1, y1)) => {
                    let (ex_, ey) = (x1 - x0, y1 - y0);
                    let len = ex_.hypot(ey);
                    let (nx, ny) = (ey / len, -ex_ / len);
                    let rho = (x0 * nx + y0 * ny).abs();
                    let alpha = if x0 * nx + y0 * ny < 0.0 {
                        (-ny).atan2(-nx)
                    } else {
                        ny.atan2(nx)
                    };
                    let da = (f64::from(l.alpha) - alpha + PI).rem_euclid(2.0 * PI) - PI;
                    let dr = (f64::from(l.rho) - rho).abs() / rho;
                    worst_angle = worst_angle.max(da.abs());
                    worst_rel = worst_rel.max(dr);
                    assert!(
                        da.abs() < ANGLE && dr < REL,
                        "{name}: {l:?} vs ({alpha}, {rho})"
                    );
                }
                (Feature::Circle(c), Prim::Circle(cx, cy, r)) => {
                    let d = (f64::from(c.center.x) - cx).hypot(f64::from(c.center.y) - cy);
                    let dr = (f64::from(c.radius) - r).abs();
                    let dist = cx.hypot(cy);
                    worst_rel = worst_rel.max(d / dist).max(dr / dist);
                    assert!(d < REL * dist && dr < REL * dist, "{name}: {c:?}");
                }
                (f, p) => panic!("{name}: {f:?} typed wrongly for {p:?}"),
            }
        }
    }
    eprintln!("micromath: worst relative error {worst_rel:.2e}, worst angle {worst_angle:.2e} rad");
}
