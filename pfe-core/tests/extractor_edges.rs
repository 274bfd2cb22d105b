//! Extractor behaviours at their edges, against analytic truth (the exact ray casting of
//! `common`, closed-form poses, f64 first-order propagation): distant walls at grazing
//! incidence at any heading, a bent wall of less than 30° of arc, the covariance of a line of a
//! de-skewed scan, and a beam within 10⁻⁶ of a window's line. (How they were found:
//! docs/TESTING.md, "Mutation testing".)
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]
#![allow(clippy::needless_range_loop)]

mod common;

use common::{scan, Noise, Prim};
use pfe_core::predict::WindowLine;
use pfe_core::{Config, Extractor, Feature, Motion, Point, Scan, ScanGeometry};

/// Ranges with Gaussian noise σ, rounded to `quantum` mm.
fn noisy(exact: &[f32], sigma: f64, quantum: f64, seed: u64) -> Vec<f32> {
    let mut noise = Noise::new(seed);
    exact
        .iter()
        .map(|&x| {
            ((f64::from(x) + sigma * noise.gauss()) / quantum).round() as f32 * quantum as f32
        })
        .collect()
}

/// A corridor 3 m wide and 40 m long along the heading `th` (cm-mode LMS200, 1° beams, σ_r
/// 10 mm, ranges to 50 m): beyond 8 m its walls are seen at a few degrees, too sparse for the
/// walk, and must still come out as lines on their walls (as in tests/grazing.rs, which has
/// the corridor along x). Headings where a wall's normal has cos α = −0.618 (±128°, corridor
/// at ±38°) and an oblique one: the join's tests must hold for any direction of the line.
#[test]
fn distant_walls_at_any_heading_are_lines() {
    let mut g = ScanGeometry::lms200(180.0, 1.0);
    g.r_max = 50_000.0;
    let (start, step) = (f64::from(g.start_angle), f64::from(g.angle_step));
    let sigma = 10.0;
    let config = Config::default().with_sigma_r(sigma as f32);
    let mut ex = Extractor::<181, 64>::new();
    for th in [0.6669f64, -0.6669, 0.3] {
        let (c, s) = (th.cos(), th.sin());
        let rot = |x: f64, y: f64| (c * x - s * y, s * x + c * y);
        let seg = |a: (f64, f64), b: (f64, f64)| {
            let (p, q) = (rot(a.0, a.1), rot(b.0, b.1));
            Prim::Seg(p.0, p.1, q.0, q.1)
        };
        let prims = [
            seg((1000.0, 1500.0), (40_000.0, 1500.0)),
            seg((1000.0, -1500.0), (40_000.0, -1500.0)),
            seg((40_000.0, -1500.0), (40_000.0, 1500.0)),
        ];
        // Distance of a point from wall w, in the corridor's frame (y = ±1500).
        let off = |p: Point, w: usize| {
            let y = -s * f64::from(p.x) + c * f64::from(p.y);
            (y - if w == 0 { 1500.0 } else { -1500.0 }).abs()
        };
        let (exact, hits) = scan(&prims, start, step, 181, 50_000.0);
        let (mut far, mut covered) = (0usize, 0usize);
        for seed in 0..20 {
            let ranges = noisy(&exact, sigma, 10.0, seed);
            ex.extract(&Scan::from_mm(g, &ranges), &config).unwrap();
            for (i, h) in hits.iter().enumerate() {
                let Some(w @ (0 | 1)) = *h else { continue };
                // Up to 25 m: a line of the wall from 8 m is seen within 85° at its midpoint up
                // to 2·1.5 m·tan 85° − 8 m = 26 m along the wall (issue 39); beyond, no
                // reported line can hold a beam.
                if exact[i] < 8000.0 || exact[i] > 25_000.0 {
                    continue;
                }
                far += 1;
                covered += usize::from(ex.features().iter().any(|f| match f {
                    Feature::Line(l) => {
                        usize::from(l.first) <= i
                            && i <= usize::from(l.last)
                            && off(l.start, w) < 4.0 * sigma
                            && off(l.end, w) < 4.0 * sigma
                    }
                    _ => false,
                }));
            }
        }
        assert!(far > 100, "heading {th}: {far} far wall beams");
        assert!(
            covered * 4 >= far * 3,
            "heading {th}: {covered} of {far} far wall beams in a line on their wall"
        );
    }
}

/// A wall bent as 20° of a circle of radius 1.5 m (sagitta 23 mm, far above σ_r 5 mm), 3 m
/// ahead, concave and convex: an arc of less than the 30° a circle must cover, so no circle,
/// while the visible side of a pillar of radius 400 mm is one.
#[test]
fn an_arc_of_less_than_thirty_degrees_is_not_a_circle() {
    let g = ScanGeometry::LMS200_180_050;
    let (start, step) = (f64::from(g.start_angle), f64::from(g.angle_step));
    let mut ex = Extractor::<361, 64>::new();
    let half = 10f64.to_radians();
    let arc_prims = |cx: f64, r: f64, from: f64, to: f64| -> Vec<Prim> {
        // The arc as 200 chords (a polygon within 0.02 mm of the circle).
        (0..200)
            .map(|k| {
                let (a, b) = (
                    from + (to - from) * k as f64 / 200.0,
                    from + (to - from) * (k + 1) as f64 / 200.0,
                );
                Prim::Seg(cx + r * a.cos(), r * a.sin(), cx + r * b.cos(), r * b.sin())
            })
            .collect()
    };
    let mut circles = 0;
    for seed in 0..10 {
        // Convex towards the scanner (centre beyond the wall), and concave (centre in front).
        for prims in [
            arc_prims(
                4500.0,
                1500.0,
                std::f64::consts::PI - half,
                std::f64::consts::PI + half,
            ),
            arc_prims(1500.0, 1500.0, -half, half),
        ] {
            let (exact, _) = scan(&prims, start, step, 361, 8000.0);
            let ranges = noisy(&exact, 5.0, 1.0, seed);
            ex.extract(&Scan::from_mm(g, &ranges), &Config::default())
                .unwrap();
            circles += ex
                .features()
                .iter()
                .filter(|f| matches!(f, Feature::Circle(_)))
                .count();
        }
    }
    assert_eq!(circles, 0, "circles on 20° arcs");
    // A pillar: a circle of its radius.
    let pillar = [Prim::Circle(3000.0, 200.0, 400.0)];
    let (exact, _) = scan(&pillar, start, step, 361, 8000.0);
    let ranges = noisy(&exact, 5.0, 1.0, 99);
    ex.extract(&Scan::from_mm(g, &ranges), &Config::default())
        .unwrap();
    assert!(
        ex.features()
            .iter()
            .any(|f| matches!(f, Feature::Circle(c) if (c.radius - 400.0).abs() < 15.0)),
        "{:?}",
        ex.features()
    );
}

/// Total least-squares line (α, ρ) of points in f64.
fn tls(pts: &[(f64, f64)]) -> (f64, f64) {
    let n = pts.len() as f64;
    let cx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let cy = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for p in pts {
        sxx += (p.0 - cx).powi(2);
        syy += (p.1 - cy).powi(2);
        sxy += (p.0 - cx) * (p.1 - cy);
    }
    // Normal angle: the direction of least spread.
    let alpha = 0.5 * (-2.0 * sxy).atan2(syy - sxx);
    let rho = cx * alpha.cos() + cy * alpha.sin();
    if rho < 0.0 {
        let a = alpha + std::f64::consts::PI;
        (
            a - 2.0 * std::f64::consts::PI * (a / (2.0 * std::f64::consts::PI)).round(),
            -rho,
        )
    } else {
        (alpha, rho)
    }
}

/// First-order variances of (α, ρ) of the f64 line fit of the points `at(i, 0)` of beams
/// `idx` under range noise σ on each: `at(i, dr)` is beam i's point moved `dr` along its beam.
fn propagated(idx: &[usize], at: impl Fn(usize, f64) -> (f64, f64), sigma: f64) -> (f64, f64) {
    let base: Vec<(f64, f64)> = idx.iter().map(|&i| at(i, 0.0)).collect();
    let (mut va, mut vr) = (0.0f64, 0.0f64);
    for (k, &i) in idx.iter().enumerate() {
        let h = 0.01;
        let mut plus = base.clone();
        plus[k] = at(i, h);
        let mut minus = base.clone();
        minus[k] = at(i, -h);
        let (ap, rp) = tls(&plus);
        let (am, rm) = tls(&minus);
        let (da, dr) = ((ap - am) / (2.0 * h), (rp - rm) / (2.0 * h));
        va += sigma * sigma * da * da;
        vr += sigma * sigma * dr * dr;
    }
    (va, vr)
}

/// A wall x = 3 m from y = 0.5 m to 2.05 m, static, seen by beams 199 to 248 of an LMS200 at
/// 0.5° (incidence 10° to 34°): the line's variances are those of range noise along its
/// beams (f64 first-order propagation; within 10⁻³: the extractor's closed form over the beam
/// span is exact here to 10⁻⁵), which depend on where the beams meet it.
#[test]
fn a_line_off_to_the_side_has_the_covariance_of_its_beams() {
    let g = ScanGeometry::LMS200_180_050;
    let sigma = 5.0;
    let dir = |i: usize| {
        let b = f64::from(g.bearing(i));
        (b.cos(), b.sin())
    };
    let ranges: Vec<f32> = (0..361)
        .map(|i| {
            let (dx, dy) = dir(i);
            let t = 3000.0 / dx;
            if dx > 0.1 && (500.0..2050.0).contains(&(t * dy)) {
                t as f32
            } else {
                f32::NAN
            }
        })
        .collect();
    let mut ex = Extractor::<361, 8>::new();
    ex.extract(
        &Scan::from_mm(g, &ranges),
        &Config::default().with_sigma_r(sigma as f32),
    )
    .unwrap();
    let [Feature::Line(l)] = ex.features() else {
        panic!("{:?}", ex.features())
    };
    // 50 beams: the middle lies half a step past beam 223.
    assert_eq!((l.first, l.last), (199, 248), "{l:?}");
    let idx: Vec<usize> = (usize::from(l.first)..=usize::from(l.last)).collect();
    let at = |i: usize, dr: f64| {
        let (dx, dy) = dir(i);
        let t = 3000.0 / dx + dr;
        (t * dx, t * dy)
    };
    let (va, vr) = propagated(&idx, at, sigma);
    let (ra, rr) = (f64::from(l.var_alpha) / va, f64::from(l.var_rho) / vr);
    assert!(
        (0.999..1.001).contains(&ra) && (0.999..1.001).contains(&rr),
        "var_alpha {} vs {va:.3e} (×{ra:.3}), var_rho {} vs {vr:.3e} (×{rr:.3})",
        l.var_alpha,
        l.var_rho
    );
}

/// The exact pose of a constant-velocity motion at time t (f64).
fn pose64(v: f64, omega: f64, t: f64) -> (f64, f64, f64) {
    let th = omega * t;
    (v / omega * th.sin(), v / omega * (1.0 - th.cos()), th)
}

/// A wall seen while the robot drives at 1 m/s and turns at 1 rad/s (the skew made large:
/// beams 2.666 ms apart, 0.96 s a scan). The extracted line's variances are those of range
/// noise along each beam from where the scanner was when it took it: f64 first-order
/// propagation by finite differences of an f64 line fit, within 4 % (the extractor takes one
/// scanner position, its middle beam's, for the whole segment: 1 % off here; the position of
/// another beam is up to 10 % off).
#[test]
fn a_deskewed_line_has_the_covariance_of_its_beams() {
    let g = ScanGeometry::LMS200_180_050;
    let (v, omega, dt) = (1000.0f64, 1.0f64, 0.002_666f64);
    let m = Motion::uniform(v as f32, omega as f32, dt as f32);
    let wall = 4000.0;
    let sigma = 5.0;
    // Beam i from its pose: the exact range to x = wall.
    let beam = |i: usize| {
        let (ox, oy, th) = pose64(v, omega, i as f64 * dt);
        let b = f64::from(g.bearing(i)) + th;
        let (dx, dy) = (b.cos(), b.sin());
        let t = (wall - ox) / dx;
        ((ox, oy), (dx, dy), t, oy + t * dy)
    };
    let ranges: Vec<f32> = (0..361)
        .map(|i| {
            let (_, (dx, _), t, y) = beam(i);
            if dx > 0.1 && t > 0.0 && y.abs() < 3000.0 {
                t as f32
            } else {
                f32::NAN
            }
        })
        .collect();
    let mut ex = Extractor::<361, 8>::new();
    ex.extract(
        &Scan::from_mm(g, &ranges).with_motion(m),
        &Config::default().with_sigma_r(sigma as f32),
    )
    .unwrap();
    let [Feature::Line(l)] = ex.features() else {
        panic!("{:?}", ex.features())
    };
    let idx: Vec<usize> = (usize::from(l.first)..=usize::from(l.last))
        .filter(|&i| ranges[i].is_finite())
        .collect();
    let at = |i: usize, dr: f64| {
        let ((ox, oy), (dx, dy), t, _) = beam(i);
        (ox + (t + dr) * dx, oy + (t + dr) * dy)
    };
    let (va, vr) = propagated(&idx, at, sigma);
    let (ra, rr) = (f64::from(l.var_alpha) / va, f64::from(l.var_rho) / vr);
    assert!(
        (0.96..1.04).contains(&ra) && (0.96..1.04).contains(&rr),
        "var_alpha {} vs {va:.3e} (×{ra:.3}), var_rho {} vs {vr:.3e} (×{rr:.3})",
        l.var_alpha,
        l.var_rho
    );
}

#[test]
fn a_beam_within_a_millionth_of_the_line_predicts_nothing() {
    // The window's line y = 1000 and beams from the origin at 10⁻⁷ and 10⁻⁵ rad to it: the
    // first runs along the line (|sin ϕ| < 10⁻⁶, the bound of `ray_line_intersection` too) and
    // predicts nothing; the second meets it 10⁸ mm away.
    let w = [
        Point::new(-200.0, 1000.0),
        Point::new(0.0, 1000.0),
        Point::new(200.0, 1000.0),
    ];
    let o = Point::new(0.0, 0.0);
    let line = WindowLine::fit(&w, o).unwrap();
    let r = 3000.0f32;
    let along = line.predict(o, r, r * 1e-7, r);
    assert!(
        along.error.is_infinite() && along.var_factor.is_infinite(),
        "{along:?}"
    );
    let steep = line.predict(o, r, r * 1e-5, r);
    assert!(steep.error.is_finite() && steep.error > 1e7, "{steep:?}");
}

/// A scan told that the robot stood still (odometry of zero speed) is de-skewed along the
/// paths of a moving robot (each beam's own scanner position and window lines), which must
/// find what the static paths find: the same marks and the same features over the same beams
/// with the same parameters (within f32 rounding: 10⁻⁵ rad, 0.01 mm; a circle's refinement,
/// which stops at steps below 0.01 mm, within 0.1 mm), over 40 noisy scans of a room with corners, a doorway and a
/// pillar. (Only the line covariances differ: a moving scanner's are propagated point by
/// point.)
#[test]
fn odometry_of_standing_still_changes_nothing() {
    use pfe_core::BeamTiming;
    let g = ScanGeometry::LMS200_180_050;
    let prims = [
        Prim::Seg(3000.0, -2500.0, 3000.0, 400.0),
        Prim::Seg(3000.0, 1200.0, 3000.0, 2500.0),
        Prim::Seg(3000.0, 2500.0, -1000.0, 2500.0),
        Prim::Seg(3000.0, -2500.0, -1000.0, -2500.0),
        Prim::Seg(4200.0, 400.0, 4200.0, 1200.0),
        Prim::Circle(1800.0, -900.0, 250.0),
    ];
    let (exact, _) = scan(
        &prims,
        f64::from(g.start_angle),
        f64::from(g.angle_step),
        361,
        8000.0,
    );
    let still = Motion {
        v: 0.0,
        omega: 0.0,
        timing: BeamTiming::lms2xx(0.5),
    };
    let config = Config::default().with_sigma_r(5.0);
    let mut noise = Noise::new(41);
    let (mut a, mut b) = (Extractor::<361, 32>::new(), Extractor::<361, 32>::new());
    let mut marks = 0;
    for t in 0..40 {
        let ranges: Vec<f32> = exact
            .iter()
            .map(|&r| (f64::from(r) + 5.0 * noise.gauss()) as f32)
            .collect();
        a.extract(&Scan::from_mm(g, &ranges), &config).unwrap();
        b.extract(&Scan::from_mm(g, &ranges).with_motion(still), &config)
            .unwrap();
        let (ma, mb): (Vec<usize>, Vec<usize>) = (a.marks().collect(), b.marks().collect());
        assert_eq!(ma, mb, "scan {t}");
        marks += ma.len();
        assert_eq!(a.features().len(), b.features().len(), "scan {t}");
        for (fa, fb) in a.features().iter().zip(b.features()) {
            let same = match (fa, fb) {
                (Feature::Line(x), Feature::Line(y)) => {
                    (x.first, x.last) == (y.first, y.last)
                        && (x.alpha - y.alpha).abs() < 1e-5
                        && (x.rho - y.rho).abs() < 0.01
                }
                (Feature::Circle(x), Feature::Circle(y)) => {
                    (x.first, x.last) == (y.first, y.last)
                        && x.center.distance(&y.center) < 0.1
                        && (x.radius - y.radius).abs() < 0.1
                }
                _ => false,
            };
            assert!(same, "scan {t}: {fa:?} vs {fb:?}");
        }
    }
    assert!(marks >= 40 * 8, "{marks} marks in 40 scans");
}
