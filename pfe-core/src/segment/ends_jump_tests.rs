//! Tests of the corner point's move ([`give_corner_point`]) across a range jump, and of the
//! variances its tests weigh ([`closer`], [`beyond_corner`]).
#![allow(clippy::indexing_slicing)]

use heapless::Vec;

use super::super::emitted::emitted_after;
use crate::config::Config;
use crate::extractor::Extractor;
use crate::flags::JUMP;
use crate::math;
use crate::scan::{Scan, ScanGeometry};

/// Ranges at 1° of a wall x = 1000 mm seen at grazing incidence over beams 150..=160
/// (60°..70° off its normal, its points 100-150 mm apart) that ends, 0.5° past beam 160, in a
/// corner with a face y = 2824 mm (normal to the wall, towards the scanner's side) seen over
/// beams 161..=163. No noise; other beams see nothing.
fn grazing_wall_and_face(g: &ScanGeometry) -> [f32; 181] {
    let (s, c) = math::sin_cos(g.bearing(160) + 0.5f32.to_radians());
    let corner_y = 1000.0 * s / c;
    core::array::from_fn(|i| {
        let (s, c) = math::sin_cos(g.bearing(i));
        match i {
            150..=160 => 1000.0 / c,
            161..=163 => corner_y / s,
            _ => f32::NAN,
        }
    })
}

/// The wall's last beam (160), its step from beam 159 a range jump (as the walk flags where a
/// grazing wall's points grow apart faster than it predicts), in one segment with the face's
/// three beams: the beam lies on the wall's line and 77 mm off the face's (far beyond the
/// noise), so it goes to the wall, and the face's three beams are too few for a feature. The
/// jump between the two segments does not keep it from moving.
#[test]
fn a_grazing_wall_s_last_beam_across_a_jump_goes_back_to_the_wall() {
    let g = ScanGeometry::lms200(180.0, 1.0);
    let ranges = grazing_wall_and_face(&g);
    let spans: Vec<(usize, usize), 8> =
        emitted_after(g, &ranges, [(150, 159), (160, 163)], |pass| {
            pass.set(160, JUMP)
        })
        .iter()
        .map(|f| (f.first(), f.last()))
        .collect();
    assert_eq!(spans[..], [(150, 160)]);
}

/// [`closer`]'s residual variance holds the range noise's σ_r² (25 mm²) when the line has
/// none of its own: the wall's beam 100, 12 mm (2.4 σ_r) beyond the line, lies on it (χ²₁
/// 5.8 of 6.63); 14 mm beyond (7.8) it does not.
#[test]
fn a_point_within_the_range_noise_of_an_exact_line_lies_on_it() {
    use super::{closer, OFF_LINE_CHI2};
    use crate::feature::LineFeature;
    let g = ScanGeometry::lms200(180.0, 1.0);
    let ranges = super::tests::scene_at(&g, (80, 82), 0.25, false);
    let config = Config::default();
    let mut ex = Extractor::<181, 8>::new();
    let judged = ex.with_pass(&Scan::from_mm(g, &ranges), &config, |pass, rule| {
        let Some(noise) = rule.noise() else {
            panic!("the default rule")
        };
        assert_eq!(noise.sigma_r, 5.0);
        let p = pass.point(100);
        [12.0, 14.0].map(|off| {
            let l = LineFeature::new(83, 99, 17, 0.0, p.x - off, 0.0, 0.0, 0.0, p, p);
            closer(pass, noise, &l, 100, 80..=82, OFF_LINE_CHI2)
        })
    });
    assert_eq!(judged, [true, false]);
}

/// [`beyond_corner`]'s σ of the corner across the beam weighs each line's variance by how
/// far a shift of it moves the corner across the beam: the wall's (σ_ρ² = V) moves it along
/// the face, whose normal makes 38° with beam 83 (cos² 0.62). The corner of the wall and the
/// face's three beams lies 21.1 mm past beam 83's (446 mm²); with the face's own share
/// (41 mm² × cos² 7°) the corner's variance is (41 + 0.62 V) / sin² 45°: below 446 for V =
/// 240 mm², above it for V = 320 mm² (and for V = 240 without the 0.62).
#[test]
fn the_corner_s_sigma_weighs_each_line_along_the_other() {
    use super::beyond_corner;
    use crate::feature::LineFeature;
    use crate::fit::line::fit_line;
    let g = ScanGeometry::lms200(180.0, 1.0);
    let ranges = super::tests::scene_at(&g, (80, 82), 0.6, false);
    let config = Config::default();
    let mut ex = Extractor::<181, 8>::new();
    let judged = ex.with_pass(&Scan::from_mm(g, &ranges), &config, |pass, rule| {
        let Some(noise) = rule.noise() else {
            panic!("the default rule")
        };
        let Ok(face) = fit_line(&pass.points[80..=82]) else {
            panic!("the face's line")
        };
        let (p, q) = (pass.point(83), pass.point(82));
        let var_r = noise.sigma_r * noise.sigma_r;
        [240.0, 320.0].map(|v| {
            let wall = LineFeature::new(83, 100, 18, 0.0, 3000.0, 0.0, v, 0.0, p, p);
            beyond_corner(&wall, &face, var_r, p, q)
        })
    });
    assert_eq!(judged, [true, false]);
}
