//! Tests of the corner point's move ([`give_corner_point`]) across a range jump.
#![allow(clippy::indexing_slicing)]

use heapless::Vec;

use super::super::join::join_collinear;
use super::super::{emit, JOINS_MAX};
use crate::config::Config;
use crate::extractor::Extractor;
use crate::feature::Feature;
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
    let config = Config::default();
    let mut ex = Extractor::<181, 8>::new();
    let spans: Vec<(usize, usize), 8> =
        ex.with_pass(&Scan::from_mm(g, &ranges), &config, |pass, rule| {
            let Some(noise) = rule.noise() else {
                panic!("the default rule")
            };
            pass.set(160, JUMP);
            let mut out: Vec<Feature, 8> = Vec::new();
            let mut joins = JOINS_MAX;
            for (s, e) in [(150, 159), (160, 163)] {
                emit::<true>(pass, s, e, None, &config, &mut out);
                join_collinear(pass, noise, &config, &mut out, &mut joins);
            }
            out.iter().map(|f| (f.first(), f.last())).collect()
        });
    assert_eq!(spans[..], [(150, 160)]);
}
