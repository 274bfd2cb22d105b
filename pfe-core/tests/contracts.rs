//! Small public contracts, each against closed-form or counted truth: the scanner pose of a
//! constant-velocity motion (the exact arc `x = v/ω sin ωt`, `y = v/ω (1 − cos ωt)`, in f64), a
//! de-skewed point, `Point::norm`, which configurations are valid, a range corrected to zero,
//! and the statistics of a scan whose interleaved sweeps were moved and extracted again. (How
//! they were found: docs/TESTING.md, "Mutation testing".)
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

mod common;

use common::{cast, scan, Noise, Prim};
use pfe_core::predict::WindowLine;
use pfe_core::{
    BeamTiming, Config, Extractor, Feature, Motion, NoiseModel, Point, RangeCorrection, Scan,
    ScanGeometry, Threshold, Typing,
};

/// The exact pose in f64: heading ωt and the arc of radius v/ω (a straight line for ω = 0).
fn pose64(v: f64, omega: f64, t: f64) -> (f64, f64, f64) {
    let th = omega * t;
    if omega == 0.0 {
        (v * t, 0.0, 0.0)
    } else {
        (v / omega * th.sin(), v / omega * (1.0 - th.cos()), th)
    }
}

#[test]
fn pose_is_the_exact_arc_of_a_constant_velocity_motion() {
    // Headings from 0 through the series range (|ωt| < 10⁻³) to well beyond it, both turn
    // directions, forwards and backwards.
    for &(v, omega) in &[
        (1000.0f32, 0.0f32),
        (1000.0, 1e-4),
        (-700.0, 4e-4),
        (1000.0, -9e-4),
        (2000.0, 9.9e-4),
        (500.0, 1.5e-3),
        (800.0, 0.45),
        (-300.0, -2.0),
        (1200.0, 3.0),
    ] {
        for t in [0.0f32, 0.3, 1.0] {
            let p = Motion::uniform(v, omega, 0.001).pose_at(t);
            let (x, y, th) = pose64(f64::from(v), f64::from(omega), f64::from(t));
            // f32 rounding: relative 2.5 × 10⁻⁷ of the distance travelled, and where the exact
            // branch runs (|ωt| ≥ 10⁻³) the cancellation in 1 − cos of ~10⁻⁷ v/ω.
            let travel = f64::from(v * t).abs();
            let cancel = if (omega * t).abs() >= 1e-3 {
                2e-7 * f64::from(v / omega).abs()
            } else {
                0.0
            };
            // (2.5 × 10⁻⁷: the series' −θ²/6 term is 1.6 × 10⁻⁷ of x near |ωt| = 10⁻³, and
            // a +θ²/6 instead is 3.3 × 10⁻⁷ off.)
            let tol = 2.5e-7 * travel + 1e-6;
            let what = format!("v {v} ω {omega} t {t}: {p:?} vs ({x}, {y}, {th})");
            assert!((f64::from(p.origin.x) - x).abs() <= tol, "x: {what}");
            // y is second order in ωt: relative to itself.
            assert!(
                (f64::from(p.origin.y) - y).abs() <= 1e-5 * y.abs() + 1e-6 + cancel,
                "y: {what}"
            );
            assert!(
                (f64::from(p.theta) - th).abs() <= 1e-6 * th.abs() + 1e-9,
                "θ: {what}"
            );
        }
    }
}

#[test]
fn pose_of_a_beam_is_the_pose_at_its_time_and_deskew_moves_the_point_with_it() {
    // 0.5° LMS2xx: beam i at (i mod 2)·turn + (i div 2)·turn/360.
    let m = Motion {
        v: 600.0,
        omega: 0.45,
        timing: BeamTiming::lms2xx(0.5),
    };
    let turn = 1.0 / 75.0;
    for i in [0usize, 1, 2, 7, 180, 361] {
        let t = (i % 2) as f64 * turn + (i / 2) as f64 * turn / 360.0;
        let (x, y, th) = pose64(600.0, 0.45, t);
        let p = m.pose(i);
        assert!(
            (f64::from(p.origin.x) - x).abs() < 1e-3
                && (f64::from(p.origin.y) - y).abs() < 1e-3
                && (f64::from(p.theta) - th).abs() < 1e-6,
            "beam {i}: {p:?} vs ({x}, {y}, {th})"
        );
        // The reading (range, bearing) of beam i: rotated by the heading, from the origin.
        let (range, bearing) = (3000.0f32, -0.7f32 + 0.01 * i as f32);
        let (point, origin) = m.deskew(i, range, bearing);
        let b = f64::from(bearing) + th;
        let want = (x + 3000.0 * b.cos(), y + 3000.0 * b.sin());
        assert!(
            (f64::from(point.x) - want.0).abs() < 2e-3
                && (f64::from(point.y) - want.1).abs() < 2e-3,
            "beam {i}: {point:?} vs {want:?}"
        );
        assert_eq!(origin, p.origin);
    }
}

#[test]
fn norm_is_the_distance_from_the_origin() {
    for (x, y) in [(3.0f32, 4.0f32), (-5.0, 12.0), (0.0, -7.5), (1e-3, 0.0)] {
        let want = f64::from(x).hypot(f64::from(y));
        let got = f64::from(Point::new(x, y).norm());
        assert!((got - want).abs() <= 1e-6 * want, "({x}, {y}): {got}");
    }
    assert_eq!(Point::new(0.0, 0.0).norm(), 0.0);
}

/// The default configuration with its noise model changed by `f`.
fn with_model(f: impl Fn(&mut NoiseModel)) -> Config {
    let mut c = Config::default();
    let Threshold::Noise(mut m) = c.threshold else {
        panic!("the default threshold is the noise model")
    };
    f(&mut m);
    c.threshold = Threshold::Noise(m);
    c
}

#[test]
fn a_configuration_is_valid_only_when_every_parameter_is() {
    assert!(Config::default().is_valid() && Config::paper().is_valid());
    // Each noise-model parameter alone out of its range makes the configuration invalid.
    let bad: [(&str, Config); 9] = [
        ("k NaN", with_model(|m| m.k = f32::NAN)),
        ("k ≤ 0", with_model(|m| m.k = 0.0)),
        ("k_locate ∞", with_model(|m| m.k_locate = f32::INFINITY)),
        ("floor NaN", with_model(|m| m.floor = f32::NAN)),
        ("floor < 0", with_model(|m| m.floor = -1.0)),
        ("window < 2", with_model(|m| m.window = 1)),
        ("min_span NaN", with_model(|m| m.min_span = f32::NAN)),
        ("arc_chi2 ∞", with_model(|m| m.arc_chi2 = f32::INFINITY)),
        ("arc_max_radius 0", with_model(|m| m.arc_max_radius = 0.0)),
    ];
    for (what, c) in bad {
        assert!(!c.is_valid(), "{what}");
    }
    // The edges of the ranges are valid.
    assert!(with_model(|m| m.floor = 0.0).is_valid());
    assert!(with_model(|m| m.window = 2).is_valid());
    // The paper's threshold, the typing and the shared parameters.
    let mut c = Config::paper();
    c.threshold = Threshold::Paper {
        d0: 0.0,
        lambda: 2.0,
    };
    assert!(!c.is_valid());
    c.threshold = Threshold::Paper {
        d0: 50.0,
        lambda: f32::NAN,
    };
    assert!(!c.is_valid());
    let mut c = Config::paper();
    c.typing = Typing::MeanDistance { d_f: -1.0 };
    assert!(!c.is_valid());
    let mut c = Config::default();
    c.typing = Typing::CompareFits {
        chi2: 25.0,
        ratio: f32::NAN,
        max_radius: 2000.0,
    };
    assert!(!c.is_valid());
    assert!(!Config::default().with_sigma_r(0.0).is_valid());
    let mut c = Config::default();
    c.min_points = 1;
    assert!(!c.is_valid());
    // The zero edges that are out: λ of the paper's threshold, the typing's largest radius.
    let mut c = Config::paper();
    c.threshold = Threshold::Paper {
        d0: 50.0,
        lambda: 0.0,
    };
    assert!(!c.is_valid());
    let mut c = Config::default();
    c.typing = Typing::CompareFits {
        chi2: 25.0,
        ratio: 0.5,
        max_radius: 0.0,
    };
    assert!(!c.is_valid());
    // σ_sys: zero is valid, below or not finite is not.
    assert!(Config::default().with_sigma_sys(0.0).is_valid());
    assert!(!Config::default().with_sigma_sys(-0.1).is_valid());
    assert!(!Config::default().with_sigma_sys(f32::NAN).is_valid());
}

#[test]
fn a_reading_corrected_to_zero_range_is_dropped() {
    // The correction subtracts 100 mm: a reading of 100 mm is at the scanner, one of 60 mm
    // behind it; neither is a point. The rest of the wall stays.
    let g = ScanGeometry::LMS200_180_050;
    let mut ranges: Vec<f32> = (0..361)
        .map(|i| {
            let b = g.bearing(i);
            if b.abs() < 1.0 {
                100.0 + 3000.0 / b.cos()
            } else {
                f32::NAN
            }
        })
        .collect();
    let valid = ranges.iter().filter(|r| r.is_finite()).count();
    ranges[180] = 100.0;
    ranges[181] = 60.0;
    let corr = RangeCorrection {
        coeffs: [100.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        scale: 8000.0,
    };
    let mut ex = Extractor::<361, 8>::new();
    let stats = ex
        .extract(
            &Scan::from_mm(g, &ranges),
            &Config::default().with_correction(corr),
        )
        .unwrap();
    assert_eq!(stats.valid, valid - 2);
    assert!(!ex.points()[180].is_valid() && !ex.points()[181].is_valid());
    assert!(ex.points()[179].is_valid() && ex.points()[182].is_valid());
    // The rest lie on the wall x = 3 m, where their corrected ranges put them.
    for (i, p) in ex.points().iter().enumerate() {
        if p.is_valid() {
            let b = g.bearing(i);
            assert!(
                (p.x - 3000.0).abs() < 0.01 && (p.y - 3000.0 * b.tan()).abs() < 0.01,
                "beam {i}: {p:?}"
            );
        }
    }
}

#[test]
fn statistics_survive_the_alignment_of_interleaved_sweeps() {
    // A room 6 m × 5 m seen by an LMS200 at 0.5° (two sweeps), the odd sweep from 8 mm further
    // forward and turned 6 mrad: the sweeps are out of place, the extractor moves the odd one
    // before the fits. Its statistics still count every reading and valid point.
    let g = ScanGeometry::LMS200_180_050;
    let room = |ox: f64, oy: f64, th: f64| {
        let (s, c) = th.sin_cos();
        let to = |x: f64, y: f64| {
            let (dx, dy) = (x - ox, y - oy);
            (c * dx + s * dy, -s * dx + c * dy)
        };
        let corners = [
            to(-1500.0, -2000.0),
            to(4500.0, -2000.0),
            to(4500.0, 3000.0),
            to(-1500.0, 3000.0),
        ];
        (0..4)
            .map(|k| {
                let (a, b) = (corners[k], corners[(k + 1) % 4]);
                Prim::Seg(a.0, a.1, b.0, b.1)
            })
            .collect::<Vec<_>>()
    };
    let sweeps = [room(0.0, 0.0, 0.0), room(8.0, 0.0, 0.006)];
    let ranges: Vec<f32> = (0..361)
        .map(|i| match cast(&sweeps[i % 2], f64::from(g.bearing(i))) {
            // Beams past 7.9 m (none here) and one beam in ten missing.
            Some((t, _)) if t < 7900.0 && i % 10 != 3 => t as f32,
            _ => f32::NAN,
        })
        .collect();
    let valid = ranges.iter().filter(|r| r.is_finite()).count();
    // Without the check step every prediction is the walk's: the count is the marking passes'.
    let mut config = Config::default();
    config.check_step = false;
    let mut ex = Extractor::<361, 128>::new();
    let stats = ex
        .extract(&Scan::from_mm(g, &ranges).with_sweeps(2), &config)
        .unwrap();
    assert_eq!(stats.sweeps_aligned, 1, "{stats:?}");
    assert_eq!((stats.readings, stats.valid), (361, valid), "{stats:?}");
    // With scrutiny two sweeps are walked unmoved with the scan's σ (the same walk as the
    // readings taken as one sweep, whose σ counts the sweeps' offset: noise-free rooms, only
    // the offset scatters), then moved and walked again (and, when that walk leaves no fewer
    // marks, the unmoved points a third time): every walk's predictions are counted. The moved
    // points scatter no more than σ_r, so the fits keep it.
    let first = ex.extract(&Scan::from_mm(g, &ranges), &config).unwrap();
    assert!(
        stats.predictions > first.predictions + first.predictions / 2
            && stats.predictions < 3 * first.predictions + first.predictions / 2,
        "{stats:?}\nfirst {first:?}"
    );
    assert!(first.scan_sigma_um > 7_500, "{first:?}");
    assert_eq!(stats.scan_sigma_um, 0, "{stats:?}");
    assert_eq!(
        stats.features,
        stats.segments - stats.short_segments,
        "{stats:?}"
    );
}

/// The variance factor of a prediction in f64 from its definition,
/// `1 + (1/n + u²/S_uu) sin²ϕ̄ / sin²ϕ`: the window's principal axis, the beam from `origin`
/// through `target`, u the meeting point's position along the axis from the centroid, ϕ̄ the
/// incidence at the window's last point, ϕ the beam's.
fn var_factor64(window: &[(f64, f64)], origin: (f64, f64), target: (f64, f64)) -> f64 {
    let n = window.len() as f64;
    let cx = window.iter().map(|p| p.0).sum::<f64>() / n;
    let cy = window.iter().map(|p| p.1).sum::<f64>() / n;
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for p in window {
        sxx += (p.0 - cx).powi(2);
        syy += (p.1 - cy).powi(2);
        sxy += (p.0 - cx) * (p.1 - cy);
    }
    let th = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let (tx, ty) = (th.cos(), th.sin());
    let (nx, ny) = (-ty, tx);
    let (bx, by) = (target.0 - origin.0, target.1 - origin.1);
    let r = bx.hypot(by);
    let (dx, dy) = (bx / r, by / r);
    let dn = dx * nx + dy * ny;
    let t = ((cx - origin.0) * nx + (cy - origin.1) * ny) / dn;
    let u = (origin.0 + t * dx - cx) * tx + (origin.1 + t * dy - cy) * ty;
    let suu: f64 = window
        .iter()
        .map(|p| ((p.0 - cx) * tx + (p.1 - cy) * ty).powi(2))
        .sum();
    let last = window[window.len() - 1];
    let (lx, ly) = (last.0 - origin.0, last.1 - origin.1);
    let sin_last = (lx * nx + ly * ny).abs() / lx.hypot(ly);
    1.0 + (1.0 / n + u * u / suu) * sin_last.powi(2) / dn.powi(2)
}

#[test]
fn a_window_line_predicts_from_a_moved_scanner_as_from_the_origin() {
    // Windows of 3..=6 points on a wall, the scanner away from the origin (a de-skewed scan):
    // the variance factor is the definition's, from that scanner.
    let mut noise = Noise::new(61);
    for &(origin, x0, y0, ang) in &[
        ((400.0f64, -250.0f64), 2500.0f64, 300.0f64, 1.9f64),
        ((-600.0, 900.0), 1200.0, 2600.0, -0.3),
        ((1500.0, 1500.0), 3000.0, -1000.0, 2.4),
    ] {
        for n in 3..=6usize {
            let window: Vec<(f64, f64)> = (0..n)
                .map(|i| {
                    let (s, e) = (70.0 * i as f64, 3.0 * noise.gauss());
                    (
                        x0 + s * ang.cos() - e * ang.sin(),
                        y0 + s * ang.sin() + e * ang.cos(),
                    )
                })
                .collect();
            let s = 70.0 * n as f64;
            let target = (
                x0 + s * ang.cos() - 25.0 * ang.sin(),
                y0 + s * ang.sin() + 25.0 * ang.cos(),
            );
            let w32: Vec<Point> = window
                .iter()
                .map(|p| Point::new(p.0 as f32, p.1 as f32))
                .collect();
            let o32 = Point::new(origin.0 as f32, origin.1 as f32);
            let line = WindowLine::fit(&w32, o32).unwrap();
            let (bx, by) = (target.0 - origin.0, target.1 - origin.1);
            let p = line.predict(o32, bx as f32, by as f32, bx.hypot(by) as f32);
            let want = var_factor64(&window, origin, target);
            let got = f64::from(p.var_factor);
            assert!(
                (got - want).abs() <= 2e-3 * want,
                "origin {origin:?}, n {n}: var_factor {got} vs {want}"
            );
        }
    }
}

/// Stated over empirical (var_rho, cov_alpha_rho) of the line of a wall 2.5 m ahead, off-centre
/// (ρ and α correlated), range noise 9 mm told as 5 mm, over 400 scans.
fn stated_over_spread(config: &Config) -> [f64; 2] {
    let [_, rho, cov] = stated_over_spread_of(config, Prim::Seg(2500.0, -300.0, 2200.0, 1500.0));
    [rho, cov]
}

/// Stated over observed (α, ρ) variances and covariance of the one line fitted to `wall`
/// under range noise of 9 mm (400 scans), the configuration told 5 mm.
fn stated_over_spread_of(config: &Config, wall: Prim) -> [f64; 3] {
    let g = ScanGeometry::LMS200_180_050;
    let (start, step) = (f64::from(g.start_angle), f64::from(g.angle_step));
    let mut ex = Extractor::<361, 64>::new();
    let (exact, _) = scan(&[wall], start, step, 361, 8000.0);
    let mut noise = Noise::new(2025);
    let (mut fits, mut stated) = (Vec::new(), [0.0f64; 3]);
    for _ in 0..400 {
        let ranges: Vec<f32> = exact
            .iter()
            .map(|&r| (f64::from(r) + 9.0 * noise.gauss()) as f32)
            .collect();
        ex.extract(&Scan::from_mm(g, &ranges), config).unwrap();
        if let [Feature::Line(l)] = ex.features() {
            fits.push((f64::from(l.alpha), f64::from(l.rho)));
            stated[0] += f64::from(l.var_alpha);
            stated[1] += f64::from(l.var_rho);
            stated[2] += f64::from(l.cov_alpha_rho);
        }
    }
    let n = fits.len() as f64;
    assert!(n >= 250.0, "{n} scans one line");
    let (ma, mr) = (
        fits.iter().map(|f| f.0).sum::<f64>() / n,
        fits.iter().map(|f| f.1).sum::<f64>() / n,
    );
    let var_alpha = fits.iter().map(|f| (f.0 - ma).powi(2)).sum::<f64>() / (n - 1.0);
    let var_rho = fits.iter().map(|f| (f.1 - mr).powi(2)).sum::<f64>() / (n - 1.0);
    let cov = fits.iter().map(|f| (f.0 - ma) * (f.1 - mr)).sum::<f64>() / (n - 1.0);
    [
        stated[0] / n / var_alpha,
        stated[1] / n / var_rho,
        stated[2] / n / cov,
    ]
}

/// A rough wall seen at 45°–68° of incidence (x − y = 3000 mm, range noise 12 mm) beside a
/// smooth wall with 5 mm (x = 2000 mm, which keeps the scan's own σ at 5 mm): the rough line's
/// covariance is scaled by its reduced χ², whose residuals are compared with the range noise's
/// share along the normal (σ_r² cos²β at the middle point): its stated variances are 0.68 of
/// the spread (seed 2026; the middle point's incidence stands for 45°–68°), inside 0.5–1.5,
/// where a wrong incidence term (the normal's sine turned) states 0.30.
#[test]
fn a_rough_line_covariance_follows_its_scatter_at_oblique_incidence() {
    let g = ScanGeometry::LMS200_180_050;
    let (start, step) = (f64::from(g.start_angle), f64::from(g.angle_step));
    let walls = [
        Prim::Seg(2000.0, -4000.0, 2000.0, -200.0),
        Prim::Seg(3000.0, 0.0, 5000.0, 2000.0),
    ];
    let (exact, hits) = scan(&walls, start, step, 361, 8000.0);
    let mut ex = Extractor::<361, 64>::new();
    let mut noise = Noise::new(2026);
    let (mut fits, mut stated) = (Vec::new(), [0.0f64; 2]);
    for _ in 0..400 {
        let ranges: Vec<f32> = exact
            .iter()
            .zip(&hits)
            .map(|(&r, h)| {
                let sigma = if *h == Some(1) { 12.0 } else { 5.0 };
                (f64::from(r) + sigma * noise.gauss()) as f32
            })
            .collect();
        ex.extract(&Scan::from_mm(g, &ranges), &Config::default())
            .unwrap();
        let rough = ex.features().iter().find_map(|f| match f {
            Feature::Line(l) if l.rho > 1500.0 && l.alpha < -0.5 => Some(*l),
            _ => None,
        });
        if let Some(l) = rough.filter(|l| l.points >= 35) {
            fits.push((f64::from(l.alpha), f64::from(l.rho)));
            stated[0] += f64::from(l.var_alpha);
            stated[1] += f64::from(l.var_rho);
        }
    }
    let n = fits.len() as f64;
    assert!(n >= 150.0, "{n} scans with the rough line whole");
    let mean = |k: usize| fits.iter().map(|f| [f.0, f.1][k]).sum::<f64>() / n;
    for (k, what) in ["var_alpha", "var_rho"].into_iter().enumerate() {
        let m = mean(k);
        let spread = fits
            .iter()
            .map(|f| ([f.0, f.1][k] - m).powi(2))
            .sum::<f64>()
            / (n - 1.0);
        let ratio = stated[k] / n / spread;
        println!("{what}: stated / spread {ratio:.2}");
        assert!(
            (0.5..=1.5).contains(&ratio),
            "{what}: stated / spread {ratio:.2}"
        );
    }
}

#[test]
fn a_line_covariance_follows_the_real_scatter_in_rho_too() {
    // With scrutiny (the default) the stated var_rho and cov_alpha_rho, scaled by the fit's
    // reduced χ², match the spread within a factor 1.5; without, they are the 5 mm model's:
    // (5/9)² = 0.31 of it (documented: the scaling is one of scrutiny's checks).
    for (what, ratio) in ["var_rho", "cov_alpha_rho"]
        .into_iter()
        .zip(stated_over_spread(&Config::default()))
    {
        assert!(
            (1.0 / 1.5..=1.5).contains(&ratio),
            "{what}: stated / spread {ratio:.2}"
        );
    }
    for (what, ratio) in ["var_rho", "cov_alpha_rho"]
        .into_iter()
        .zip(stated_over_spread(&Config::default().with_scrutiny(false)))
    {
        assert!(
            (0.2..0.45).contains(&ratio),
            "without scrutiny, {what}: stated / spread {ratio:.2}"
        );
    }
}

#[test]
fn a_scan_geometry_needs_a_positive_maximum_range() {
    let mut g = ScanGeometry::LMS200_180_050;
    assert!(g.is_valid());
    g.r_max = 0.0;
    assert!(!g.is_valid());
    let ranges = [1000.0f32; 361];
    let mut ex = Extractor::<361, 8>::new();
    assert_eq!(
        ex.extract(&Scan::from_mm(g, &ranges), &Config::default()),
        Err(pfe_core::ExtractError::InvalidGeometry)
    );
}

/// `stats()` is what the last extraction returned; `is_mark(i)` is `marks()` membership, and
/// false past the last scan's readings although a longer scan before left marks there.
#[test]
fn the_extractor_reports_its_last_extraction() {
    // A square room 4 m × 4 m around the scanner: walls and corners over 360 beams of 1°, then
    // its beams up to the first mark from beam 100 on.
    let half = 2000.0;
    let prims = [
        Prim::Seg(half, -half, half, half),
        Prim::Seg(half, half, -half, half),
        Prim::Seg(-half, half, -half, -half),
        Prim::Seg(-half, -half, half, -half),
    ];
    let step = 1f64.to_radians();
    let (long, _) = scan(&prims, 0.0, step, 360, 7900.0);
    let g = ScanGeometry::new(0.0, 1f32.to_radians(), 8000.0);
    let mut ex = Extractor::<400, 32>::new();
    let config = Config::default();
    let first = ex.extract(&Scan::from_mm(g, &long), &config).unwrap();
    assert_eq!(first, ex.stats());
    let marks: Vec<usize> = ex.marks().collect();
    for i in 0..400 {
        assert_eq!(ex.is_mark(i), marks.contains(&i), "beam {i}");
    }
    // The second scan ends right before a mark of the first: beam `cut` is past its readings.
    let cut = *marks.iter().find(|&&m| m >= 100).unwrap();
    let second = ex
        .extract(&Scan::from_mm(g, &long[..cut]), &config)
        .unwrap();
    assert_eq!(second, ex.stats());
    assert_ne!(first, second);
    let marks: Vec<usize> = ex.marks().collect();
    assert!(
        marks.iter().all(|&m| m < cut) && !marks.is_empty(),
        "{marks:?}"
    );
    assert!(!ex.is_mark(cut));
    for i in 0..400 {
        assert_eq!(ex.is_mark(i), marks.contains(&i), "beam {i}");
    }
}

/// A circle feature's numbers in declaration order, its arc's angles measured at its centre
/// (an arc around (1000, 2000), not the origin), and well-formedness needing both first ≤ last
/// and finite numbers.
#[test]
fn a_circle_feature_carries_its_arc_seen_from_its_centre() {
    use pfe_core::Circle;
    let center = Point::new(1000.0, 2000.0);
    let r = 300.0f32;
    let angles: Vec<f32> = (0..9).map(|k| -2.5 + 0.1 * k as f32).collect();
    let pts: Vec<Point> = angles
        .iter()
        .map(|&a| Point::new(center.x + r * a.cos(), center.y + r * a.sin()))
        .collect();
    let circle = Circle { center, radius: r };
    let f = pfe_core::circle_feature(&pts, 10, 18, &circle, Point::new(0.0, 0.0), 5.0).unwrap();
    let Feature::Circle(c) = f else {
        panic!("not a circle: {f:?}")
    };
    assert!(
        (c.start_angle - angles[0]).abs() < 1e-5,
        "{}",
        c.start_angle
    );
    assert!((c.end_angle - angles[8]).abs() < 1e-5, "{}", c.end_angle);
    assert_eq!((c.first, c.last, c.points), (10, 18, 9));
    let v = c.values();
    assert_eq!(v[..3], [1000.0, 2000.0, 300.0]);
    let cov: Vec<f32> = c.cov.iter().flatten().copied().collect();
    assert_eq!(v[3..12], cov[..]);
    assert_eq!(v[12..], [c.start_angle, c.end_angle]);
    assert!(f.is_well_formed());

    let mut turned = c;
    (turned.first, turned.last) = (18, 10);
    assert!(!Feature::Circle(turned).is_well_formed());
    let mut nan = c;
    nan.radius = f32::NAN;
    assert!(!Feature::Circle(nan).is_well_formed());
}

/// A rough pillar (range noise 9 mm, the configuration told 5 mm, which a smooth wall behind it
/// keeps as the scan's own σ): the circle's covariance is scaled by its fit's reduced χ²,
/// whose residuals are compared with the range noise's share along the circle's normal at each
/// point (σ_r² cos²β), so its stated variances of centre and radius follow their spread over
/// 300 scans (within 0.5–2: the unweighted fit loses some efficiency). Unscaled they would be
/// about a third of it; compared with σ_r² (as if every beam met the circle head on), 0.42 in
/// y (seed 2027).
#[test]
fn a_rough_circle_covariance_follows_its_scatter() {
    let g = ScanGeometry::LMS200_180_050;
    let (start, step) = (f64::from(g.start_angle), f64::from(g.angle_step));
    let prims = [
        Prim::Seg(4000.0, -3500.0, 4000.0, 3500.0),
        Prim::Circle(2000.0, 500.0, 300.0),
    ];
    let (exact, hits) = scan(&prims, start, step, 361, 8000.0);
    let mut ex = Extractor::<361, 64>::new();
    let mut noise = Noise::new(2027);
    let (mut fits, mut stated) = (Vec::new(), [0.0f64; 3]);
    for _ in 0..300 {
        let ranges: Vec<f32> = exact
            .iter()
            .zip(&hits)
            .map(|(&r, h)| {
                let sigma = if *h == Some(1) { 9.0 } else { 5.0 };
                (f64::from(r) + sigma * noise.gauss()) as f32
            })
            .collect();
        ex.extract(&Scan::from_mm(g, &ranges), &Config::default())
            .unwrap();
        let pillar = ex.features().iter().find_map(|f| match f {
            Feature::Circle(c) if c.center.distance(&Point::new(2000.0, 500.0)) < 100.0 => Some(*c),
            _ => None,
        });
        if let Some(c) = pillar {
            fits.push([c.center.x, c.center.y, c.radius].map(f64::from));
            for (k, s) in stated.iter_mut().enumerate() {
                *s += f64::from(c.cov[k][k]);
            }
        }
    }
    let n = fits.len() as f64;
    assert!(n >= 200.0, "{n} scans with the pillar");
    for (k, what) in ["x", "y", "radius"].into_iter().enumerate() {
        let m = fits.iter().map(|f| f[k]).sum::<f64>() / n;
        let spread = fits.iter().map(|f| (f[k] - m).powi(2)).sum::<f64>() / (n - 1.0);
        let ratio = stated[k] / n / spread;
        println!("{what}: stated / spread {ratio:.2}");
        assert!(
            (0.5..=2.0).contains(&ratio),
            "{what}: stated / spread {ratio:.2}"
        );
    }
}

/// Raw codes: 0 and the reserved codes above `max_valid` are no return, even where the
/// geometry's maximum range would allow their value (here 100 m with cm codes); the others are
/// code × mm per unit. A scan's readings are empty only when there are none.
#[test]
fn raw_codes_beyond_the_valid_ones_are_no_return() {
    use pfe_core::Ranges;
    let codes = [0u16, 100, 8182, 8183, 8191, 5];
    let raw = Ranges::Raw {
        values: &codes,
        mm_per_unit: 10.0,
        max_valid: 8182,
    };
    let got: Vec<Option<f32>> = (0..codes.len()).map(|i| raw.get_mm(i, 100_000.0)).collect();
    assert_eq!(
        got,
        [None, Some(1000.0), Some(81_820.0), None, None, Some(50.0)]
    );
    assert!(!raw.is_empty());
    assert!(Ranges::Mm(&[]).is_empty() && !Ranges::Mm(&[1.0]).is_empty());
    let none = Ranges::Raw {
        values: &[],
        mm_per_unit: 1.0,
        max_valid: 8182,
    };
    assert!(none.is_empty());
}

/// A beam step must be below 1 rad (and not 0): 1 rad exactly is refused.
#[test]
fn a_beam_step_of_one_radian_is_refused() {
    let g = |angle_step: f32| ScanGeometry::new(0.0, angle_step, 8000.0);
    assert!(g(0.999).is_valid() && g(-0.999).is_valid());
    assert!(!g(1.0).is_valid() && !g(-1.0).is_valid() && !g(0.0).is_valid());
}

/// A scan of LMS range codes extracts exactly as the same ranges in mm: mm mode (1 mm a code)
/// and cm mode (10 mm a code), a room with a pillar.
#[test]
fn a_scan_of_range_codes_extracts_as_its_ranges_in_mm() {
    let g = ScanGeometry::LMS200_180_050;
    let (start, step) = (f64::from(g.start_angle), f64::from(g.angle_step));
    let prims = [
        Prim::Seg(3000.0, -2500.0, 3000.0, 2500.0),
        Prim::Seg(3000.0, 2500.0, -500.0, 2500.0),
        Prim::Circle(1500.0, -700.0, 200.0),
    ];
    let (exact, _) = scan(&prims, start, step, 361, 8000.0);
    for unit in [1.0f32, 10.0] {
        let codes: Vec<u16> = exact
            .iter()
            .map(|&r| {
                if r.is_finite() {
                    (r / unit).round() as u16
                } else {
                    0
                }
            })
            .collect();
        let mm: Vec<f32> = codes
            .iter()
            .map(|&c| {
                if c == 0 {
                    f32::NAN
                } else {
                    f32::from(c) * unit
                }
            })
            .collect();
        let geometry = ScanGeometry::new(g.start_angle, g.angle_step, 8000.0);
        let (mut a, mut b) = (Extractor::<361, 32>::new(), Extractor::<361, 32>::new());
        let config = Config::default().with_sigma_r(5.0);
        let sa = a
            .extract(&Scan::from_lms(geometry, &codes, unit), &config)
            .unwrap();
        // The codes' unit is their grid: the same ranges in mm, on the same grid.
        let mm_scan = Scan::from_mm(geometry, &mm).with_quantum(unit);
        let sb = b.extract(&mm_scan, &config).unwrap();
        assert_eq!(sa, sb, "unit {unit}");
        assert!(sa.features >= 3, "{sa:?}");
        assert_eq!(a.features(), b.features(), "unit {unit}");
    }
}

/// A floor above `k σ_r` (10 mm against 4 · 1 mm): the walk's exact test decides every point
/// (the fast path's test holds only for floors below `k σ_r`; what it rejects is examined
/// again), so a wall with 0.5 mm of noise is one line with no mark inside it, as with the
/// floor at 3 mm.
#[test]
fn a_floor_above_k_sigma_takes_the_exact_test() {
    let g = ScanGeometry::LMS200_180_050;
    let (start, step) = (f64::from(g.start_angle), f64::from(g.angle_step));
    let (exact, _) = scan(
        &[Prim::Seg(2000.0, -1500.0, 2000.0, 1500.0)],
        start,
        step,
        361,
        8000.0,
    );
    let mut noise = Noise::new(5);
    let ranges: Vec<f32> = exact
        .iter()
        .map(|&r| (f64::from(r) + 0.5 * noise.gauss()) as f32)
        .collect();
    let mut ex = Extractor::<361, 8>::new();
    for floor in [3.0f32, 10.0] {
        let config = with_model(|m| m.floor = floor).with_sigma_r(1.0);
        ex.extract(&Scan::from_mm(g, &ranges), &config).unwrap();
        let marks: Vec<usize> = ex.marks().collect();
        let [Feature::Line(l)] = ex.features() else {
            panic!("floor {floor}: {:?}", ex.features())
        };
        let (a, b) = (usize::from(l.first), usize::from(l.last));
        assert!(
            marks.iter().all(|&m| m == a || m == b),
            "floor {floor}: marks {marks:?} in {a}..={b}"
        );
    }
}

/// The paper's threshold grows with the range (`d_m = (d_0/λ)(r/r_max + (π − ϕ)/π)`): a 20 mm
/// bump in a wall faced straight on is a mark at 0.5 m (d_m ≈ 14 mm) and not at 7.5 m
/// (d_m ≈ 36 mm).
#[test]
fn the_papers_threshold_grows_with_range() {
    let g = ScanGeometry::LMS200_180_050;
    let mut ex = Extractor::<361, 32>::new();
    for (d, marked) in [(500.0f32, true), (7500.0, false)] {
        let ranges: Vec<f32> = (0..361)
            .map(|i| {
                let b = g.bearing(i);
                let r = d / b.cos() + if i == 180 { 20.0 } else { 0.0 };
                if b.abs() < 0.5 {
                    r
                } else {
                    f32::NAN
                }
            })
            .collect();
        ex.extract(&Scan::from_mm(g, &ranges), &Config::paper())
            .unwrap();
        assert_eq!(ex.is_mark(180), marked, "wall at {d} mm");
    }
}

/// Loading LMS codes: the largest valid code (the lesser of the device's 8182 and r_max over
/// the unit) is a point, the next one is no return.
#[test]
fn a_code_one_past_the_largest_valid_one_is_no_return() {
    let g = ScanGeometry::LMS200_180_050;
    for (unit, r_max, largest) in [(1.0f32, 8000.0f32, 8000u16), (10.0, 81_820.0, 8182)] {
        let geometry = ScanGeometry::new(g.start_angle, g.angle_step, r_max);
        let mut codes = [1000u16; 361];
        (codes[100], codes[101], codes[200]) = (largest, largest + 1, largest);
        let mut ex = Extractor::<361, 32>::new();
        let stats = ex
            .extract(&Scan::from_lms(geometry, &codes, unit), &Config::default())
            .unwrap();
        assert_eq!(stats.valid, 360, "unit {unit}");
        let points = ex.points();
        assert!(points[100].is_valid() && points[200].is_valid() && !points[101].is_valid());
        let r = f32::from(largest) * unit;
        assert!(
            (points[100].norm() - r).abs() < 1e-3 * r,
            "unit {unit}: {:?}",
            points[100]
        );
    }
}
