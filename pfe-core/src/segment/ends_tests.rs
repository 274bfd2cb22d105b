//! Tests of the corner point's move ([`give_corner_point`]).
#![allow(clippy::indexing_slicing)]

use heapless::Vec;

use super::super::join::join_collinear;
use super::super::{emit, JOINS_MAX};
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
/// segment step does (each followed by [`join_collinear`]).
fn segments_of(
    ranges: &[f32; 181],
    first: (usize, usize),
    second: (usize, usize),
) -> Vec<Feature, 8> {
    let g = ScanGeometry::lms200(180.0, 1.0);
    let config = Config::default();
    let mut ex = Extractor::<181, 8>::new();
    ex.with_pass(&Scan::from_mm(g, ranges), &config, |pass, rule| {
        let Some(noise) = rule.noise() else {
            panic!("the default rule")
        };
        let mut out: Vec<Feature, 8> = Vec::new();
        let mut joins = JOINS_MAX;
        for (s, e) in [first, second] {
            emit::<true>(pass, s, e, None, &config, &mut out);
            join_collinear(pass, noise, &config, &mut out, &mut joins);
        }
        out
    })
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
