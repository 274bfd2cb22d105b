//! [`emit`]'s pieces: a run split around one pillar after another still searches the pieces
//! waiting after it (up to [`PIECES`] in all).

use super::*;
use crate::extractor::Extractor;
use crate::geometry::{ray_circle_intersection, Point};
use crate::scan::{Scan, ScanGeometry};

/// Features [`emit`] gives for the whole run of valid beams of `ranges` (an LMS200 scan, 180°
/// at 0.5°), with a scan's budget for pillar searches.
fn emitted(ranges: &[f32; 361]) -> Vec<Feature, 16> {
    let mut ex = Extractor::<361, 16>::new();
    let config = Config::default();
    let scan = Scan::from_mm(ScanGeometry::LMS200_180_050, ranges);
    ex.with_pass(&scan, &config, |pass, rule| {
        let mut out: Vec<Feature, 16> = Vec::new();
        let s = (0..pass.len()).find(|&i| pass.valid(i));
        let e = (0..pass.len()).rev().find(|&i| pass.valid(i));
        let mut budget = PILLAR_SCANS * pass.len();
        let arc = rule.noise().and_then(arc_rule).map(|r| (r, &mut budget));
        if let (Some(s), Some(e)) = (s, e) {
            emit::<true>(pass, s, e, arc, &config, &mut out);
        }
        out
    })
}

/// The wall 2 m ahead of the pillar tests below.
const WALL: f32 = 2000.0;
/// Their pillars: centre's y on the wall and radius, mm.
const PILLARS: [(f32, f32); 3] = [(-1100.0, 150.0), (0.0, 200.0), (1100.0, 250.0)];

/// Exact ranges of [`PILLARS`] standing out of the wall [`WALL`] ahead, beams within 60° of
/// the wall's normal (no return beyond).
fn three_pillars_scene(g: ScanGeometry) -> [f32; 361] {
    core::array::from_fn(|i| {
        let (s, c) = math::sin_cos(g.bearing(i));
        if c < 0.5 {
            return 0.0;
        }
        PILLARS
            .iter()
            .filter_map(|&(y, r)| {
                ray_circle_intersection(Point::new(0.0, 0.0), c, s, Point::new(WALL, y), r)
            })
            .fold(WALL / c, f32::min)
    })
}

/// Three pillars standing out of a wall 2 m ahead (their centres on it, radii 250, 200 and
/// 150 mm, the largest at the run's far end), no noise, one run over beams within 60° of the
/// wall's normal: three circles on the pillars between four pieces of the wall. The largest
/// residual is the largest pillar's, so it is found first; the second is found in the piece
/// before it, and the third in the piece before that, with four pieces waiting (the wall
/// beyond each pillar, each pillar's arc).
#[test]
fn three_pillars_on_a_wall_are_three_circles() {
    let pillars = PILLARS;
    let g = ScanGeometry::LMS200_180_050;
    let ranges = three_pillars_scene(g);
    let f = emitted(&ranges);
    let circles: Vec<_, 16> = f
        .iter()
        .filter_map(|x| match x {
            Feature::Circle(c) => Some((c.center, c.radius)),
            _ => None,
        })
        .collect();
    let lines = f
        .iter()
        .filter(|x| matches!(x, Feature::Line(l) if (l.rho - WALL).abs() < 5.0))
        .count();
    assert!(
        circles.len() == 3
            && circles.iter().zip(&pillars).all(|((c, r), &(y, radius))| {
                c.distance(&Point::new(WALL, y)) < 15.0 && (r - radius).abs() < 15.0
            })
            && lines == 4
            && f.len() == 7,
        "{f:?}"
    );
}

/// The scan's budget for pillar searches is [`PILLAR_SCANS`] (2) scans' lengths: the scene of
/// [`three_pillars_on_a_wall_are_three_circles`], its valid beams one segment (no marks
/// between them) that [`segments`] emits, searches the whole run (241 points) and then the
/// piece before each pillar found (more than one scan's 361 points in all), and finds the
/// three pillars.
#[test]
fn the_pillar_search_has_two_scans_lengths_of_points() {
    let pillars = PILLARS;
    let g = ScanGeometry::LMS200_180_050;
    let ranges = three_pillars_scene(g);
    let config = Config::default();
    let mut ex = Extractor::<361, 16>::new();
    let f = ex.with_pass(&Scan::from_mm(g, &ranges), &config, |pass, rule| {
        for k in 0..pass.len() {
            pass.clear(k, START | END);
        }
        let mut out: Vec<Feature, 16> = Vec::new();
        segments(pass, rule, &config, &mut out);
        out
    });
    let found = pillars
        .iter()
        .filter(|&&(y, radius)| {
            f.iter().any(|x| {
                matches!(x, Feature::Circle(c)
                    if c.center.distance(&Point::new(WALL, y)) < 15.0
                        && (c.radius - radius).abs() < 15.0)
            })
        })
        .count();
    assert_eq!(found, 3, "{f:?}");
}
