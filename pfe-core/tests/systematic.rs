//! The beam-to-beam systematic range error (`Config::sigma_sys`): what it adds to a line's and
//! a circle's covariance, against the model written out here in f64 — a line's offset σ_sys
//! along its normal and a tilt about its middle of variance 2σ_sys²/L², whose effect on ρ is
//! found by rotating the line numerically; a circle centre's σ_sys² along the beam to it.
//! A scan's rounding (`Scan::quantum`) adds the part neighbouring beams share, q²/12 ·
//! exp(−2π²σ_r²/q²), to σ_sys², written out here in f64 too.
//! Truth is the analytic ray casting of `common`.
#![allow(
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::needless_range_loop
)]

mod common;

use common::{scan, Noise, Prim};
use pfe_core::{Config, Extractor, Feature, Motion, Scan, ScanGeometry};

const SYS: f64 = 5.0;

/// A wall at an angle and a pillar of radius 150 mm.
fn features(config: Config) -> Vec<Feature> {
    features_rounded(config, 0.0)
}

/// The same, the scan declared on a grid of `quantum` mm.
fn features_rounded(config: Config, quantum: f32) -> Vec<Feature> {
    let g = ScanGeometry::LMS200_180_050;
    let prims = [
        Prim::Seg(2500.0, -3000.0, 4000.0, 2000.0),
        Prim::Circle(1500.0, 800.0, 150.0),
    ];
    let (exact, _) = scan(
        &prims,
        f64::from(g.start_angle),
        f64::from(g.angle_step),
        361,
        f64::from(g.r_max),
    );
    let mut noise = Noise::new(11);
    let ranges: Vec<f32> = exact
        .iter()
        .map(|&r| (f64::from(r) + 5.0 * noise.gauss()) as f32)
        .collect();
    let mut ex = Extractor::<361, 32>::new();
    let scan = Scan::from_mm(g, &ranges).with_quantum(quantum);
    ex.extract(&scan, &config).unwrap();
    ex.features().to_vec()
}

#[test]
fn the_systematic_error_adds_its_share_to_every_feature() {
    let plain = features(Config::default());
    let sys = features(Config::default().with_sigma_sys(SYS as f32));
    assert_added(&plain, &sys, SYS * SYS);
}

#[test]
fn a_scans_rounding_adds_the_part_its_beams_share() {
    // σ_r = 5 mm on a 50 mm grid: e^(−2π²·25/2500) = 0.821 of 2500/12 is shared; with
    // σ_sys = 5 mm the two add as variances.
    let config = Config::default().with_sigma_r(5.0);
    let shared = 2500.0 / 12.0 * (-2.0 * std::f64::consts::PI.powi(2) * 25.0 / 2500.0).exp();
    let plain = features(config);
    assert_added(&plain, &features_rounded(config, 50.0), shared);
    let sys = config.with_sigma_sys(SYS as f32);
    assert_added(&plain, &features_rounded(sys, 50.0), shared + SYS * SYS);
    // On a 10 mm grid, noise of 5 mm leaves 0.7 % of its 8.3 mm² shared.
    let ten = 100.0 / 12.0 * (-2.0 * std::f64::consts::PI.powi(2) * 25.0 / 100.0).exp();
    assert_added(&plain, &features_rounded(sys, 10.0), ten + SYS * SYS);
    // Noise as large as the grid leaves e^(−2π²) = 3·10⁻⁹ of it: below f32's resolution of
    // the covariances.
    let loud = Config::default().with_sigma_r(50.0);
    for (a, b) in features(loud).iter().zip(&features_rounded(loud, 50.0)) {
        let (Feature::Line(a), Feature::Line(b)) = (a, b) else {
            // A small object of the noisy scene: the same in both.
            assert!(a.is_object() && a == b, "{a:?} vs {b:?}");
            continue;
        };
        assert_eq!((a.alpha, a.rho, a.var_alpha), (b.alpha, b.rho, b.var_alpha));
        assert!(
            (a.var_rho - b.var_rho).abs() <= 1e-6 * a.var_rho,
            "{a:?} vs {b:?}"
        );
    }
    // Nor does a grid that is no number.
    for q in [f32::NAN, -50.0, f32::INFINITY] {
        assert_eq!(features(config), features_rounded(config, q), "{q}");
    }
}

#[test]
fn without_scrutiny_a_scans_rounding_changes_nothing() {
    for base in [Config::paper(), Config::default().with_scrutiny(false)] {
        assert_eq!(features(base), features_rounded(base, 50.0));
    }
}

/// `sys` has the features of `plain` with `s2` (mm²) of systematic variance added.
fn assert_added(plain: &[Feature], sys: &[Feature], s2: f64) {
    assert_eq!(plain.len(), sys.len());
    let (mut lines, mut circles) = (0, 0);
    for (a, b) in plain.iter().zip(sys) {
        match (a, b) {
            (Feature::Line(a), Feature::Line(b)) => {
                assert_eq!(
                    (a.alpha, a.rho, a.start, a.end),
                    (b.alpha, b.rho, b.start, b.end)
                );
                let (alpha, rho) = (f64::from(a.alpha), f64::from(a.rho));
                let (s, e) = (a.start, a.end);
                let len2 = f64::from(e.x - s.x).powi(2) + f64::from(e.y - s.y).powi(2);
                let tilt = 2.0 * s2 / len2;
                // dρ/dδ of the line turned by δ about its middle M, numerically: the turned
                // line through M has ρ(δ) = M · n(α + δ).
                let m = (0.5 * f64::from(s.x + e.x), 0.5 * f64::from(s.y + e.y));
                let rho_at = |d: f64| m.0 * (alpha + d).cos() + m.1 * (alpha + d).sin();
                assert!((rho_at(0.0) - rho).abs() < 0.5, "M on the line");
                let h = 1e-6;
                let along = (rho_at(h) - rho_at(-h)) / (2.0 * h);
                let want = [tilt, tilt * along, s2 + tilt * along * along];
                let got = [
                    f64::from(b.var_alpha - a.var_alpha),
                    f64::from(b.cov_alpha_rho - a.cov_alpha_rho),
                    f64::from(b.var_rho - a.var_rho),
                ];
                for (w, g) in want.iter().zip(got) {
                    assert!(
                        (g - w).abs() <= 1e-3 * w.abs() + 1e-9,
                        "{got:?} vs {want:?}"
                    );
                }
                lines += 1;
            }
            (Feature::Circle(a), Feature::Circle(b)) => {
                assert_eq!((a.center, a.radius), (b.center, b.radius));
                let (cx, cy) = (f64::from(a.center.x), f64::from(a.center.y));
                let d = cx.hypot(cy);
                let u = (cx / d, cy / d);
                let want = [
                    [s2 * u.0 * u.0, s2 * u.0 * u.1],
                    [s2 * u.0 * u.1, s2 * u.1 * u.1],
                ];
                for r in 0..2 {
                    for c in 0..2 {
                        let g = f64::from(b.cov[r][c] - a.cov[r][c]);
                        assert!((g - want[r][c]).abs() < 0.01 * s2, "{r}{c}: {g}");
                    }
                }
                // The radius's variance is untouched.
                assert_eq!(a.cov[2][2], b.cov[2][2]);
                circles += 1;
            }
            _ => panic!("{a:?} vs {b:?}"),
        }
    }
    assert!(
        lines >= 1 && circles == 1,
        "{lines} lines, {circles} circles"
    );
}

#[test]
fn only_a_usable_systematic_error_is_accepted() {
    assert!(Config::default().with_sigma_sys(0.0).is_valid());
    assert!(Config::default().with_sigma_sys(15.0).is_valid());
    assert!(!Config::default().with_sigma_sys(-1.0).is_valid());
    assert!(!Config::default().with_sigma_sys(f32::NAN).is_valid());
    assert!(!Config::default().with_sigma_sys(f32::INFINITY).is_valid());
    assert_eq!(Config::default().sigma_sys, 0.0);
    assert_eq!(Config::paper().sigma_sys, 0.0);
}

#[test]
fn without_scrutiny_the_covariances_stay_as_they_were() {
    for base in [Config::paper(), Config::default().with_scrutiny(false)] {
        assert_eq!(features(base), features(base.with_sigma_sys(SYS as f32)));
    }
}

#[test]
fn a_moving_scanners_circle_gets_it_along_the_beam_from_where_it_was() {
    // 2 m/s and 1 ms a beam: the scanner is ~0.25 m along when it sees the pillar.
    let g = ScanGeometry::LMS200_180_050;
    let motion = Motion::uniform(2000.0, 0.0, 1e-3);
    let (exact, _) = scan(
        &[Prim::Circle(1500.0, 800.0, 150.0)],
        f64::from(g.start_angle),
        f64::from(g.angle_step),
        361,
        f64::from(g.r_max),
    );
    let mut ex = Extractor::<361, 32>::new();
    let mut cov = Vec::new();
    for sys in [0.0, SYS as f32] {
        let scan = Scan::from_mm(g, &exact).with_motion(motion);
        ex.extract(&scan, &Config::default().with_sigma_sys(sys))
            .unwrap();
        let [Feature::Circle(c)] = ex.features() else {
            panic!("{:?}", ex.features())
        };
        cov.push((*c, c.cov));
    }
    let (c, _) = cov[0];
    let o = motion.pose((c.first as usize + c.last as usize) / 2).origin;
    assert!(o.x > 200.0, "{o:?}");
    let (dx, dy) = (f64::from(c.center.x - o.x), f64::from(c.center.y - o.y));
    let d = dx.hypot(dy);
    let u = (dx / d, dy / d);
    let want = [[u.0 * u.0, u.0 * u.1], [u.0 * u.1, u.1 * u.1]];
    for r in 0..2 {
        for k in 0..2 {
            let got = f64::from(cov[1].1[r][k] - cov[0].1[r][k]);
            let w = SYS * SYS * want[r][k];
            assert!((got - w).abs() < 0.01 * SYS * SYS, "{r}{k}: {got} vs {w}");
        }
    }
}
