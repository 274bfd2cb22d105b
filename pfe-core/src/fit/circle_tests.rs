//! Unit tests of `fit::circle`'s crate-private kernels (`ArcSums`, `inverse3`).

extern crate std;
use super::*;
use std::vec::Vec;

/// The one-pass sums give the same line residual and Kåsa circle as the two-pass fits, on
/// arcs of several radii, spans and distances, with alternating 5 mm offsets as noise.
#[test]
fn arc_sums_match_the_two_pass_fits() -> Result<(), FitError> {
    for &(cx, cy, r) in &[
        (3000.0f32, 500.0f32, 150.0f32),
        (6000.0, -2000.0, 400.0),
        (1500.0, 0.0, 1500.0),
    ] {
        for n in [6usize, 12, 24, 64] {
            let span = 1.2f32;
            let pts: Vec<Point> = (0..n)
                .map(|i| {
                    let t = 2.5 + span * i as f32 / (n - 1) as f32;
                    let rr = r + if i % 2 == 0 { 5.0 } else { -5.0 };
                    Point::new(cx + rr * t.cos(), cy + rr * t.sin())
                })
                .collect();
            let sums = ArcSums::of(&pts).ok_or(FitError::Degenerate)?;
            let two_pass = fit_circle(&pts, CircleMethod::Kasa)?;
            let one_pass = sums.kasa().ok_or(FitError::Degenerate)?;
            assert!(
                one_pass.center.distance(&two_pass.center) < 1e-3 * r,
                "{n} {r}"
            );
            assert!(
                (one_pass.radius - two_pass.radius).abs() < 1e-3 * r,
                "{n} {r}"
            );
            let line = crate::fit::line::fit_line(&pts)?.sse();
            assert!(
                (sums.line_sse() - line).abs() <= 1e-3 * line + 1.0,
                "{n} {r}"
            );
        }
    }
    Ok(())
}

/// Points on one line, or nearly (a determinant below 1e-10 of the spread squared), have no
/// Kåsa circle in the arc test's sums; a gentle arc does.
#[test]
fn arc_sums_of_collinear_points_have_no_circle() {
    for (x0, y0, dx, dy) in [
        (1000.0f32, 0.0f32, 7.0f32, 3.0f32),
        (-4000.0, 2500.0, 1.0, -40.0),
    ] {
        let pts: [Point; 9] =
            core::array::from_fn(|i| Point::new(x0 + dx * i as f32, y0 + dy * i as f32));
        let sums = ArcSums::of(&pts);
        assert!(sums.is_some_and(|s| s.kasa().is_none()), "{x0} {y0}");
    }
    // Bowed by 1.6e-4 mm over 0.8 m (radius 5e8 mm): its determinant (about 0.02) is far
    // above rounding but below 1e-10 of the spread squared (36).
    let bow: [Point; 9] = core::array::from_fn(|i| {
        let k = i as f32 - 4.0;
        Point::new(2000.0 + 100.0 * k, 1e-5 * k * k)
    });
    assert!(ArcSums::of(&bow).is_some_and(|s| s.kasa().is_none()));
    let arc: [Point; 9] = core::array::from_fn(|i| {
        let t = 0.05 * i as f32;
        Point::new(5000.0 * t.cos(), 5000.0 * t.sin())
    });
    let c = ArcSums::of(&arc).and_then(|s| s.kasa());
    assert!(c.is_some_and(|c| (c.radius - 5000.0).abs() < 5.0), "{c:?}");
}

/// The singularity test is relative to the spread squared, not to the spread: an arc of
/// 500 m radius seen over 0.8 m (bowed by 0.16 mm; determinant about 2e4, spread 6e5) still
/// has a Kåsa circle.
#[test]
fn arc_sums_judge_a_gentle_arc_by_the_spread_squared() {
    let arc: [Point; 9] = core::array::from_fn(|i| {
        let k = i as f32 - 4.0;
        Point::new(2000.0 + 100.0 * k, 0.01 * k * k)
    });
    let c = ArcSums::of(&arc).and_then(|s| s.kasa());
    assert!(c.is_some_and(|c| c.radius > 1e5), "{c:?}");
}

/// `inverse3` refuses matrices singular relative to their scale (condition beyond 1e9 of
/// the largest entry cubed), whatever their scale, and a determinant that overflows; it
/// inverts a well-conditioned one at any scale.
#[test]
fn inverse3_judges_singularity_relative_to_scale() {
    let diag = |a: f32, b: f32, c: f32| [[a, 0.0, 0.0], [0.0, b, 0.0], [0.0, 0.0, c]];
    for s in [1e-3f32, 1.0, 1e3] {
        // det = s³·1e-11: 1e-11 of the scale cubed.
        assert_eq!(inverse3(&diag(s, s, s * 1e-11)), None, "{s}");
        // Entries in any order: the largest sets the scale.
        assert_eq!(inverse3(&diag(s * 1e-11, s, s)), None, "{s}");
        let m = [[2.0 * s, s, 0.0], [s, 3.0 * s, s], [0.0, s, 4.0 * s]];
        let inv = inverse3(&m).unwrap();
        for (i, row) in mul3(&m, &inv).iter().enumerate() {
            for (j, p) in row.iter().enumerate() {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((p - want).abs() < 1e-5, "{s} {i} {j} {p}");
            }
        }
    }
    // |det| = 4 · (5e12)³ overflows f32 while the scale cubed does not.
    let k = 5e12f32;
    let big = [[k, k, k], [k, -k, k], [k, k, -k]];
    assert!(!det3(&big).is_finite());
    assert_eq!(inverse3(&big), None);
}

/// The normal equations with their sums in locals are the sums kept in the answer, bit for
/// bit: arcs of random centres, radii and noise, at circles off the truth, with a point at the
/// centre (no direction: only its residual counts) and non-finite points among them.
#[test]
fn the_normal_equations_are_the_sums_in_their_slot() {
    // The sums as they were, in the answer's slot.
    let reference = |points: &[Point], c: &Circle| {
        let mut eq = NormalEquations {
            jtj: [[0.0; 3]; 3],
            jtr: [0.0; 3],
            sse: 0.0,
        };
        let mut jtj = OuterSum::default();
        for p in points {
            let (dx, dy) = (p.x - c.center.x, p.y - c.center.y);
            let d = math::hypot(dx, dy);
            let r = d - c.radius;
            eq.sse += r * r;
            if !(d > 0.0) {
                continue;
            }
            let inv_d = 1.0 / d;
            let (a, b) = (-dx * inv_d, -dy * inv_d);
            jtj.add([a, b, -1.0]);
            eq.jtr[0] += a * r;
            eq.jtr[1] += b * r;
            eq.jtr[2] -= r;
        }
        eq.jtj = jtj.matrix();
        eq
    };
    let mut seed = 5u32;
    let mut u = move || {
        seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (seed >> 8) as f32 / (1u32 << 24) as f32
    };
    let bits = |eq: &NormalEquations| {
        let mut v: Vec<u32> = eq.jtj.iter().flatten().map(|x| x.to_bits()).collect();
        v.extend(eq.jtr.iter().map(|x| x.to_bits()));
        v.push(eq.sse.to_bits());
        v
    };
    for t in 0..500 {
        let (cx, cy, r) = (8000.0 * u() - 4000.0, 8000.0 * u(), 50.0 + 2000.0 * u());
        let n = 3 + (t % 40);
        let mut pts: Vec<Point> = (0..n)
            .map(|_| {
                let a = 6.0 * u();
                let rr = r + 20.0 * (u() - 0.5);
                Point::new(cx + rr * a.cos(), cy + rr * a.sin())
            })
            .collect();
        let c = Circle {
            center: Point::new(cx + 30.0 * (u() - 0.5), cy + 30.0 * (u() - 0.5)),
            radius: r * (0.9 + 0.2 * u()),
        };
        match t % 10 {
            0 => pts.push(c.center),
            1 => pts.push(Point::INVALID),
            2 => pts.push(Point::new(f32::INFINITY, cy)),
            _ => {}
        }
        assert_eq!(
            bits(&NormalEquations::at(&pts, &c)),
            bits(&reference(&pts, &c)),
            "{t}"
        );
    }
}

/// A full circle of points mirrored about the x axis, refined from a centre 2 mm off along x
/// and the radius that is the mean distance to it (computed in f64): the first step is about
/// (2, 0, 0) (its radius part of the order of 2²/R, the y part zero by symmetry), its length
/// 2 mm, far above the convergence tolerance (0.01 mm), and the refinement
/// reaches the true centre (0, 0) and radius 1000 mm (the points lie on it exactly, up to f32
/// rounding).
#[test]
fn refinement_moves_a_centre_off_along_one_axis_only() -> Result<(), FitError> {
    let r = 1000.0f64;
    let mut pts: Vec<Point> = Vec::new();
    for k in 0..=18 {
        let t = core::f64::consts::PI * f64::from(k) / 18.0;
        let (x, y) = ((r * t.cos()) as f32, (r * t.sin()) as f32);
        pts.push(Point::new(x, y));
        if k != 0 && k != 18 {
            pts.push(Point::new(x, -y));
        }
    }
    let c0 = (2.0f64, 0.0f64);
    let mean = pts
        .iter()
        .map(|p| (f64::from(p.x) - c0.0).hypot(f64::from(p.y) - c0.1))
        .sum::<f64>()
        / pts.len() as f64;
    let initial = Circle {
        center: Point::new(c0.0 as f32, c0.1 as f32),
        radius: mean as f32,
    };
    let c = refine_circle(&pts, initial, 10)?;
    assert!(
        c.center.x.abs() < 0.01 && c.center.y.abs() < 0.01 && (c.radius - 1000.0).abs() < 0.01,
        "{c:?}"
    );
    Ok(())
}
