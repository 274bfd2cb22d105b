//! Unit tests of the scan plot.

use super::*;

#[test]
fn nice_steps() {
    assert_eq!(tick_step(10_000.0, 8.0), 1000.0);
    assert_eq!(tick_step(3_000.0, 8.0), 500.0);
    assert_eq!(tick_step(1_600.0, 8.0), 200.0);
}

#[test]
fn labels() {
    assert_eq!(tick_label(-1e-9, 1000.0, true), "0");
    assert_eq!(tick_label(-0.4, 200.0, false), "0");
    assert_eq!(tick_label(2500.0, 500.0, true), "2.5");
    assert_eq!(tick_label(-3000.0, 1000.0, true), "-3");
}

#[test]
fn arcs_take_the_short_way() {
    let p = arc_points(0.0, 0.0, 1.0, 3.0, -3.0);
    // From 3 rad to −3 rad the short way passes through π, not 0.
    assert!(p.iter().all(|&(x, _)| x < -0.9));
}

#[test]
fn ellipse_axes_match_an_analytic_covariance() {
    // C = R(θ) diag(σ1², σ2²) R(θ)ᵀ with σ1 = 5, σ2 = 2, θ = 30°.
    let (s1, s2, th) = (5.0f64, 2.0f64, 30f64.to_radians());
    let (c, s) = (th.cos(), th.sin());
    let cov = [
        [
            c * c * s1 * s1 + s * s * s2 * s2,
            c * s * (s1 * s1 - s2 * s2),
        ],
        [
            c * s * (s1 * s1 - s2 * s2),
            s * s * s1 * s1 + c * c * s2 * s2,
        ],
    ];
    let (a, b, angle) = super::ellipse(cov, 3.0);
    assert!((a - 15.0).abs() < 1e-9, "{a}");
    assert!((b - 6.0).abs() < 1e-9, "{b}");
    assert!((angle - th).abs() < 1e-9, "{angle}");
    // Isotropic: a circle.
    let (a, b, _) = super::ellipse([[4.0, 0.0], [0.0, 4.0]], 1.0);
    assert!((a - 2.0).abs() < 1e-12 && (b - 2.0).abs() < 1e-12);
}

#[test]
fn line_point_cov_is_the_propagated_covariance() {
    // α = 0, point at t along the line x = ρ: p = (ρ, t) rotated; analytic J C Jᵀ.
    let (rho, t, va, vr, car) = (2000.0, 300.0, 1e-6, 4.0, 1e-4);
    let c = super::line_point_cov(0.0, rho, t, [[va, car], [car, vr]]);
    // ∂p/∂α = (−t, ρ), ∂p/∂ρ = (1, 0).
    let want = [
        [t * t * va - 2.0 * t * car + vr, -t * rho * va + rho * car],
        [-t * rho * va + rho * car, rho * rho * va],
    ];
    for i in 0..2 {
        for j in 0..2 {
            assert!((c[i][j] - want[i][j]).abs() < 1e-9, "{c:?} vs {want:?}");
        }
    }
    // Against finite differences at another angle.
    let (al, rho, t) = (0.7f64, 1500.0f64, -250.0f64);
    let p = |a: f64, r: f64| (r * a.cos() - t * a.sin(), r * a.sin() + t * a.cos());
    let h = 1e-6;
    let ja = (
        (p(al + h, rho).0 - p(al - h, rho).0) / (2.0 * h),
        (p(al + h, rho).1 - p(al - h, rho).1) / (2.0 * h),
    );
    let jr = (
        (p(al, rho + h).0 - p(al, rho - h).0) / (2.0 * h),
        (p(al, rho + h).1 - p(al, rho - h).1) / (2.0 * h),
    );
    let c = super::line_point_cov(al, rho, t, [[va, car], [car, vr]]);
    let xx = ja.0 * ja.0 * va + 2.0 * ja.0 * jr.0 * car + jr.0 * jr.0 * vr;
    let xy = ja.0 * ja.1 * va + (ja.0 * jr.1 + ja.1 * jr.0) * car + jr.0 * jr.1 * vr;
    assert!(
        (c[0][0] - xx).abs() < 1e-5 && (c[0][1] - xy).abs() < 1e-5,
        "{c:?}"
    );
}

#[test]
fn the_plot_draws_uncertainty_and_explains_bare_marks() {
    use pfe_eval::methods::{Method, Pfe};
    use pfe_formats::Record;
    // A wall x = 2000 from −30° to +30°, then three isolated points (a segment too short).
    let mut ranges: Vec<f32> = (0..61)
        .map(|i| 2000.0 / (f64::from(i - 30).to_radians().cos() as f32))
        .collect();
    ranges.extend([f32::NAN, f32::NAN, 900.0, f32::NAN, f32::NAN]);
    let geometry = pfe_core::ScanGeometry::new(-30f32.to_radians(), 1f32.to_radians(), 8000.0);
    let record = Record {
        id: 0,
        geometry,
        ranges_mm: ranges,
        time: None,
        pose: None,
        sweeps: None,
    };
    let mut m = Pfe::new("pfe", pfe_core::Config::default().with_sigma_r(5.0));
    let ex = m.extract(&record.geometry, &record.ranges_mm);
    assert_eq!(ex.features.len(), 1, "{:?}", ex.features);
    let svg = super::svg(&record, &ex, "t");
    assert_eq!(
        svg.matches("<ellipse").count(),
        2 + 1,
        "two end points + legend icon"
    );
    assert!(svg.contains("ellipses: 3σ × "), "{svg}");
    assert!(svg.contains("no feature (1): segment too short"), "{svg}");
}

/// The short line of hokuyo-cylinders scan 100, beams 370–374: 120 mm long at 4.7 m, σ_α 0.12
/// rad, σ_ρ 92 mm (its σ across the line is 7.7 mm at its middle).
fn short_far_line() -> pfe_core::LineFeature {
    let (va, tc, vmin) = (0.01453f32, 764.5f32, 60.0f32);
    pfe_core::LineFeature::new(
        370,
        374,
        5,
        -0.233_848_2,
        4730.634,
        va,
        vmin + tc * tc * va,
        tc * va,
        pfe_core::Point::new(4765.386, -409.7695),
        pfe_core::Point::new(4792.8584, -294.43906),
    )
}

#[test]
fn a_short_lines_band_stays_on_its_extent() {
    let l = short_far_line();
    let (n, d, t0, t1) = super::ellipses::line_frame(&l);
    let (lo, hi) = (t0.min(t1), t0.max(t1));
    let k = 3.0;
    let widest = k * super::line_sigma_at(&l, t0).max(super::line_sigma_at(&l, t1));
    let band = super::ellipses::line_band(&l, k);
    assert_eq!(band.len(), 2 * 17);
    for &(x, y) in &band {
        let (t, off) = (x * d.0 + y * d.1, x * n.0 + y * n.1 - f64::from(l.rho));
        assert!(t >= lo - 1e-6 && t <= hi + 1e-6, "t {t} outside {lo}..{hi}");
        assert!(off.abs() <= widest + 1e-6, "offset {off} beyond {widest}");
    }
    // Narrow where the points are, not the foot-of-normal wedge (3 ρ σ_α = 1.7 m).
    assert!(widest < 60.0, "{widest}");
    // The end points: across, the band's width there; along, the point's own σ (10 mm) at
    // most.
    for p in [l.start, l.end] {
        let (a, b, _) = super::ellipse(super::end_point_cov(&l, &p, 10.0), k);
        assert!(
            a <= k * 10f64.hypot(super::line_sigma_at(
                &l,
                f64::from(p.x) * d.0 + f64::from(p.y) * d.1
            )) + 1e-9
        );
        assert!(b > 0.0 && a < 60.0, "{a} {b}");
    }
}

#[test]
fn objects_veils_and_bands_are_drawn_and_counted() {
    use pfe_core::{Feature, ObjectFeature, Point};
    use pfe_eval::methods::Extraction;
    use pfe_formats::Record;
    let g = pfe_core::ScanGeometry::new(-30f32.to_radians(), 1f32.to_radians(), 8000.0);
    let record = Record {
        id: 0,
        geometry: g,
        ranges_mm: vec![4800.0; 61],
        time: None,
        pose: None,
        sweeps: None,
    };
    let ex = Extraction {
        marks: vec![0, 60],
        features: vec![
            Feature::Line(short_far_line()),
            Feature::Object(ObjectFeature::new(
                10,
                13,
                4,
                Point::new(3000.0, -800.0),
                [[400.0, 0.0], [0.0, 100.0]],
                120.0,
            )),
        ],
    };
    let opts = super::Options {
        veils: vec![20, 21, 22],
        sigma_point_mm: 10.0,
        ..Default::default()
    };
    let svg = super::svg_with(&record, &ex, "t", &opts);
    assert_eq!(svg.matches(r#"<polygon class="band""#).count(), 1);
    assert!(svg.contains("small objects (1): extent"), "{svg}");
    assert_eq!(svg.matches(r#"<circle class="object""#).count(), 1);
    assert!(svg.contains("veils (3): mixed pixels"), "{svg}");
    // No uncertainty drawn wider than a tenth of the plot (the old end-point ellipses of
    // this line were 1.7 m across a 5 m scene).
    for part in svg.split("<ellipse ").skip(1) {
        let rx: f64 = part
            .split("rx=\"")
            .nth(1)
            .and_then(|r| r.split('"').next())
            .and_then(|r| r.parse().ok())
            .unwrap();
        assert!(rx < 82.0, "an ellipse {rx} px wide");
    }
}
