//! Tests of [`join_collinear`]: its bound on a joined line's points, and a noisy wall's pieces joined.
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

/// Two pieces of one straight wall (x = 3 m, 0.25°) whose ranges alternate ±4 mm about the
/// truth (0.8 σ_r of the default 5 mm) are one line within the noise: joined into one. Their
/// residual sum (about 13 mm² a point) is within `on_one_line`'s 2.25 σ_r² a point only when
/// the variance is σ_r² (25 mm²), not σ_r / σ_r.
#[test]
fn pieces_of_one_noisy_wall_are_joined() {
    let g = ScanGeometry::lms200(180.0, 0.25);
    let ranges: [f32; 721] = core::array::from_fn(|i| {
        let (_, c) = crate::math::sin_cos(g.bearing(i));
        let noise = if i % 2 == 0 { 4.0 } else { -4.0 };
        if (40..=680).contains(&i) {
            3000.0 / c + noise
        } else {
            f32::NAN
        }
    });
    let lines: Vec<(u16, u16), 4> = emitted(g, &ranges, [(250, 369), (370, 489)])
        .iter()
        .filter_map(|f| match f {
            Feature::Line(l) => Some((l.first, l.last)),
            _ => None,
        })
        .collect();
    assert_eq!(lines[..], [(250, 489)]);
}
