//! A pillar standing in a wall, seen over 15 beams: one circle, not two lines.
#![allow(clippy::indexing_slicing)]

use crate::extractor::Extractor;
use crate::feature::Feature;
use crate::geometry::{ray_circle_intersection, Point};
use crate::scan::{Scan, ScanGeometry};
use crate::Config;

use super::super::tests::gaussian;

/// A wall 1.1 m to the right (running away at 11°) with a pillar of 263 mm radius standing in
/// it, 61 mm proud of it, 1.65 m away (a corridor scene's, where the walk cut the pillar's 15
/// beams in two, 12 + 3 with one beam of the wall, each typed a line). Over 100 noise draws
/// (σ_r = 5 mm) the feature on the pillar's beams (index-range IoU ≥ 0.5) is a circle in at
/// least 90 of them and a line in at most 5, and no feature off the pillar is a circle.
#[test]
fn a_pillar_in_a_wall_is_one_circle() {
    let g = ScanGeometry::LMS200_180_050;
    let config = Config::default();
    let (a, b) = (Point::new(770.1, -1113.9), Point::new(3162.2, -661.6));
    // The wall's line: n·x = ρ.
    let (tx, ty) = (b.x - a.x, b.y - a.y);
    let len = libm::sqrtf(tx * tx + ty * ty);
    let (nx, ny) = (-ty / len, tx / len);
    let rho = nx * a.x + ny * a.y;
    let centre = Point::new(1508.0, -1175.8);
    let radius = 262.7;
    let hit = |i: usize| {
        let (s, c) = crate::math::sin_cos(g.bearing(i));
        let wall = rho / (nx * c + ny * s);
        let wall = if (30..=200).contains(&i) && wall > 0.0 {
            wall
        } else {
            f32::INFINITY
        };
        let post = ray_circle_intersection(Point::new(0.0, 0.0), c, s, centre, radius)
            .unwrap_or(f32::INFINITY);
        (wall.min(post), post < wall)
    };
    let on_post: heapless::Vec<usize, 361> = (0..361).filter(|&i| hit(i).1).collect();
    let (p0, p1) = (on_post[0], on_post[on_post.len() - 1]);
    assert_eq!((p0, p1, on_post.len()), (105, 119, 15));
    let iou = |f: &Feature| {
        let (lo, hi) = (f.first().max(p0), f.last().min(p1));
        let inter = if hi >= lo { hi + 1 - lo } else { 0 };
        inter as f32 / (f.last() + 1 - f.first() + p1 + 1 - p0 - inter) as f32
    };
    let (mut circles, mut lines) = (0, 0);
    for seed in 0..100u32 {
        let mut noise = gaussian(seed + 1, 5.0);
        let ranges: [f32; 361] = core::array::from_fn(|i| {
            let (r, _) = hit(i);
            let n = noise();
            if r.is_finite() {
                libm::roundf(r + n)
            } else {
                0.0
            }
        });
        let mut ex = Extractor::<361, 32>::new();
        assert!(ex.extract(&Scan::from_mm(g, &ranges), &config).is_ok());
        for f in ex.features() {
            let on = iou(f) >= 0.5;
            match f {
                Feature::Circle(_) if on => circles += 1,
                Feature::Line(_) if on => lines += 1,
                Feature::Circle(_) => panic!("a circle off the pillar: {f:?}"),
                _ => {}
            }
        }
    }
    assert!(
        circles >= 70 && lines <= 25,
        "circles {circles}, lines {lines}"
    );
}
