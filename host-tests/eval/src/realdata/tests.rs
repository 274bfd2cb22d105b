//! The frame change, matching and NIS on a simulated scene seen from two known poses, where
//! the truth is known: consistent covariances must give NIS medians near the χ²₂ median.
//!
//! Features are fitted on the true segments (pfe-core's fits and range-noise covariances), so
//! the test checks the benchmark's arithmetic, not an extractor's segmentation.

use pfe_core::{
    circle_feature, fit_circle, fit_line, line_feature, refine_circle, CircleMethod, Feature, Point,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::compare::{PairTally, Seen};
use super::report::CHI2_2_MEDIAN;
use crate::scene::{render, Scenario, SceneKind, Shape, TruthKind};
use crate::score::quantile;

const SIGMA_R: f32 = 5.0;

/// A 9 m × 7 m room with a box and three pillars, in mm.
fn room() -> Vec<Shape> {
    let seg = |a: [f64; 2], b: [f64; 2]| Shape::Segment { a, b };
    let pillar = |x: f64, y: f64, r: f64| Shape::Circle {
        center: [x, y],
        radius: r,
    };
    vec![
        seg([0.0, 0.0], [9000.0, 0.0]),
        seg([9000.0, 0.0], [9000.0, 7000.0]),
        seg([9000.0, 7000.0], [0.0, 7000.0]),
        seg([0.0, 7000.0], [0.0, 0.0]),
        seg([6000.0, 1000.0], [7500.0, 1000.0]),
        seg([7500.0, 1000.0], [7500.0, 2200.0]),
        seg([7500.0, 2200.0], [6000.0, 2200.0]),
        seg([6000.0, 2200.0], [6000.0, 1000.0]),
        pillar(2500.0, 5000.0, 300.0),
        pillar(6500.0, 5200.0, 400.0),
        pillar(4200.0, 1600.0, 250.0),
    ]
}

/// The features of the true segments of one scan from `pose` (x mm, y mm, θ rad).
fn features_from(pose: [f64; 3], rng: &mut ChaCha8Rng) -> Vec<Feature> {
    let shapes: Vec<Shape> = room().iter().map(|s| s.to_frame(pose)).collect();
    let scenario = Scenario::new(SceneKind::Office, 0).with_sigma(SIGMA_R);
    let sim = render(&shapes, &scenario, rng);
    let points = sim.points();
    let origin = Point::new(0.0, 0.0);
    sim.truth
        .iter()
        .filter_map(|t| {
            let pts: Vec<Point> = points
                .get(t.first..=t.last)?
                .iter()
                .map(|p| p.unwrap_or(Point::INVALID))
                .collect();
            match t.kind {
                TruthKind::Line { .. } => line_feature(
                    &pts,
                    t.first,
                    t.last,
                    &fit_line(&pts).ok()?,
                    origin,
                    SIGMA_R,
                ),
                TruthKind::Circle { .. } if pts.len() >= 8 => {
                    let c =
                        refine_circle(&pts, fit_circle(&pts, CircleMethod::Hyper).ok()?, 5).ok()?;
                    circle_feature(&pts, t.first, t.last, &c, origin, SIGMA_R)
                }
                TruthKind::Circle { .. } => None,
            }
        })
        .collect()
}

/// `pairs` independent pairs of scans: a pose in the room, then one up to 1 m further and up
/// to 0.3 rad turned; the second pose given to the benchmark is off by `pose_error`.
fn simulate(pairs: usize, pose_error: [f64; 3]) -> Vec<(Seen, Seen)> {
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    (0..pairs)
        .map(|_| {
            let a = [
                rng.gen_range(1000.0..4500.0),
                rng.gen_range(2800.0..4200.0),
                rng.gen_range(-std::f64::consts::PI..std::f64::consts::PI),
            ];
            let step = rng.gen_range(0.0..1000.0);
            let b = [
                a[0] + step * a[2].cos(),
                a[1] + step * a[2].sin(),
                a[2] + rng.gen_range(-0.3..0.3),
            ];
            let fa = features_from(a, &mut rng);
            let fb = features_from(b, &mut rng);
            let b_told = [
                b[0] + pose_error[0],
                b[1] + pose_error[1],
                b[2] + pose_error[2],
            ];
            (Seen::new(a, &fa), Seen::new(b_told, &fb))
        })
        .collect()
}

fn tally(pairs: &[(Seen, Seen)], scale: f64) -> PairTally {
    let mut t = PairTally::default();
    for (a, b) in pairs {
        t.add(&a.scaled(scale), &b.scaled(scale));
    }
    t
}

/// Sample size and tolerance: the median of n draws of a χ²₂ (density ¼ at its median) has a
/// standard error of 1 / (2 · ¼ · √n) = 2/√n (0.1 at the smallest sample allowed, 400); the
/// tolerance is 3 standard errors plus 0.05 for the first-order covariances. A covariance 4×
/// too large puts the median at 0.35, 4× too small at 5.5: both far outside.
const MIN_SAMPLES: usize = 400;

fn consistent(nis: &[f64]) -> bool {
    let tolerance = 3.0 * 2.0 / (nis.len() as f64).sqrt() + 0.05;
    nis.len() >= MIN_SAMPLES && (quantile(nis, 0.5) - CHI2_2_MEDIAN).abs() <= tolerance
}

#[test]
fn line_nis_is_chi2_with_exact_poses_and_fails_with_scaled_covariances() {
    let pairs = simulate(300, [0.0; 3]);
    let t = tally(&pairs, 1.0);
    assert!(
        t.line_points_matched as f64 >= 0.9 * t.line_points as f64,
        "lines should re-appear: {} of {} points",
        t.line_points_matched,
        t.line_points
    );
    assert!(
        consistent(&t.nis),
        "n {} median {}",
        t.nis.len(),
        quantile(&t.nis, 0.5)
    );
    assert!(!consistent(&tally(&pairs, 4.0).nis));
    assert!(!consistent(&tally(&pairs, 0.25).nis));
}

#[test]
fn circle_centre_nis_is_chi2_with_exact_poses_and_fails_with_scaled_covariances() {
    let pairs = simulate(300, [0.0; 3]);
    let t = tally(&pairs, 1.0);
    // Some pillars are seen by too few beams in the second scan (or hidden) to be fitted.
    assert!(t.circles_matched as f64 >= 0.75 * t.circles as f64);
    let median = quantile(&t.circle_nis, 0.5);
    assert!(
        consistent(&t.circle_nis),
        "n {} median {median}",
        t.circle_nis.len()
    );
    assert!(!consistent(&tally(&pairs, 4.0).circle_nis));
}

#[test]
fn the_pose_refit_removes_a_pose_error() {
    let exact = tally(&simulate(150, [0.0; 3]), 1.0);
    let off = tally(&simulate(150, [30.0, -20.0, 0.01]), 1.0);
    let (raw, refit) = (quantile(&off.nis, 0.5), quantile(&off.nis_refit, 0.5));
    let refit_exact = quantile(&exact.nis_refit, 0.5);
    assert!(raw > 20.0, "a 36 mm / 10 mrad pose error must show: {raw}");
    assert!(exact.refits >= 100 && off.refits == exact.refits);
    assert!(
        (refit / refit_exact - 1.0).abs() < 0.05,
        "refit {refit} vs {refit_exact} with exact poses"
    );
    // Fewer degrees of freedom after the refit: below the χ²₂ median, but not far.
    assert!(
        refit_exact < CHI2_2_MEDIAN && refit_exact > 0.5,
        "{refit_exact}"
    );
}

#[test]
fn the_lines_pose_refit_removes_a_pose_error_from_the_circles() {
    let exact = tally(&simulate(150, [0.0; 3]), 1.0);
    let off = tally(&simulate(150, [30.0, -20.0, 0.01]), 1.0);
    let raw = quantile(&off.circle_nis, 0.5);
    let (refit, refit_exact) = (
        quantile(&off.circle_nis_refit, 0.5),
        quantile(&exact.circle_nis_refit, 0.5),
    );
    assert!(raw > 20.0, "a 36 mm / 10 mrad pose error must show: {raw}");
    assert!(!off.circle_nis_refit.is_empty());
    assert_eq!(off.circle_nis_refit.len(), exact.circle_nis_refit.len());
    // The refit is fitted to the lines, whose noise it carries into the circles (not in
    // their covariance): near the exact poses' figure, a little above the χ²₂ median.
    assert!(
        (refit / refit_exact - 1.0).abs() < 0.25,
        "refit {refit} vs {refit_exact} with exact poses"
    );
    assert!(
        refit_exact > CHI2_2_MEDIAN && refit_exact < 1.5 * CHI2_2_MEDIAN,
        "{refit_exact}"
    );
}

/// A method that finds nothing.
struct Blind;

impl crate::methods::Method for Blind {
    fn name(&self) -> &str {
        "blind"
    }
    fn extract(&mut self, _: &pfe_core::ScanGeometry, _: &[f32]) -> crate::methods::Extraction {
        crate::methods::Extraction::default()
    }
}

#[test]
fn the_run_compares_pfe_default_with_each_method_on_the_beams_both_hold() {
    // The room seen from three poses 0.3 m apart, given exactly; the box (shapes 4..=7) is
    // taken away before the third scan, so only its lines of the second scan are not found
    // again.
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let poses = [
        [3000.0, 3500.0, 0.0],
        [3300.0, 3500.0, 0.05],
        [3600.0, 3600.0, 0.1],
    ];
    let box_shapes = 4..=7;
    let scenario = Scenario::new(SceneKind::Office, 0).with_sigma(SIGMA_R);
    let mut box_beams = Vec::new();
    let records: Vec<_> = poses
        .iter()
        .enumerate()
        .map(|(k, &pose)| {
            let shapes: Vec<Shape> = room()
                .iter()
                .enumerate()
                .filter(|(s, _)| k < 2 || !box_shapes.contains(s))
                .map(|(_, s)| s.to_frame(pose))
                .collect();
            let sim = render(&shapes, &scenario, &mut rng);
            // Shape ids index the shapes rendered: the box's hold while it is there.
            let on_box = |p: &Option<usize>| k < 2 && p.is_some_and(|p| box_shapes.contains(&p));
            box_beams.push(sim.beam_primitive.iter().filter(|p| on_box(p)).count());
            pfe_formats::Record {
                id: k as u64,
                geometry: sim.geometry,
                ranges_mm: sim.ranges_mm,
                time: None,
                pose: Some([pose[0] / 1000.0, pose[1] / 1000.0, pose[2]]),
                sweeps: None,
            }
        })
        .collect();
    // pfe-default's beams in lines of ≥ 10 points in scans 0 and 1 (the first of each pair),
    // counted here from its features.
    let mut default = super::methods(SIGMA_R).remove(0);
    let in_lines: usize = records
        .iter()
        .take(2)
        .map(|r| {
            let context = super::context_of(r, Some(1));
            let ex = default.extract_in(&r.geometry, &r.ranges_mm, &context);
            let mut held = vec![false; r.ranges_mm.len()];
            for f in &ex.features {
                if let Feature::Line(l) = f {
                    if usize::from(l.points) >= super::compare::MIN_LINE_POINTS {
                        let span = usize::from(l.first)..=usize::from(l.last);
                        held.iter_mut()
                            .take(*span.end() + 1)
                            .skip(*span.start())
                            .for_each(|h| *h = true);
                    }
                }
            }
            held.iter().filter(|&&h| h).count()
        })
        .collect::<Vec<_>>()
        .iter()
        .sum();
    let mut methods = super::methods(SIGMA_R);
    methods.truncate(1);
    methods.push(Box::new(Blind));
    methods.push(super::methods(SIGMA_R).remove(0));
    let r = super::run_records(
        "room",
        records.into_iter().map(Ok),
        &mut methods,
        0,
        super::Told {
            sweeps: Some(1),
            ..super::Told::default()
        },
    )
    .unwrap();
    let [blind, twin] = &r.shared[..] else {
        panic!("{:?}", r.shared);
    };
    assert_eq!(
        (blind.method.as_str(), twin.method.as_str()),
        ("blind", "pfe-default")
    );
    // Against a method that finds nothing, every beam of pfe-default's lines is its alone.
    assert!(in_lines > 300, "{in_lines}");
    assert_eq!(
        (blind.only_reference, blind.both, blind.only_other),
        (in_lines, 0, 0)
    );
    // Against itself, every such beam is shared and found again alike.
    assert_eq!(
        (twin.both, twin.only_reference, twin.only_other),
        (in_lines, 0, 0)
    );
    assert_eq!(twin.both_reference_refound, twin.both_other_refound);
    assert_eq!(blind.only_reference_refound, twin.both_reference_refound);
    // What is not found again is the box, seen in scan 1 and gone from scan 2 (a line's span
    // may reach a beam or two past it).
    let lost = blind.only_reference - blind.only_reference_refound;
    assert!(
        lost > box_beams[1] / 2 && lost <= box_beams[1] + 4,
        "{lost} {box_beams:?}"
    );
}

/// A scan's declared sweeps: `--sweeps` first, then the record's own (a CARMEN line of a
/// scanner that is not a SICK LMS says 1), then an LMS2xx's for the step (2 at 0.5°).
#[test]
fn the_sweeps_told_are_the_options_then_the_records_then_the_lms2xx_rule() {
    let record = |sweeps: Option<u8>| pfe_formats::Record {
        id: 0,
        geometry: pfe_core::ScanGeometry::lms200(180.0, 0.5),
        ranges_mm: vec![1000.0; 361],
        time: None,
        pose: None,
        sweeps,
    };
    assert_eq!(super::context_of(&record(None), None).sweeps, 2);
    assert_eq!(super::context_of(&record(Some(1)), None).sweeps, 1);
    assert_eq!(super::context_of(&record(Some(1)), Some(4)).sweeps, 4);
    assert_eq!(super::context_of(&record(None), Some(1)).sweeps, 1);
}

/// A method that notes the odometry it is told and finds nothing.
struct Probe(std::rc::Rc<std::cell::RefCell<Vec<Option<pfe_core::Motion>>>>);

impl crate::methods::Method for Probe {
    fn name(&self) -> &str {
        "probe"
    }
    fn extract(&mut self, _: &pfe_core::ScanGeometry, _: &[f32]) -> crate::methods::Extraction {
        crate::methods::Extraction::default()
    }
    fn extract_in(
        &mut self,
        _: &pfe_core::ScanGeometry,
        _: &[f32],
        context: &crate::methods::ScanContext,
    ) -> crate::methods::Extraction {
        self.0.borrow_mut().push(context.odometry);
        crate::methods::Extraction::default()
    }
}

/// With `odometry_from_poses` each scan with a neighbour on both sides at most
/// `ODOMETRY_SPAN_S` apart is told the motion between them (0.4 m/s along the heading, 0.3
/// rad/s, 0.5° LMS2xx timing); the first and last scans, a scan after a gap, and every scan
/// without the option are told none.
#[test]
fn odometry_from_poses_is_the_motion_between_the_neighbours() {
    let record = |k: usize, t: f64| {
        let th = 0.3 * t;
        pfe_formats::Record {
            id: k as u64,
            geometry: pfe_core::ScanGeometry::lms200(180.0, 0.5),
            ranges_mm: vec![2000.0; 361],
            time: Some(t),
            // 0.4 m/s along the heading θ = 0.3 t (and 0.12 t m/s across it): the chord between
            // the neighbours, projected on the heading, gives 0.4 m/s within 2 mm/s.
            pose: Some([0.4 * t * th.cos(), 0.4 * t * th.sin(), th]),
            sweeps: None,
        }
    };
    // Scans 0.25 s apart, then a 3 s gap before the last two.
    let times = [0.0, 0.25, 0.5, 0.75, 3.75, 4.0];
    let run = |told: super::Told| {
        let seen = std::rc::Rc::new(std::cell::RefCell::new(Vec::new()));
        let mut methods: Vec<Box<dyn crate::methods::Method>> = vec![Box::new(Probe(seen.clone()))];
        let records = times.iter().enumerate().map(|(k, &t)| Ok(record(k, t)));
        super::run_records("probe", records, &mut methods, 0, told).unwrap();
        let v = seen.borrow().clone();
        v
    };
    let told = run(super::Told {
        odometry_from_poses: true,
        ..super::Told::default()
    });
    let given: Vec<bool> = told.iter().map(Option::is_some).collect();
    assert_eq!(given, [false, true, true, false, false, false]);
    for m in told.iter().flatten() {
        assert!(
            (m.v - 400.0).abs() < 2.0 && (m.omega - 0.3).abs() < 1e-4,
            "{m:?}"
        );
        assert_eq!(m.timing, pfe_core::BeamTiming::lms2xx(0.5));
    }
    assert!(run(super::Told::default()).iter().all(Option::is_none));
}

/// The static objects' NIS: a post seen from a moving scanner counts, with its noise giving a
/// NIS near the χ²₂ median; a person keeping pace with the scanner (the same place in its
/// frame) and two posts closer than the gate (which of them is which cannot be told) do not.
#[test]
fn static_objects_are_posts_not_companions_nor_a_railing() {
    use super::statics::Statics;
    use super::CircleObs;
    let sigma = 20.0f64;
    let obj = |c: [f64; 2]| CircleObs {
        center: c,
        cov: [[sigma * sigma, 0.0], [0.0, sigma * sigma]],
        radius: 30.0,
    };
    let mut rng = ChaCha8Rng::seed_from_u64(39);
    let mut gauss = || {
        let (u, v): (f64, f64) = (rng.gen::<f64>().max(1e-12), rng.gen());
        sigma * (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    };
    let (mut post, mut companion, mut railing) =
        (Statics::default(), Statics::default(), Statics::default());
    for k in 0..400 {
        // The scanner drives along x at 0.2 m a scan, turning slowly.
        let x = 200.0 * f64::from(k % 40);
        let th = 0.01 * f64::from(k % 40);
        let pose = [x, 0.0, th];
        // A world point in the scanner's frame.
        let local = |w: [f64; 2]| {
            let (s, c) = th.sin_cos();
            let d = [w[0] - x, w[1]];
            [c * d[0] + s * d[1], -s * d[0] + c * d[1]]
        };
        let at = local([4000.0, 1500.0]);
        post.scan(&Seen {
            pose,
            objects: vec![obj([at[0] + gauss(), at[1] + gauss()])],
            ..Seen::default()
        });
        companion.scan(&Seen {
            pose,
            objects: vec![obj([800.0 + gauss(), -600.0 + gauss()])],
            ..Seen::default()
        });
        let (a, b) = (local([4000.0, 1500.0]), local([4200.0, 1500.0]));
        railing.scan(&Seen {
            pose,
            objects: vec![obj(a), obj(b)],
            ..Seen::default()
        });
    }
    let nis = post.nis();
    assert!(nis.len() > 300, "{}", nis.len());
    let m = quantile(&nis, 0.5);
    assert!((m - CHI2_2_MEDIAN).abs() < 0.3, "post: median NIS {m}");
    assert!(companion.nis().is_empty(), "{:?}", companion.nis().len());
    assert!(railing.nis().is_empty(), "{:?}", railing.nis().len());
}
