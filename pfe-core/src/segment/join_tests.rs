//! Tests of [`join_collinear`]'s bound on a joined line's points.
#![allow(clippy::indexing_slicing)]

use heapless::Vec;

use super::super::emitted::emitted;
use super::JOIN_MAX_POINTS;
use crate::feature::Feature;
use crate::scan::ScanGeometry;

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
    emitted(g, &ranges, [first, second])
        .iter()
        .filter_map(|f| match f {
            Feature::Line(l) => Some((l.first, l.last)),
            _ => None,
        })
        .collect()
}

/// Two pieces of one wall are joined into one line of up to [`JOIN_MAX_POINTS`] (400)
/// points, and not beyond: 200 + 200 points make one line, 200 + 201 stay two.
#[test]
fn a_joined_line_holds_at_most_join_max_points() {
    assert_eq!(JOIN_MAX_POINTS, 400);
    assert_eq!(joined((100, 299), (300, 499))[..], [(100, 499)]);
    assert_eq!(joined((100, 299), (300, 500))[..], [(100, 299), (300, 500)]);
}
