//! Tests of [`join_collinear`]'s bound on a joined line's points.
#![allow(clippy::indexing_slicing)]

use heapless::Vec;

use super::super::{emit, JOINS_MAX};
use super::{join_collinear, JOIN_MAX_POINTS};
use crate::config::Config;
use crate::extractor::Extractor;
use crate::feature::Feature;
use crate::scan::{Scan, ScanGeometry};

/// The first and last beam of each line after two segments of one straight wall (x = 3 m,
/// seen at 0.25° without noise) are emitted as the segment step does, each followed by
/// [`join_collinear`].
fn joined(first: (usize, usize), second: (usize, usize)) -> Vec<(u16, u16), 4> {
    let g = ScanGeometry::lms200(180.0, 0.25);
    let ranges: [f32; 721] = core::array::from_fn(|i| {
        let (_, c) = crate::math::sin_cos(g.bearing(i));
        if (40..=680).contains(&i) {
            3000.0 / c
        } else {
            f32::NAN
        }
    });
    let config = Config::default();
    let mut ex = Extractor::<721, 8>::new();
    ex.with_pass(&Scan::from_mm(g, &ranges), &config, |pass, rule| {
        let Some(noise) = rule.noise() else {
            panic!("the default rule")
        };
        let mut out: Vec<Feature, 8> = Vec::new();
        let mut joins = JOINS_MAX;
        for (s, e) in [first, second] {
            emit::<true>(pass, s, e, None, &config, &mut out);
            join_collinear(pass, noise, &config, &mut out, &mut joins);
        }
        out.iter()
            .filter_map(|f| match f {
                Feature::Line(l) => Some((l.first, l.last)),
                _ => None,
            })
            .collect()
    })
}

/// Two pieces of one wall are joined into one line of up to [`JOIN_MAX_POINTS`] (400)
/// points, and not beyond: 200 + 200 points make one line, 200 + 201 stay two.
#[test]
fn a_joined_line_holds_at_most_join_max_points() {
    assert_eq!(JOIN_MAX_POINTS, 400);
    assert_eq!(joined((100, 299), (300, 499))[..], [(100, 499)]);
    assert_eq!(joined((100, 299), (300, 500))[..], [(100, 299), (300, 500)]);
}
