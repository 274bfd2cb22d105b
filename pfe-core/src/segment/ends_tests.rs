//! Tests of the corner point's move ([`give_corner_point`]).
#![allow(clippy::indexing_slicing)]

use heapless::Vec;

use crate::config::Config;
use crate::extractor::Extractor;
use crate::feature::{Feature, LineFeature};
use crate::geometry::Point;
use crate::scan::{Scan, ScanGeometry};

/// Ranges at 1° of a wall 3 m ahead (x = 3000 mm) from beam 83 on, and before it, from beam
/// `face` to 82, a face at 45° running from the wall towards the scanner; their corner is at
/// 0.25° past beam 82, so beam 83 is 28 mm off the face's line. No noise; other beams see
/// nothing. `mirrored`: the same scene seen upside down (beam i at 180 − i).
fn scene(g: &ScanGeometry, face: usize, mirrored: bool) -> [f32; 181] {
    scene_at(g, (face, 82), 0.25, mirrored)
}

/// [`scene`] with the face over the beams `face.0..=face.1` and the corner `past`° past beam
/// `face.1`, the wall from beam `face.1 + 1` to 100.
pub(super) fn scene_at(
    g: &ScanGeometry,
    face: (usize, usize),
    past: f32,
    mirrored: bool,
) -> [f32; 181] {
    let d2r = core::f32::consts::PI / 180.0;
    let corner_bearing = g.bearing(face.1) + past * d2r;
    let c = Point::new(
        3000.0,
        3000.0 * crate::math::sin_cos(corner_bearing).0 / crate::math::sin_cos(corner_bearing).1,
    );
    let h = core::f32::consts::FRAC_1_SQRT_2;
    // The face's normal (1, −1)/√2 and distance from the scanner.
    let rho_a = h * (c.x - c.y);
    core::array::from_fn(|j| {
        let i = if mirrored { 180 - j } else { j };
        let (s, co) = crate::math::sin_cos(g.bearing(i));
        match i {
            _ if (face.1 + 1..=100).contains(&i) => 3000.0 / co,
            _ if (face.0..=face.1).contains(&i) => rho_a / (h * (co - s)),
            _ => f32::NAN,
        }
    })
}

/// The features of the scene after its two segments (`first`, `second`) are emitted as the
/// segment step does.
fn segments_of(
    ranges: &[f32; 181],
    first: (usize, usize),
    second: (usize, usize),
) -> Vec<Feature, 8> {
    super::super::emitted::emitted(ScanGeometry::lms200(180.0, 1.0), ranges, [first, second])
}

/// The first and last beam of each line of `out`.
fn spans(out: &[Feature]) -> Vec<(u16, u16), 8> {
    out.iter()
        .map(|f| match f {
            Feature::Line(l) => (l.first, l.last),
            _ => (0, 0),
        })
        .collect()
}

/// A face seen over three beams (80..=82) and the wall's first beam (83) in one segment, the
/// wall's others (84..=100) in the next: beam 83 lies on the wall's line and 28 mm (5.6 σ_r,
/// beyond the 3-point line's uncertainty there) off the face's, so it goes to the wall, and
/// the face's three beams are too few for a feature. Seen upside down (the wall first, its
/// segment ending at the mirrored beam 97 after the face's first beam, beams 97..=100) the
/// same.
#[test]
fn a_three_beam_face_and_the_next_surface_s_first_beam_are_not_one_line() {
    let g = ScanGeometry::lms200(180.0, 1.0);
    let out = segments_of(&scene(&g, 80, false), (80, 83), (84, 100));
    assert_eq!(spans(&out), [(83, 100)].as_slice(), "{out:?}");
    let out = segments_of(&scene(&g, 80, true), (80, 96), (97, 100));
    assert_eq!(spans(&out), [(80, 97)].as_slice(), "{out:?}");
}

/// A face seen over four beams (79..=82), its segment ending at its own last beam: that beam
/// lies on the face's line, and both lines stay as they are.
#[test]
fn a_four_beam_face_keeps_its_beams() {
    let g = ScanGeometry::lms200(180.0, 1.0);
    let out = segments_of(&scene(&g, 79, false), (79, 82), (83, 100));
    assert_eq!(spans(&out), [(79, 82), (83, 100)].as_slice(), "{out:?}");
    let out = segments_of(&scene(&g, 79, true), (80, 97), (98, 101));
    assert_eq!(spans(&out), [(80, 97), (98, 101)].as_slice(), "{out:?}");
}

/// The end point moves out of a segment of at most `REST_MAX` (32) points only: the face over
/// beams 52..=82 with the wall's first beam 83 in its segment (32 points) gives beam 83 to the
/// wall; the face from beam 51 (33 points in the segment) keeps it, the two lines as emitted.
#[test]
fn the_end_point_moves_out_of_a_segment_of_at_most_rest_max_points() {
    let g = ScanGeometry::lms200(180.0, 1.0);
    assert_eq!(super::REST_MAX, 32);
    let out = segments_of(&scene(&g, 52, false), (52, 83), (84, 100));
    assert_eq!(spans(&out), [(52, 82), (83, 100)].as_slice(), "{out:?}");
    let out = segments_of(&scene(&g, 51, false), (51, 83), (84, 100));
    assert_eq!(spans(&out), [(51, 83), (84, 100)].as_slice(), "{out:?}");
}

/// [`closer`]'s distance to a line counts the line's own uncertainty where the point lies:
/// the wall's beam 100 (10° off the x axis, 529 mm from the line's foot) lies 15 mm beyond
/// the line x = wall − 15 mm, 3 σ_r; with σ_α = 0.01 rad the line itself is uncertain by
/// 529 σ_α = 5.3 mm there, and the residual's σ √(5² + 5.3²) mm puts the point within
/// χ²₁ 99 % (4.2 of 6.63); without σ_α it would not be (9); far off the face's line. The
/// same line seen with ρ's uncertainty only (σ_ρ 5.3 mm) agrees.
#[test]
fn a_line_s_own_uncertainty_counts_where_the_point_lies() {
    use super::{closer, OFF_LINE_CHI2};
    let g = ScanGeometry::lms200(180.0, 1.0);
    let ranges = scene(&g, 80, false);
    let config = Config::default();
    let mut ex = Extractor::<181, 8>::new();
    let judged = ex.with_pass(&Scan::from_mm(g, &ranges), &config, |pass, rule| {
        let Some(noise) = rule.noise() else {
            panic!("the default rule")
        };
        let p = pass.point(100);
        assert!((p.y - 529.0).abs() < 1.0, "{p:?}");
        let line = |var_alpha: f32, var_rho: f32| {
            LineFeature::new(83, 99, 17, 0.0, p.x - 15.0, var_alpha, var_rho, 0.0, p, p)
        };
        [line(1e-4, 0.0), line(0.0, 0.0), line(0.0, 28.0)]
            .map(|l| closer(pass, noise, &l, 100, 80..=82, OFF_LINE_CHI2))
    });
    assert_eq!(judged, [true, false, true]);
}

/// A face seen over three beams (80..=82) whose corner with the wall is 0.6° past beam 82 (0.4°
/// before beam 83): beam 83 hits the wall 21 mm past the corner, 15 mm off the face's line, within
/// the noise of the line of the face's three beams carried there, so its range does not tell;
/// where the two lines meet, between beams 82 and 83, does: beam 83 goes to the wall and the
/// face's three beams are too few for a feature. Seen upside down the same.
#[test]
fn a_beam_past_the_corner_of_two_lines_is_the_far_line_s() {
    let g = ScanGeometry::lms200(180.0, 1.0);
    let out = segments_of(&scene_at(&g, (80, 82), 0.6, false), (80, 83), (84, 100));
    assert_eq!(spans(&out), [(83, 100)].as_slice(), "{out:?}");
    let out = segments_of(&scene_at(&g, (80, 82), 0.6, true), (80, 96), (97, 100));
    assert_eq!(spans(&out), [(80, 97)].as_slice(), "{out:?}");
}

/// A face seen over four beams (80..=83) whose corner with the wall is 0.3° past beam 83: beam 83
/// lies within the noise of the wall's line too (11 mm off it), but the corner lies past its beam
/// on the wall's side, so it stays with the face. Seen upside down the same.
#[test]
fn a_beam_before_the_corner_of_two_lines_stays() {
    let g = ScanGeometry::lms200(180.0, 1.0);
    let out = segments_of(&scene_at(&g, (80, 83), 0.3, false), (80, 83), (84, 100));
    assert_eq!(spans(&out), [(80, 83), (84, 100)].as_slice(), "{out:?}");
    let out = segments_of(&scene_at(&g, (80, 83), 0.3, true), (80, 96), (97, 100));
    assert_eq!(spans(&out), [(80, 96), (97, 100)].as_slice(), "{out:?}");
}

/// [`beyond_corner`] against the geometry worked out independently in f64 over 6000 random
/// corners of two lines (any orientations 20–160° apart, 1.5–5 m off, the corner anywhere from
/// a beam before `p`'s to one past `q`'s, either turn): the corner by walking along one line
/// to the other, its σ across `p`'s beam by moving each line by a millimetre and watching the
/// corner move, each line's σ at the corner from its covariance (`l`) or from its points (`f`:
/// σ_r² (1/n + u²/Σu²)). Every case more than 3 % off the 1σ margin is judged alike, and
/// more than a hundred lie within a factor of 2 of it on each side.
#[test]
fn the_corner_test_agrees_with_the_geometry() {
    use super::beyond_corner;
    use crate::fit::line::fit_line;
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut uniform = |lo: f64, hi: f64| {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        lo + (hi - lo) * (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let cross = |a: [f64; 2], b: [f64; 2]| a[0] * b[1] - a[1] * b[0];
    let dot = |a: [f64; 2], b: [f64; 2]| a[0] * b[0] + a[1] * b[1];
    // Where the beam at `bearing` meets the line through `c` along `d`.
    let hit = |bearing: f64, c: [f64; 2], d: [f64; 2]| {
        let u = [bearing.cos(), bearing.sin()];
        let t = cross(c, d) / cross(u, d);
        [t * u[0], t * u[1]]
    };
    // The point of (α₁, ρ₁)'s line on (α₂, ρ₂)'s, walking along the first.
    let meet = |(a1, r1): (f64, f64), (a2, r2): (f64, f64)| {
        let (n1, d1, n2) = (
            [a1.cos(), a1.sin()],
            [-a1.sin(), a1.cos()],
            [a2.cos(), a2.sin()],
        );
        let p0 = [r1 * n1[0], r1 * n1[1]];
        let t = (r2 - dot(n2, p0)) / dot(n2, d1);
        [p0[0] + t * d1[0], p0[1] + t * d1[1]]
    };
    let step = 0.5f64.to_radians();
    let (mut judged, mut near, mut yes) = (0usize, [0usize; 2], 0usize);
    for _ in 0..6000 {
        let (range, bearing) = (uniform(1500.0, 5000.0), uniform(-1.2, 1.2));
        let corner = [range * bearing.cos(), range * bearing.sin()];
        let phi1 = uniform(0.0, core::f64::consts::PI);
        let phi2 = phi1 + uniform(20.0, 160.0).to_radians();
        let (d1, d2) = ([phi1.cos(), phi1.sin()], [phi2.cos(), phi2.sin()]);
        let turn = if uniform(0.0, 1.0) < 0.5 { 1.0 } else { -1.0 };
        let bp = bearing - turn * uniform(-1.0, 2.0) * step;
        let beam = |i: f64| bp + turn * i * step;
        let grazing = |b: f64, d: [f64; 2]| cross([b.cos(), b.sin()], d).abs() < 0.3;
        if grazing(beam(0.0), d1) || (0..12).any(|i| grazing(beam(f64::from(i + 1)), d2)) {
            continue;
        }
        let p = hit(beam(0.0), corner, d1);
        let n = 3 + (uniform(0.0, 10.0) as usize);
        let on_f: Vec<[f64; 2], 16> = (1..=n).map(|i| hit(beam(i as f64), corner, d2)).collect();
        if dot(p, p).sqrt() < 100.0
            || on_f
                .iter()
                .any(|q| dot(*q, *q) > 2.0e8 || dot(*q, [beam(0.0).cos(), beam(0.0).sin()]) < 0.0)
        {
            continue;
        }
        let q = on_f[0];
        // l: normal away from the scanner, a covariance of any shape.
        let mut a1 = phi1 + core::f64::consts::FRAC_PI_2;
        let mut r1 = dot(corner, [a1.cos(), a1.sin()]);
        if r1 < 0.0 {
            a1 -= core::f64::consts::PI;
            r1 = -r1;
        }
        let (va, vr) = (
            10f64.powf(uniform(-7.0, -3.5)),
            10f64.powf(uniform(0.0, 2.5)),
        );
        let cov = uniform(-0.6, 0.6) * (va * vr).sqrt();
        let var_r = 10f64.powf(uniform(0.5, 2.5));
        let pt = |v: [f64; 2]| Point::new(v[0] as f32, v[1] as f32);
        let l = LineFeature::new(
            0,
            1,
            5,
            a1 as f32,
            r1 as f32,
            va as f32,
            vr as f32,
            cov as f32,
            pt(p),
            pt(p),
        );
        let pts: Vec<Point, 16> = on_f.iter().map(|&v| pt(v)).collect();
        let Ok(f) = fit_line(&pts) else { continue };
        let got = beyond_corner(&l, &f, var_r as f32, pt(p), pt(q));
        // The truth, in f64 from the same inputs.
        let lines = (
            (f64::from(l.alpha), f64::from(l.rho)),
            (f64::from(f.alpha), f64::from(f.rho)),
        );
        let c = meet(lines.0, lines.1);
        let (pf, qf) = ([f64::from(l.start.x), f64::from(l.start.y)], q);
        let norm = dot(pf, pf).sqrt();
        let u = [pf[0] / norm, pf[1] / norm];
        let sense = cross(pf, qf).signum();
        let off = cross(u, c) * sense;
        let across = |v: [f64; 2]| cross(u, v) * sense - off;
        let h = 1.0;
        let gain_l = across(meet((lines.0 .0, lines.0 .1 + h), lines.1)) / h;
        let gain_f = across(meet(lines.0, (lines.1 .0, lines.1 .1 + h))) / h;
        let t = -c[0] * lines.0 .0.sin() + c[1] * lines.0 .0.cos();
        let var_l = t * t * va + vr - 2.0 * t * cov;
        let pts64: Vec<[f64; 2], 16> = pts
            .iter()
            .map(|p| [f64::from(p.x), f64::from(p.y)])
            .collect();
        let mean = pts64.iter().fold([0.0, 0.0], |m, p| {
            [m[0] + p[0] / n as f64, m[1] + p[1] / n as f64]
        });
        let dir = [-lines.1 .0.sin(), lines.1 .0.cos()];
        let suu: f64 = pts64
            .iter()
            .map(|p| dot([p[0] - mean[0], p[1] - mean[1]], dir).powi(2))
            .sum();
        let uc = dot([c[0] - mean[0], c[1] - mean[1]], dir);
        let var_f = var_r * (1.0 / n as f64 + uc * uc / suu);
        let var_c = var_l * gain_l * gain_l + var_f * gain_f * gain_f;
        let ratio = off * off / var_c;
        let before_q = cross(c, qf) * sense;
        if (ratio - 1.0).abs() < 0.03
            || before_q.abs() < 1e-4 * dot(c, c).sqrt() * dot(qf, qf).sqrt()
            || off.abs() < 1e-3
        {
            continue;
        }
        let want = dot(c, pf) > 0.0 && off > 0.0 && ratio > 1.0 && before_q > 0.0;
        assert_eq!(
            got, want,
            "{l:?} {f:?} var_r {var_r} p {p:?} q {q:?} corner {c:?} ratio {ratio}"
        );
        judged += 1;
        yes += usize::from(want);
        if off > 0.0 && before_q > 0.0 && (0.5..2.0).contains(&ratio) {
            near[usize::from(ratio > 1.0)] += 1;
        }
    }
    assert!(judged > 3000 && yes > 400, "{judged} judged, {yes} beyond");
    assert!(near[0] > 100 && near[1] > 100, "near the margin: {near:?}");
}

/// [`closer`]'s distance from a point to the line of the short segment's other points counts
/// that line's uncertainty carried to the point, σ_r² (1/n + u²/Σu²) beside the point's own
/// σ_r²: against the same question worked out in f64 (the three points' total least-squares
/// line, u along it from their centroid) for faces at 10–80° and the point 0–60 mm off the
/// face's line along its beam, on a line parallel to the face (so no corner decides), every
/// case more than 2 % off the χ² threshold is judged alike, and the threshold is crossed.
#[test]
fn the_distance_to_the_short_line_counts_its_uncertainty_at_the_point() {
    use super::{closer, OFF_LINE_CHI2};
    let g = ScanGeometry::lms200(180.0, 1.0);
    let config = Config::default();
    let d2r = core::f64::consts::PI / 180.0;
    let (mut alike, mut on_each_side) = (0usize, [0usize; 2]);
    for deg in (10..=80).step_by(5) {
        let alpha = f64::from(deg) * d2r - 10.0 * d2r;
        let rho = 2000.0f64;
        let range = |i: usize, off: f64| (rho + off) / (f64::from(g.bearing(i)) - alpha).cos();
        for step in 0..=60 {
            let off = f64::from(step);
            let ranges: [f32; 181] = core::array::from_fn(|i| match i {
                80..=82 => range(i, 0.0) as f32,
                83 => range(83, off) as f32,
                _ => 0.0,
            });
            let mut ex = Extractor::<181, 8>::new();
            let (judged, sigma_r, pts) =
                ex.with_pass(&Scan::from_mm(g, &ranges), &config, |pass, rule| {
                    let Some(noise) = rule.noise() else {
                        panic!("the default rule")
                    };
                    let p = pass.point(83);
                    let l = LineFeature::new(
                        83,
                        99,
                        17,
                        alpha as f32,
                        (rho + off) as f32,
                        0.0,
                        0.0,
                        0.0,
                        p,
                        p,
                    );
                    let pts: [[f64; 2]; 4] =
                        [80, 81, 82, 83].map(|i| [pass.point(i).x, pass.point(i).y].map(f64::from));
                    let judged = closer(pass, noise, &l, 83, 80..=82, OFF_LINE_CHI2);
                    (judged, f64::from(noise.sigma_r), pts)
                });
            // The rest's line in f64: centroid, direction by the principal axis.
            let n = 3.0;
            let (cx, cy) = (
                (pts[0][0] + pts[1][0] + pts[2][0]) / n,
                (pts[0][1] + pts[1][1] + pts[2][1]) / n,
            );
            let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
            for q in &pts[..3] {
                let (dx, dy) = (q[0] - cx, q[1] - cy);
                sxx += dx * dx;
                syy += dy * dy;
                sxy += dx * dy;
            }
            let theta = 0.5 * (2.0 * sxy).atan2(sxx - syy);
            let (tx, ty) = (theta.cos(), theta.sin());
            let along = |q: &[f64; 2]| (q[0] - cx) * tx + (q[1] - cy) * ty;
            let across = |q: &[f64; 2]| -(q[0] - cx) * ty + (q[1] - cy) * tx;
            let suu: f64 = pts[..3].iter().map(|q| along(q).powi(2)).sum();
            let u = along(&pts[3]);
            let var_f = sigma_r * sigma_r * (1.0 + 1.0 / n + u * u / suu);
            let chi2 = across(&pts[3]).powi(2) / var_f;
            let margin = chi2 / f64::from(OFF_LINE_CHI2);
            if (margin - 1.0).abs() > 0.02 {
                let expected = chi2 >= f64::from(OFF_LINE_CHI2);
                assert_eq!(
                    judged, expected,
                    "{deg}° off {off} mm: χ² {chi2:.3}, u {u:.1}, Σu² {suu:.1}"
                );
                alike += 1;
                on_each_side[usize::from(expected)] += 1;
            }
        }
    }
    assert!(
        alike > 800 && on_each_side.iter().all(|&k| k > 100),
        "{alike} {on_each_side:?}"
    );
}

/// [`closer`]'s distance from a point to the other segment's line counts that line's
/// uncertainty at the point (its covariance in α, ρ carried along the line) beside the point's
/// own σ_r²: against the same question worked out in f64 (the distance's change with α by a
/// central difference, with ρ by −1) for lines at 30–70° either side of the point's beam (the
/// point up to 2.8 m along them from their normal's foot), a correlation of α and ρ of −0.8, 0
/// or 0.8, and the point 0–60 mm off the line (the other points' line 2 m away: only the
/// distance decides), every case more than 2 % off the χ² threshold is judged alike, and the
/// threshold is crossed.
#[test]
fn the_distance_to_the_long_line_counts_its_covariance_at_the_point() {
    use super::{closer, ON_LINE_CHI2};
    let g = ScanGeometry::lms200(180.0, 1.0);
    let config = Config::default();
    let d2r = core::f64::consts::PI / 180.0;
    let ranges: [f32; 181] = core::array::from_fn(|i| match i {
        80..=82 => 1000.0,
        83 => 3000.0,
        _ => 0.0,
    });
    let (var_alpha, var_rho) = (25.0f64 / (1500.0 * 1500.0), 25.0f64);
    let (mut alike, mut on_each_side) = (0usize, [0usize; 2]);
    for phi in [-70, -50, -30, 30, 50, 70] {
        for corr in [-0.8f64, 0.0, 0.8] {
            let cov = corr * (var_alpha * var_rho).sqrt();
            for step in 0..=120 {
                let off = 0.5 * f64::from(step);
                let mut ex = Extractor::<181, 8>::new();
                let (judged, sigma_r, p) =
                    ex.with_pass(&Scan::from_mm(g, &ranges), &config, |pass, rule| {
                        let Some(noise) = rule.noise() else {
                            panic!("the default rule")
                        };
                        let p = pass.point(83);
                        let (px, py) = (f64::from(p.x), f64::from(p.y));
                        let alpha = py.atan2(px) + f64::from(phi) * d2r;
                        // The line `off` mm from the point along its normal.
                        let rho = px * alpha.cos() + py * alpha.sin() - off;
                        let l = LineFeature::new(
                            90,
                            120,
                            31,
                            alpha as f32,
                            rho as f32,
                            var_alpha as f32,
                            var_rho as f32,
                            cov as f32,
                            p,
                            p,
                        );
                        let judged = closer(pass, noise, &l, 83, 80..=82, ON_LINE_CHI2);
                        (judged, f64::from(noise.sigma_r), [px, py, alpha, rho])
                    });
                let [px, py, alpha, rho] = p;
                let d = |a: f64| px * a.cos() + py * a.sin() - rho;
                let h = 1e-6;
                let d_alpha = (d(alpha + h) - d(alpha - h)) / (2.0 * h);
                // Var(d) = J Σ Jᵀ with J = (∂d/∂α, ∂d/∂ρ = −1).
                let var = sigma_r * sigma_r + d_alpha * d_alpha * var_alpha + var_rho
                    - 2.0 * d_alpha * cov;
                let chi2 = d(alpha).powi(2) / var;
                let margin = chi2 / f64::from(ON_LINE_CHI2);
                if (margin - 1.0).abs() > 0.02 {
                    let expected = chi2 <= f64::from(ON_LINE_CHI2);
                    assert_eq!(
                        judged, expected,
                        "φ {phi}° ρα-correlation {corr} off {off} mm: χ² {chi2:.3}, ∂d/∂α {d_alpha:.0}"
                    );
                    alike += 1;
                    on_each_side[usize::from(expected)] += 1;
                }
            }
        }
    }
    assert!(
        alike > 2000 && on_each_side.iter().all(|&k| k > 500),
        "{alike} {on_each_side:?}"
    );
}
