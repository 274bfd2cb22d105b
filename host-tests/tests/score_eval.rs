//! The evaluation pipeline end to end on a few scans, with methods of known behaviour.

use pfe_cli::eval::parse_args;
use pfe_core::{CircleFeature, Feature, LineFeature, Point, ScanGeometry};
use pfe_eval::methods::{Extraction, Method};
use pfe_eval::scene::{Scenario, SceneKind, SimScan, TruthKind};
use pfe_eval::{evaluate, quick_report, report, run_methods, scenarios, svg, EvalOptions};

/// Finds nothing.
struct Blind;
impl Method for Blind {
    fn name(&self) -> &str {
        "blind"
    }
    fn extract(&mut self, _: &ScanGeometry, _: &[f32]) -> Extraction {
        Extraction::default()
    }
}

/// Marks every valid point, finds no feature.
struct MarkAll;
impl Method for MarkAll {
    fn name(&self) -> &str {
        "mark-all"
    }
    fn extract(&mut self, _: &ScanGeometry, r: &[f32]) -> Extraction {
        Extraction {
            marks: (0..r.len()).filter(|&i| r[i].is_finite()).collect(),
            features: vec![],
        }
    }
}

/// `n` simulated scans of mixed scenes (σ_r = 5 mm) from `seed`.
fn mixed_scans(n: usize, seed: u64) -> Vec<SimScan> {
    scenarios(SceneKind::Mixed, n, 5.0, seed)
        .iter()
        .map(Scenario::simulate)
        .collect()
}

#[test]
fn known_methods_give_known_ratios() {
    let sims = mixed_scans(5, 3);
    let (mut a, mut b) = (Blind, MarkAll);
    let res = run_methods(&mut [&mut a, &mut b], &sims);
    let truth: usize = sims.iter().map(|s| s.truth.len()).sum();
    let marks: usize = sims.iter().map(|s| s.true_marks.len()).sum();
    let (blind, all) = (&res[0].score, &res[1].score);
    assert_eq!(blind.truth_features, truth);
    assert_eq!((blind.missed, blind.spurious, blind.matched), (truth, 0, 0));
    assert_eq!(blind.missed_ratio(), 1.0);
    // Blind omits every true mark; mark-all marks every other counted point.
    assert_eq!(blind.omitted_marks, marks);
    assert_eq!(all.omitted_marks, 0);
    assert_eq!(all.false_marks, all.points - marks);
    assert!((blind.false_mark_ratio() + all.false_mark_ratio() - 1.0).abs() < 1e-12);
}

/// Outputs, scan after scan, the ground truth of the given scans as features (exact
/// parameters), with every circle typed as a line when `swap_circles`, and one extra feature on
/// beams 0..=1 of every scan when `extra`.
struct Replay {
    truth: Vec<Vec<Feature>>,
    marks: Vec<Vec<usize>>,
    next: usize,
    extra: bool,
}

impl Replay {
    fn new(sims: &[SimScan], swap_circles: bool, extra: bool) -> Self {
        let feature = |f: &pfe_eval::scene::TruthFeature| {
            let (first, last) = (f.first as u16, f.last as u16);
            let points = last + 1 - first;
            match f.kind {
                TruthKind::Line { alpha, rho } => Feature::Line(LineFeature::new(
                    first,
                    last,
                    points,
                    alpha as f32,
                    rho as f32,
                    0.0,
                    0.0,
                    0.0,
                    Point::new(0.0, 0.0),
                    Point::new(0.0, 0.0),
                )),
                TruthKind::Circle { center, radius } if !swap_circles => {
                    Feature::Circle(CircleFeature::new(
                        first,
                        last,
                        points,
                        Point::new(center[0] as f32, center[1] as f32),
                        radius as f32,
                        [[0.0; 3]; 3],
                        0.0,
                        0.0,
                    ))
                }
                TruthKind::Circle { .. } => Feature::Line(LineFeature::new(
                    first,
                    last,
                    points,
                    0.0,
                    1000.0,
                    0.0,
                    0.0,
                    0.0,
                    Point::new(0.0, 0.0),
                    Point::new(0.0, 0.0),
                )),
            }
        };
        Self {
            truth: sims
                .iter()
                .map(|s| s.truth.iter().map(feature).collect())
                .collect(),
            marks: sims.iter().map(|s| s.true_marks.clone()).collect(),
            next: 0,
            extra,
        }
    }
}

impl Method for Replay {
    fn name(&self) -> &str {
        "replay"
    }
    fn extract(&mut self, _: &ScanGeometry, _: &[f32]) -> Extraction {
        let k = self.next % self.truth.len();
        self.next += 1;
        let mut features = self.truth[k].clone();
        if self.extra {
            features.push(Feature::Line(LineFeature::new(
                0,
                1,
                2,
                0.0,
                1.0,
                0.0,
                0.0,
                0.0,
                Point::new(0.0, 0.0),
                Point::new(0.0, 0.0),
            )));
        }
        Extraction {
            marks: self.marks[k].clone(),
            features,
        }
    }
}

#[test]
fn methods_that_output_features_are_scored_exactly() {
    let sims = mixed_scans(6, 4);
    let truth: usize = sims.iter().map(|s| s.truth.len()).sum();
    let circles: usize = sims
        .iter()
        .flat_map(|s| &s.truth)
        .filter(|f| matches!(f.kind, TruthKind::Circle { .. }))
        .count();
    assert!(
        circles > 0 && circles < truth,
        "{circles} circles of {truth}"
    );
    let (mut exact, mut swapped, mut extra) = (
        Replay::new(&sims, false, false),
        Replay::new(&sims, true, false),
        Replay::new(&sims, false, true),
    );
    let res = run_methods(&mut [&mut exact, &mut swapped, &mut extra], &sims);
    let (e, s, x) = (&res[0].score, &res[1].score, &res[2].score);
    // The truth itself: everything matched, no mark wrong, every error zero.
    assert_eq!(
        (e.matched, e.missed, e.spurious, e.predicted_features),
        (truth, 0, 0, truth)
    );
    assert_eq!(
        (e.false_marks, e.omitted_marks, e.false_iden_ratio()),
        (0, 0, 0.0)
    );
    assert_eq!(e.line_errors.len() + e.circle_errors.len(), truth);
    assert!(e
        .line_errors
        .iter()
        .all(|l| l.rho < 1e-3 && l.alpha < 1e-6 && l.crb_rho > 0.0));
    assert!(e
        .circle_errors
        .iter()
        .all(|c| c.center < 1e-3 && c.radius < 1e-3 && c.crb_radius > 0.0));
    // Circles typed as lines: matched, but every circle misidentified and without an error.
    assert_eq!(
        (s.matched, s.circles_as_lines, s.lines_as_circles),
        (truth, circles, 0)
    );
    assert!((s.false_iden_ratio() - circles as f64 / truth as f64).abs() < 1e-12);
    assert_eq!(s.circle_errors.len(), 0);
    // One extra feature per scan: spurious, nothing else changes.
    assert_eq!((x.matched, x.spurious), (truth, sims.len()));
    assert!((x.spurious_ratio() - sims.len() as f64 / truth as f64).abs() < 1e-12);
}

#[test]
fn scans_are_reproducible_and_distinct() {
    let a = scenarios(SceneKind::Mixed, 4, 5.0, 1);
    assert_eq!(a, scenarios(SceneKind::Mixed, 4, 5.0, 1));
    let seeds: std::collections::HashSet<u64> = a.iter().map(|s| s.seed).collect();
    assert_eq!(seeds.len(), 4);
    assert_ne!(a[0].seed, scenarios(SceneKind::Mixed, 1, 5.0, 2)[0].seed);
}

#[test]
fn quick_report_names_every_method() {
    let (mut a, mut b) = (Blind, MarkAll);
    let r = quick_report(&mut [&mut a, &mut b], SceneKind::Office, 3, 2.0, 1);
    assert!(r.contains("blind") && r.contains("mark-all") && r.contains("sigma_r = 2 mm"));
}

#[test]
fn report_and_plots_are_complete() {
    let options = EvalOptions {
        scans: 4,
        sweep: vec![1.0, 5.0],
        passes: 1,
        out: None,
        command: "test-command".into(),
        ..EvalOptions::default()
    };
    let mut methods: Vec<Box<dyn Method>> = vec![Box::new(Blind), Box::new(MarkAll)];
    let ev = evaluate(&mut methods, &options);
    assert_eq!(ev.sweep.len(), 2);
    assert_eq!(ev.by_kind.len(), 4);
    let md = report::markdown(&ev);
    assert!(md.contains("Generated by `test-command`") && md.contains("Seed **1**"));
    assert!(md.contains("| blind |") && md.contains("| mark-all |"));
    for s in [
        svg::errors_vs_noise(&ev),
        svg::ratios_vs_noise(&ev),
        svg::time_per_scan(&ev),
    ] {
        assert!(s.starts_with("<svg") && s.trim_end().ends_with("</svg>"));
        assert!(!s.contains("NaN") && !s.contains("inf"));
    }
}

#[test]
fn arguments_parse() {
    let args: Vec<String> = [
        "--scans",
        "7",
        "--sweep",
        "1,3",
        "--kind",
        "corridor",
        "--no-write",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let o = parse_args(&args).unwrap().unwrap();
    assert_eq!(
        (o.scans, o.sweep.clone(), o.kind, o.out),
        (7, vec![1.0, 3.0], SceneKind::Corridor, None)
    );
    assert!(parse_args(&["--help".to_string()]).unwrap().is_none());
    assert!(parse_args(&["--bogus".to_string()]).is_err());
    assert!(parse_args(&["--scans".to_string(), "0".to_string()]).is_err());
}
