//! Distant walls seen at grazing incidence (cm-mode LMS200, 1° beams, σ_r 10 mm, ranges to
//! 50 m): consecutive points are farther apart than any surface seen at ≥ 10° allows, so the
//! walk leaves each alone; together they lie on one line within the noise and must come out
//! as lines on the wall (all but runs of fewer than 5 such points). A row of separate posts that does not fit one line must not be joined.
//! Truth is the analytic ray casting of `common`.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

mod common;

use common::{scan, Noise, Prim};
use pfe_core::{Config, Extractor, Feature, Scan, ScanGeometry};

const SIGMA: f64 = 10.0;

fn geometry() -> ScanGeometry {
    let mut g = ScanGeometry::lms200(180.0, 1.0);
    g.r_max = 50_000.0;
    g
}

/// Ranges of `prims` with Gaussian noise σ = `SIGMA`, rounded to the cm mode's 10 mm.
fn noisy(exact: &[f32], seed: u64) -> Vec<f32> {
    let mut noise = Noise::new(seed);
    exact
        .iter()
        .map(|&x| ((f64::from(x) + SIGMA * noise.gauss()) / 10.0).round() as f32 * 10.0)
        .collect()
}

/// Exact ranges and hits of a corridor 3 m wide and 40 m long (walls 0 and 1, the end wall 2):
/// both walls seen at a few degrees beyond 10 m.
fn corridor() -> (Vec<f32>, Vec<Option<usize>>) {
    let g = geometry();
    let prims = [
        Prim::Seg(1000.0, 1500.0, 40_000.0, 1500.0),
        Prim::Seg(1000.0, -1500.0, 40_000.0, -1500.0),
        Prim::Seg(40_000.0, -1500.0, 40_000.0, 1500.0),
    ];
    let (start, step) = (f64::from(g.start_angle), f64::from(g.angle_step));
    scan(&prims, start, step, 181, 50_000.0)
}

#[test]
fn distant_corridor_walls_are_lines() {
    let g = geometry();
    let (exact, hits) = corridor();
    let config = Config::default().with_sigma_r(SIGMA as f32);
    let mut ex = Extractor::<181, 64>::new();
    let (mut far, mut covered) = (0usize, 0usize);
    for seed in 0..20 {
        let ranges = noisy(&exact, seed);
        ex.extract(&Scan::from_mm(g, &ranges), &config).unwrap();
        for (i, h) in hits.iter().enumerate() {
            // Side-wall beams beyond 8 m.
            if !matches!(h, Some(0 | 1)) || exact[i] < 8000.0 {
                continue;
            }
            far += 1;
            let on_line = ex.features().iter().any(|f| match f {
                Feature::Line(l) => {
                    let wall_y = if h == &Some(0) { 1500.0 } else { -1500.0 };
                    usize::from(l.first) <= i
                        && i <= usize::from(l.last)
                        && (f64::from(l.start.y) - wall_y).abs() < 4.0 * SIGMA
                        && (f64::from(l.end.y) - wall_y).abs() < 4.0 * SIGMA
                }
                _ => false,
            });
            covered += usize::from(on_line);
        }
    }
    assert!(far > 100, "{far} far wall beams");
    assert!(
        covered * 4 >= far * 3,
        "{covered} of {far} far wall beams in a line on their wall"
    );
}

#[test]
fn a_staggered_row_of_posts_is_not_one_line() {
    let g = geometry();
    let (start, step) = (f64::from(g.start_angle), f64::from(g.angle_step));
    // Posts 300 mm wide facing the scanner every 1.5 m along y ≈ 1500, staggered by ±150 mm:
    // each is hit by one beam or two; a wall far behind.
    let mut prims: Vec<Prim> = (0..20)
        .map(|j| {
            let x = 8000.0 + 1500.0 * f64::from(j);
            let y = 1500.0 + if j % 2 == 0 { 150.0 } else { -150.0 };
            Prim::Seg(x, y - 150.0, x, y + 150.0)
        })
        .collect();
    prims.push(Prim::Seg(45_000.0, -30_000.0, 45_000.0, 30_000.0));
    let (exact, hits) = scan(&prims, start, step, 181, 50_000.0);
    let config = Config::default().with_sigma_r(SIGMA as f32);
    let mut ex = Extractor::<181, 64>::new();
    for seed in 0..20 {
        let ranges = noisy(&exact, seed);
        ex.extract(&Scan::from_mm(g, &ranges), &config).unwrap();
        for f in ex.features() {
            let posts: std::collections::BTreeSet<usize> = (f.first()..=f.last())
                .filter_map(|i| hits[i])
                .filter(|&p| p < 20)
                .collect();
            assert!(posts.len() <= 1, "seed {seed}: {f:?} spans posts {posts:?}");
        }
    }
}

/// What joining the distant walls' points leaves, scan by scan: every segment counted once (as
/// short, degenerate, stored or dropped), each feature with mark points at its first and last
/// beam and none inside, features in beam order without overlap, the joined lines among them.
#[test]
fn joined_walls_leave_consistent_marks_and_counts() {
    let g = geometry();
    let (exact, _) = corridor();
    let config = Config::default().with_sigma_r(SIGMA as f32);
    let mut ex = Extractor::<181, 64>::new();
    let mut sparse = 0;
    for seed in 0..20 {
        let ranges = noisy(&exact, seed);
        let st = ex.extract(&Scan::from_mm(g, &ranges), &config).unwrap();
        assert_eq!(
            st.segments,
            st.short_segments + st.degenerate + st.features + st.dropped,
            "seed {seed}: {st:?}"
        );
        assert_eq!(st.features, ex.features().len());
        let marks: Vec<usize> = ex.marks().collect();
        let mut after = 0;
        for f in ex.features() {
            assert!(f.first() >= after, "seed {seed}: {f:?} overlaps");
            after = f.last() + 1;
            assert!(
                ex.is_mark(f.first()) && ex.is_mark(f.last()),
                "seed {seed}: {f:?}"
            );
            let inside: Vec<&usize> = marks
                .iter()
                .filter(|&&m| f.first() < m && m < f.last())
                .collect();
            assert!(
                inside.is_empty(),
                "seed {seed}: marks {inside:?} inside {f:?}"
            );
            // A joined line: it holds neighbouring points farther apart than one surface's at
            // ≥ 10° incidence (alone, the walk leaves each of them a segment of its own).
            if let Feature::Line(_) = f {
                let point = |i: usize| {
                    let (s, c) = (g.start_angle + g.angle_step * i as f32).sin_cos();
                    (ranges[i] * c, ranges[i] * s)
                };
                let apart = (f.first()..f.last()).any(|i| {
                    let ((x0, y0), (x1, y1)) = (point(i), point(i + 1));
                    (x1 - x0).hypot(y1 - y0) > 600.0
                });
                sparse += usize::from(apart);
            }
        }
        // Segments counted: the marks bound them (a one-point segment is one mark).
        assert!(
            st.segments <= marks.len(),
            "seed {seed}: {st:?}, {} marks",
            marks.len()
        );
    }
    assert!(sparse >= 20, "{sparse} joined lines in 20 scans");
}
