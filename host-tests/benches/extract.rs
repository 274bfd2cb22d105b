//! Criterion benches, so that speed regressions show: pfe-core's extractor (paper and default
//! configurations) on a 361-beam simulated scan, `fit_line` on 361 points, the Hyper circle fit
//! on 50 points, and the two baselines on the same scan.
//!
//! Run with `cargo bench -p host-tests --bench extract`.

use criterion::{criterion_group, criterion_main, Criterion};
use pfe_core::{fit_circle, fit_line, CircleMethod, Config, Extractor, Point, Scan};
use pfe_eval::bench::simulated_scans;
use pfe_eval::methods::baselines::{Acf, SplitMerge};
use pfe_eval::methods::Method;
use std::hint::black_box;

fn benches(c: &mut Criterion) {
    // A room with pillars (seed chosen so that the scan has both lines and circles).
    let scans = simulated_scans(8, 7);
    let scan = scans
        .iter()
        .max_by_key(|s| s.ranges_mm.iter().filter(|r| r.is_finite()).count())
        .cloned()
        .unwrap_or_else(|| simulated_scans(1, 1).remove(0));
    let (g, r) = (scan.geometry, scan.ranges_mm);

    let mut ex = Box::new(Extractor::<361, 64>::new());
    for (name, cfg) in [("paper", Config::paper()), ("default", Config::default())] {
        c.bench_function(&format!("pfe_extract_{name}_361"), |b| {
            b.iter(|| {
                let _ = ex.extract(&Scan::from_mm(g, black_box(&r)), &cfg);
                black_box(ex.features().len())
            })
        });
    }

    let line: Vec<Point> = (0..361)
        .map(|i| {
            Point::new(
                2000.0 + 0.3 * i as f32,
                -1800.0 + 10.0 * i as f32 + (i % 7) as f32,
            )
        })
        .collect();
    c.bench_function("fit_line_361", |b| b.iter(|| fit_line(black_box(&line))));

    let arc: Vec<Point> = (0..50)
        .map(|i| {
            let t = 0.04 * i as f32;
            Point::new(2000.0 + 300.0 * t.cos() + (i % 3) as f32, 300.0 * t.sin())
        })
        .collect();
    c.bench_function("fit_circle_hyper_50", |b| {
        b.iter(|| fit_circle(black_box(&arc), CircleMethod::Hyper))
    });

    let mut sm = SplitMerge::new();
    c.bench_function("split_merge_361", |b| {
        b.iter(|| black_box(sm.extract(&g, black_box(&r))))
    });
    let mut acf = Acf::new();
    c.bench_function("acf_361", |b| {
        b.iter(|| black_box(acf.extract(&g, black_box(&r))))
    });
}

criterion_group!(extract, benches);
criterion_main!(extract);
