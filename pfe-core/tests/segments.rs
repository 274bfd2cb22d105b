//! The segment step's accounting, on the board's path (`scrutiny` off), the host's and the
//! paper's: every segment is counted once as short, degenerate, stored or dropped; every
//! feature has at least `min_points` points and mark points at both ends; thin posts in front
//! of a wall (a range jump on both sides, 2–3 beams) are short segments. Truth is the analytic
//! ray casting of `common`.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

mod common;

use common::{runs, scan, Noise, Prim};
use pfe_core::{Config, Extractor, Scan, ScanGeometry};

/// A wall 3 m ahead and `posts` square posts 30 mm wide at 1.5 m in front of it.
fn scene(posts: usize) -> Vec<Prim> {
    let mut prims = vec![Prim::Seg(3000.0, -6000.0, 3000.0, 6000.0)];
    for k in 0..posts {
        let y = -900.0 + 400.0 * k as f64;
        prims.push(Prim::Seg(1500.0, y, 1500.0, y + 30.0));
    }
    prims
}

/// The board's path (`scrutiny` off), the host's and the paper's.
const PATHS: [(&str, Config); 3] = [
    ("board", Config::default_config().with_scrutiny(false)),
    ("host", Config::default_config()),
    ("paper", Config::paper()),
];

#[test]
fn every_segment_is_counted_once_on_every_path() {
    let g = ScanGeometry::LMS200_180_050;
    let mut ex = Extractor::<361, 64>::new();
    for (name, config) in PATHS {
        let mut shorts = 0;
        for seed in 0..10u64 {
            let (exact, hits) = scan(
                &scene(5),
                f64::from(g.start_angle),
                f64::from(g.angle_step),
                361,
                f64::from(g.r_max),
            );
            // The posts: runs of 1–3 beams (the wall's runs between them are long).
            let posts = runs(&hits, 1)
                .iter()
                .filter(|(a, b, p)| *p > 0 && b + 1 - a <= 3)
                .count();
            assert_eq!(posts, 5);
            let mut noise = Noise::new(seed);
            let ranges: Vec<f32> = exact
                .iter()
                .map(|&r| (f64::from(r) + 3.0 * noise.gauss()) as f32)
                .collect();
            let st = ex.extract(&Scan::from_mm(g, &ranges), &config).unwrap();
            assert_eq!(
                st.segments,
                st.short_segments + st.degenerate + st.features + st.dropped,
                "{name} seed {seed}: {st:?}"
            );
            assert_eq!(st.features, ex.features().len(), "{name}");
            assert_eq!(st.dropped, 0, "{name}");
            for f in ex.features() {
                assert!(
                    f.last() + 1 - f.first() >= config.min_points,
                    "{name}: {f:?}"
                );
                assert!(
                    ex.is_mark(f.first()) && ex.is_mark(f.last()),
                    "{name}: {f:?}"
                );
            }
            // The wall: lines between the posts' shadows, at least one a gap.
            assert!(ex.features().len() >= 6, "{name} seed {seed}: {st:?}");
            shorts += st.short_segments;
        }
        // The posts (2–3 beams, jumps on both sides) come out as short segments.
        assert!(
            shorts >= 25,
            "{name}: {shorts} short segments in 10 scans of 5 posts"
        );
    }
}

#[test]
fn a_post_of_min_points_beams_is_a_feature_on_every_path() {
    let g = ScanGeometry::LMS200_180_050;
    // A post face 45 mm wide at 1.5 m, square to the beams about bearing 0: 4 beams.
    let prims = [
        Prim::Seg(3000.0, -6000.0, 3000.0, 6000.0),
        Prim::Seg(1500.0, -27.0, 1500.0, 19.0),
    ];
    let (exact, hits) = scan(
        &prims,
        f64::from(g.start_angle),
        f64::from(g.angle_step),
        361,
        f64::from(g.r_max),
    );
    let post: Vec<usize> = (0..361).filter(|&i| hits[i] == Some(1)).collect();
    assert_eq!(post.len(), 4, "{post:?}");
    let (first, last) = (post[0], post[3]);
    let mut ex = Extractor::<361, 64>::new();
    for (name, config) in PATHS {
        assert_eq!(config.min_points, 4);
        let mut noise = Noise::new(3);
        let ranges: Vec<f32> = exact
            .iter()
            .map(|&r| (f64::from(r) + 1.0 * noise.gauss()) as f32)
            .collect();
        ex.extract(&Scan::from_mm(g, &ranges), &config).unwrap();
        assert!(
            ex.features()
                .iter()
                .any(|f| f.first() == first && f.last() == last),
            "{name}: no feature on beams {first}..={last}: {:?}",
            ex.features()
        );
    }
}
