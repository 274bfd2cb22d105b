//! Interleaved sweeps without odometry (LMS200 at 0.5° and 0.25°) against analytic truth:
//! rooms with a pillar ray-cast with sweep `s` taken from the pose a robot at 0.6 m/s turning
//! at 0.45 rad/s reaches `s` mirror turns later (8 mm and 6 mrad a turn).
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

mod common;

use common::{cast, Noise, Prim};
use pfe_core::sweeps::{estimate, SweepOffset};
use pfe_core::{BeamTiming, Config, Extractor, Feature, Motion, Point, Scan, ScanGeometry};

/// The robot's motion between sweeps: 0.6 m/s, 0.45 rad/s.
fn motion(resolution_deg: f32) -> Motion {
    Motion {
        v: 600.0,
        omega: 0.45,
        timing: BeamTiming::lms2xx(resolution_deg),
    }
}

/// A room `w × h` mm with a pillar, seen from (`x`, `y`) heading `th`: primitives in the
/// frame of sweep 0. Walls as (ρ, α) too.
struct Room {
    prims: Vec<Prim>,
    walls: Vec<(f64, f64)>,
}

/// [`common::room`] with its walls as (ρ, α).
fn room(noise: &mut Noise) -> Room {
    let prims = common::room(noise);
    let walls = prims
        .iter()
        .filter_map(|p| match *p {
            // Normal from the origin to the wall.
            Prim::Seg(x0, y0, x1, y1) => {
                let (ex, ey) = (x1 - x0, y1 - y0);
                let len = ex.hypot(ey);
                let (mut nx, mut ny) = (-ey / len, ex / len);
                let mut rho = x0 * nx + y0 * ny;
                if rho < 0.0 {
                    (nx, ny, rho) = (-nx, -ny, -rho);
                }
                Some((rho, ny.atan2(nx)))
            }
            Prim::Circle(..) => None,
        })
        .collect();
    Room { prims, walls }
}

/// Ranges of the scan of `prims` with beam `i` from the pose of sweep `i mod S`
/// (`pose(s)` in the frame of sweep 0), σ_r Gaussian noise, and the primitive each hits.
fn render(
    prims: &[Prim],
    g: ScanGeometry,
    n: usize,
    sweeps: usize,
    pose: impl Fn(usize) -> (f64, f64, f64),
    sigma: f64,
    noise: &mut Noise,
) -> (Vec<f32>, Vec<Option<usize>>) {
    let moved: Vec<Vec<Prim>> = (0..sweeps)
        .map(|s| common::seen_from(prims, pose(s)))
        .collect();
    (0..n)
        .map(|i| {
            let b = f64::from(g.bearing(i));
            match cast(&moved[i % sweeps], b) {
                Some((t, p)) if t < 7900.0 => ((t + sigma * noise.gauss()) as f32, Some(p)),
                _ => (f32::NAN, None),
            }
        })
        .unzip()
}

/// The LMS200 variant at `res` degrees: geometry, beams, sweeps.
fn variant(res: f32) -> (ScanGeometry, usize, usize) {
    if res < 0.375 {
        (ScanGeometry::lms200(100.0, 0.25), 401, 4)
    } else {
        (ScanGeometry::LMS200_180_050, 361, 2)
    }
}

/// Sweep `s`'s pose in the frame of sweep 0 under [`motion`].
fn sweep_pose(res: f32) -> impl Fn(usize) -> (f64, f64, f64) {
    let m = motion(res);
    move |s| {
        let p = m.pose_at(s as f32 * BeamTiming::LMS2XX_TURN);
        (
            f64::from(p.origin.x),
            f64::from(p.origin.y),
            f64::from(p.theta),
        )
    }
}

fn points(g: ScanGeometry, ranges: &[f32]) -> Vec<Point> {
    (0..ranges.len())
        .map(|i| Scan::from_mm(g, ranges).point(i).unwrap_or(Point::INVALID))
        .collect()
}

/// Noise-free: every sweep's offset within 0.3 mm (0.7 mm at 0.25°, where
/// sweeps are up to 24 mm and 18 mrad apart) and 0.3 mrad, at 0.5° and 0.25°.
#[test]
fn the_offset_is_recovered_without_noise() {
    let mut noise = Noise::new(3);
    for res in [0.5f32, 0.25] {
        let (g, n, sweeps) = variant(res);
        let truth = sweep_pose(res);
        for k in 0..20 {
            let room = room(&mut noise);
            let (ranges, _) = render(&room.prims, g, n, sweeps, &truth, 0.0, &mut noise);
            let pts = points(g, &ranges);
            for s in 1..sweeps {
                let e = estimate(&pts, sweeps, s, g.angle_step)
                    .unwrap_or_else(|| panic!("{res}° room {k} sweep {s}: no estimate"));
                let (x, y, th) = truth(s);
                let err = (
                    f64::from(e.dx) - x,
                    f64::from(e.dy) - y,
                    f64::from(e.dtheta) - th,
                );
                // At 0.25° sweeps are up to 24 mm and 18 mrad apart over a 100° field:
                // second-order terms add a bit.
                let tol = if sweeps == 4 { 0.7 } else { 0.3 };
                assert!(
                    err.0.abs() < tol && err.1.abs() < tol && err.2.abs() < 3e-4,
                    "{res}° room {k} sweep {s}: error {err:?}, {e:?}"
                );
                assert!(e.is_significant(), "{e:?}");
            }
        }
    }
}

/// σ_r = 5 mm, 300 rooms: the errors are unbiased and as large as the stated standard errors
/// (RMS of error / sd between 0.7 and 1.5 for each unknown).
#[test]
fn the_offset_is_within_its_stated_error() {
    let mut noise = Noise::new(11);
    let (g, n, sweeps) = variant(0.5);
    let truth = sweep_pose(0.5);
    let (x, y, th) = truth(1);
    let mut z2 = [0.0f64; 3];
    let mut sum = [0.0f64; 3];
    let mut count = 0;
    for _ in 0..300 {
        let room = room(&mut noise);
        let (ranges, _) = render(&room.prims, g, n, sweeps, &truth, 5.0, &mut noise);
        let Some(e) = estimate(&points(g, &ranges), sweeps, 1, g.angle_step) else {
            continue;
        };
        let err = [
            f64::from(e.dx) - x,
            f64::from(e.dy) - y,
            f64::from(e.dtheta) - th,
        ];
        for k in 0..3 {
            z2[k] += (err[k] / f64::from(e.sd[k])).powi(2);
            sum[k] += err[k] / f64::from(e.sd[k]);
        }
        count += 1;
    }
    assert!(count > 280, "{count} estimates");
    for k in 0..3 {
        let rms = (z2[k] / f64::from(count)).sqrt();
        let mean = sum[k] / f64::from(count);
        println!("unknown {k}: RMS error/sd {rms:.2}, mean {mean:.2}");
        assert!((0.7..1.5).contains(&rms), "unknown {k}: RMS error/sd {rms}");
        assert!(mean.abs() < 0.3, "unknown {k}: mean error/sd {mean}");
    }
}

/// Marks and features of a scan (σ_r = 5 mm), with the number of sweeps declared.
fn extract(
    ex: &mut Extractor<401, 128>,
    g: ScanGeometry,
    ranges: &[f32],
    sweeps: u8,
) -> (Vec<usize>, Vec<Feature>, pfe_core::Stats) {
    extract_with(ex, g, ranges, sweeps, &Config::default().with_sigma_r(5.0))
}

/// Marks and features of a scan under `config`, with the number of sweeps declared.
fn extract_with(
    ex: &mut Extractor<401, 128>,
    g: ScanGeometry,
    ranges: &[f32],
    sweeps: u8,
    config: &Config,
) -> (Vec<usize>, Vec<Feature>, pfe_core::Stats) {
    let stats = ex
        .extract(&Scan::from_mm(g, ranges).with_sweeps(sweeps), config)
        .unwrap();
    (ex.marks().collect(), ex.features().to_vec(), stats)
}

/// A static scan declared as 2 or 4 sweeps gives what it gives as one sweep, bit for bit.
#[test]
fn a_static_scan_is_unchanged() {
    let mut noise = Noise::new(5);
    let mut ex = Extractor::<401, 128>::new();
    for res in [0.5f32, 0.25] {
        let (g, n, sweeps) = variant(res);
        for _ in 0..50 {
            let room = room(&mut noise);
            let (ranges, _) = render(&room.prims, g, n, 1, |_| (0.0, 0.0, 0.0), 5.0, &mut noise);
            let one = extract(&mut ex, g, &ranges, 1);
            let many = extract(&mut ex, g, &ranges, sweeps as u8);
            assert_eq!(one, many);
        }
    }
}

/// Scores of one extraction against the truth: (false marks, valid points, truth runs
/// missed, truth runs, spurious features, features).
#[derive(Default, Debug)]
struct Score {
    false_marks: usize,
    valid: usize,
    missed: usize,
    truth: usize,
    spurious: usize,
    features: usize,
}

/// Scores marks and features: a mark is false when no primitive change is within 2 beams; a
/// truth run (≥ 10 beams on one primitive) is missed when no feature covers half of it; a
/// feature is spurious when half of it is on no single run.
fn score(hits: &[Option<usize>], marks: &[usize], features: &[Feature], s: &mut Score) {
    let change = |i: usize| {
        (i.saturating_sub(2)..=(i + 2).min(hits.len() - 1)).any(|k| {
            k == 0 || k + 1 == hits.len() || hits[k] != hits[k - 1] || hits[k] != hits[k + 1]
        })
    };
    s.valid += hits.iter().flatten().count();
    s.false_marks += marks.iter().filter(|&&i| !change(i)).count();
    let runs = common::runs(hits, 10);
    let span = |f: &Feature| match f {
        Feature::Line(l) => (usize::from(l.first), usize::from(l.last)),
        _ => (f.first(), f.last()),
    };
    let overlap =
        |a: (usize, usize), b: (usize, usize)| (a.1.min(b.1) + 1).saturating_sub(a.0.max(b.0));
    for r in &runs {
        s.truth += 1;
        let len = r.1 + 1 - r.0;
        if !features
            .iter()
            .any(|f| 2 * overlap(span(f), (r.0, r.1)) >= len)
        {
            s.missed += 1;
        }
    }
    for f in features {
        s.features += 1;
        let (a, b) = span(f);
        if !runs
            .iter()
            .any(|r| 2 * overlap((a, b), (r.0, r.1)) >= b + 1 - a)
        {
            s.spurious += 1;
        }
    }
}

/// 8 mm / 6 mrad between sweeps, σ_r = 5 mm, no odometry: declared sweeps meet the issue's
/// targets (false marks ≤ 2 %, missed ≤ 8 %, spurious ≤ 5 %), and (for 95 % of them) every
/// run of ≥ 30 beams on a wall gives one line, with ρ and α within 4 of its standard
/// deviations (plus 1 mm / 1 mrad), less than half as many failing as with one sweep.
#[test]
fn declared_sweeps_hold_up_under_interleaving() {
    let mut ex = Extractor::<401, 128>::new();
    for res in [0.5f32, 0.25] {
        let mut noise = Noise::new(21);
        let (g, n, sweeps) = variant(res);
        let truth = sweep_pose(res);
        let (mut plain, mut declared) = (Score::default(), Score::default());
        let (mut walls, mut bad_walls, mut plain_bad, mut aligned) = (0, 0, 0, 0);
        for _ in 0..100 {
            let room = room(&mut noise);
            let (ranges, hits) = render(&room.prims, g, n, sweeps, &truth, 5.0, &mut noise);
            let (marks, plain_features, _) = extract(&mut ex, g, &ranges, 1);
            score(&hits, &marks, &plain_features, &mut plain);
            let (marks, features, stats) = extract(&mut ex, g, &ranges, sweeps as u8);
            // Aligned when the scatter or the walk's marks asked for it: all sweeps or none.
            assert!([0, sweeps - 1].contains(&stats.sweeps_aligned));
            aligned += usize::from(stats.sweeps_aligned > 0);
            score(&hits, &marks, &features, &mut declared);
            let (w, bad) = wall_lines(&room, &hits, &features);
            walls += w;
            bad_walls += bad;
            plain_bad += wall_lines(&room, &hits, &plain_features).1;
        }
        let pct = |a: usize, b: usize| 100.0 * a as f64 / b.max(1) as f64;
        for (name, s) in [("1 sweep", &plain), ("declared", &declared)] {
            println!(
                "{res}° {name}: false marks {:.1} %, missed {:.1} %, spurious {:.1} %",
                pct(s.false_marks, s.valid),
                pct(s.missed, s.truth),
                pct(s.spurious, s.features)
            );
        }
        println!("{res}°: {bad_walls} of {walls} walls without exactly one good line ({plain_bad} as 1 sweep), {aligned} of 100 scans aligned");
        assert!(
            pct(declared.false_marks, declared.valid) <= 2.0,
            "{declared:?}"
        );
        assert!(pct(declared.missed, declared.truth) <= 8.0, "{declared:?}");
        assert!(
            pct(declared.spurious, declared.features) <= 5.0,
            "{declared:?}"
        );
        // As one sweep, the scan's scatter (the sweeps' offset counted as noise) keeps the
        // marks right, but the lines sit between the sweeps, off by half their offset.
        assert!(plain_bad > 2 * bad_walls, "{plain_bad} vs {bad_walls}");
        assert!(bad_walls * 20 <= walls, "{bad_walls} of {walls} walls");
    }
}

/// A robot turning on the spot at 0.3, 0.45 and 0.6 rad/s (4–8 mrad, up to half a 0.5° step,
/// between the two sweeps), σ_r = 10 mm, ranges rounded to the cm as in the CARMEN logs, no
/// odometry. A turn moves points across the beams, which the scan's scatter shows only where
/// beams graze a wall (in most of these scans not enough to show the sweeps apart), but there
/// the walk marks them. Declared sweeps are moved by their estimate and walked again, and that
/// walk kept when it leaves fewer marks: against one sweep, under 70 % of its false marks and
/// 60 % of its walls without one good line (without the second walk: 98 % of its false marks).
#[test]
fn sweeps_turned_against_each_other_are_walked_again() {
    let mut ex = Extractor::<401, 128>::new();
    let mut noise = Noise::new(23);
    let (g, n, sweeps) = variant(0.5);
    let config = Config::default().with_sigma_r(10.0);
    let (mut plain, mut declared) = (Score::default(), Score::default());
    let (mut walls, mut bad_walls, mut plain_bad) = (0, 0, 0);
    for omega in [0.3f64, 0.45, 0.6] {
        let turn = |s: usize| {
            (
                0.0,
                0.0,
                omega * f64::from(BeamTiming::LMS2XX_TURN) * s as f64,
            )
        };
        for _ in 0..100 {
            let room = room(&mut noise);
            let (ranges, hits) = render(&room.prims, g, n, sweeps, turn, 10.0, &mut noise);
            let ranges: Vec<f32> = ranges.iter().map(|r| (r / 10.0).round() * 10.0).collect();
            let (marks, plain_features, _) = extract_with(&mut ex, g, &ranges, 1, &config);
            score(&hits, &marks, &plain_features, &mut plain);
            let (marks, features, _) = extract_with(&mut ex, g, &ranges, 2, &config);
            score(&hits, &marks, &features, &mut declared);
            let (w, bad) = wall_lines(&room, &hits, &features);
            walls += w;
            bad_walls += bad;
            plain_bad += wall_lines(&room, &hits, &plain_features).1;
        }
    }
    println!("false marks {} (as 1 sweep {}); {bad_walls} of {walls} walls without exactly one good line (as 1 sweep {plain_bad})", declared.false_marks, plain.false_marks);
    assert!(
        10 * declared.false_marks < 7 * plain.false_marks,
        "{declared:?} vs {plain:?}"
    );
    assert!(10 * bad_walls < 6 * plain_bad, "{bad_walls} vs {plain_bad}");
    let pct = |a: usize, b: usize| 100.0 * a as f64 / b.max(1) as f64;
    assert!(pct(declared.missed, declared.truth) <= 8.0, "{declared:?}");
    assert!(
        pct(declared.spurious, declared.features) <= 5.0,
        "{declared:?}"
    );
}

/// The board's configuration (no `scrutiny`): 8 mm / 6 mrad between sweeps, σ_r = 5 mm, no
/// odometry. Declared sweeps are moved when the walk's marks show them out of place and the
/// scan is extracted again from scratch: fewer false marks and fewer walls without one good line
/// than as one sweep, and the statistics and features of the second extraction only (readings,
/// valid points, features as stored, both walks' predictions).
#[test]
fn the_boards_configuration_aligns_sweeps_its_marks_show_apart() {
    let mut ex = Extractor::<401, 128>::new();
    let mut noise = Noise::new(29);
    let (g, n, sweeps) = variant(0.5);
    let truth = sweep_pose(0.5);
    let config = Config::default().with_scrutiny(false).with_sigma_r(5.0);
    let (mut plain, mut declared) = (Score::default(), Score::default());
    let (mut walls, mut bad_walls, mut plain_bad, mut aligned) = (0, 0, 0, 0);
    for _ in 0..100 {
        let room = room(&mut noise);
        let (mut ranges, hits) = render(&room.prims, g, n, sweeps, &truth, 5.0, &mut noise);
        // A reading lost now and then (no return): no feature may span it, aligned or not.
        for r in ranges.iter_mut().step_by(97) {
            *r = f32::NAN;
        }
        let (marks, plain_features, one) = extract_with(&mut ex, g, &ranges, 1, &config);
        score(&hits, &marks, &plain_features, &mut plain);
        let (marks, features, stats) = extract_with(&mut ex, g, &ranges, 2, &config);
        score(&hits, &marks, &features, &mut declared);
        for f in &features {
            assert!(
                (f.first()..=f.last()).all(|i| ranges[i].is_finite()),
                "{f:?} spans a lost reading"
            );
        }
        assert_eq!(stats, ex.stats());
        assert_eq!(stats.readings, n);
        assert_eq!(stats.valid, ranges.iter().filter(|r| r.is_finite()).count());
        assert_eq!(stats.features, features.len());
        assert!(stats.sweeps_aligned <= 1);
        if stats.sweeps_aligned == 1 {
            aligned += 1;
            // Both walks' predictions, each about one a point.
            assert!(
                2 * stats.predictions > 3 * one.predictions,
                "{stats:?} vs {one:?}"
            );
        } else {
            assert_eq!(features, plain_features);
        }
        let (w, bad) = wall_lines(&room, &hits, &features);
        walls += w;
        bad_walls += bad;
        plain_bad += wall_lines(&room, &hits, &plain_features).1;
    }
    println!(
        "false marks {} (1 sweep {}), {bad_walls} of {walls} walls bad (1 sweep {plain_bad}), {aligned} aligned",
        declared.false_marks, plain.false_marks
    );
    assert!(aligned >= 20, "{aligned} of 100 scans aligned");
    assert!(
        declared.false_marks < plain.false_marks,
        "{declared:?} vs {plain:?}"
    );
    assert!(bad_walls < plain_bad, "{bad_walls} vs {plain_bad}");
}

/// Without scrutiny, declared sweeps are aligned only by the default mode's rule and only
/// without odometry: under the paper's rule, or with odometry given (the robot's motion,
/// 8 mm / 6 mrad between the sweeps), the scan is extracted as one sweep is, bit for bit:
/// odometry, when given, places the sweeps. (Odometry of a scanner standing still is no
/// odometry: `tests/odometry.rs`.)
#[test]
fn sweeps_are_aligned_only_by_the_noise_rule_without_odometry() {
    let mut ex = Extractor::<401, 128>::new();
    let mut noise = Noise::new(31);
    let (g, n, sweeps) = variant(0.5);
    let truth = sweep_pose(0.5);
    let board = Config::default().with_scrutiny(false).with_sigma_r(5.0);
    let (mut marks, mut moving_marks) = (0, 0);
    for _ in 0..30 {
        let room = room(&mut noise);
        let (ranges, _) = render(&room.prims, g, n, sweeps, &truth, 5.0, &mut noise);
        let paper = Config::paper().with_sigma_r(5.0);
        let one = extract_with(&mut ex, g, &ranges, 1, &paper);
        let two = extract_with(&mut ex, g, &ranges, 2, &paper);
        assert_eq!(two.2.sweeps_aligned, 0);
        assert_eq!((&one.0, &one.1, one.2), (&two.0, &two.1, two.2));
        marks += one.0.len();
        let mut with = |sweeps: u8| {
            let scan = Scan::from_mm(g, &ranges)
                .with_sweeps(sweeps)
                .with_motion(motion(0.5));
            let stats = ex.extract(&scan, &board).unwrap();
            (stats, ex.features().to_vec(), ex.marks().count())
        };
        let one = with(1);
        let two = with(2);
        assert_eq!(two.0.sweeps_aligned, 0);
        assert_eq!(one, two);
        moving_marks += one.2;
    }
    // As one sweep, the paper's walk leaves 43 marks a scan (seed 31); the default's with
    // the odometry 9, about the rooms' corners and the pillar's edges (24 without it).
    assert!(marks > 30 * 35, "{marks} marks in 30 scans");
    assert!(moving_marks < 30 * 12, "{moving_marks} marks in 30 scans");
}

/// Of the runs of ≥ 30 beams on a wall of `room`: how many, and how many have not exactly one
/// line of `features` over most of them with ρ and α within 4 standard deviations of the
/// wall's (plus 1 mm / 1 mrad).
fn wall_lines(room: &Room, hits: &[Option<usize>], features: &[Feature]) -> (usize, usize) {
    let (mut walls, mut bad) = (0, 0);
    for &(first, last, w) in &common::runs(hits, 30) {
        let Some(&(rho, alpha)) = room.walls.get(w) else {
            continue;
        };
        walls += 1;
        let lines: Vec<_> = features
            .iter()
            .filter_map(|f| match f {
                Feature::Line(l)
                    if 2 * (usize::from(l.last).min(last) + 1)
                        .saturating_sub(usize::from(l.first).max(first))
                        > usize::from(l.last - l.first) + 1 =>
                {
                    Some(*l)
                }
                _ => None,
            })
            .collect();
        let ok = match lines.as_slice() {
            [l] => {
                let da = (f64::from(l.alpha) - alpha + std::f64::consts::PI)
                    .rem_euclid(2.0 * std::f64::consts::PI)
                    - std::f64::consts::PI;
                let dr = f64::from(l.rho) - rho;
                dr.abs() < 4.0 * f64::from(l.var_rho).sqrt() + 1.0
                    && da.abs() < 4.0 * f64::from(l.var_alpha).sqrt() + 1e-3
            }
            _ => false,
        };
        bad += usize::from(!ok);
    }
    (walls, bad)
}

/// The estimate's χ² of a static noisy scan is mostly below the significance threshold.
#[test]
fn a_static_scan_has_no_significant_offset() {
    let mut noise = Noise::new(8);
    let (g, n, _) = variant(0.5);
    let mut significant = 0;
    for _ in 0..200 {
        let room = room(&mut noise);
        let (ranges, _) = render(&room.prims, g, n, 1, |_| (0.0, 0.0, 0.0), 5.0, &mut noise);
        let e: Option<SweepOffset> = estimate(&points(g, &ranges), 2, 1, g.angle_step);
        significant += usize::from(e.is_some_and(|e| e.is_significant()));
    }
    assert!(significant <= 4, "{significant} of 200");
}

/// The estimate's χ² (`xᵀ A x / σ²`, 3 degrees of freedom) of a static noisy scan has the
/// mean 3 of a χ² with 3 degrees of freedom (300 rooms: the mean's standard error is 0.14),
/// and its largest point shift is `|d| + |dθ|·r` for a range r within the scan's.
#[test]
fn the_chi2_of_a_static_scan_has_three_degrees_of_freedom() {
    let mut noise = Noise::new(13);
    let (g, n, _) = variant(0.5);
    let (mut sum, mut count) = (0.0f64, 0);
    for _ in 0..300 {
        let room = room(&mut noise);
        let (ranges, _) = render(&room.prims, g, n, 1, |_| (0.0, 0.0, 0.0), 5.0, &mut noise);
        let Some(e) = estimate(&points(g, &ranges), 2, 1, g.angle_step) else {
            continue;
        };
        sum += f64::from(e.chi2);
        count += 1;
        let far = ranges
            .iter()
            .filter(|r| r.is_finite())
            .fold(0.0f32, |m, &r| m.max(r));
        let base = e.dx.hypot(e.dy);
        assert!(
            e.max_shift >= base && e.max_shift <= base + e.dtheta.abs() * far * 1.001 + 1e-3,
            "{e:?}, farthest range {far}"
        );
    }
    assert!(count > 280, "{count} estimates");
    let mean = sum / f64::from(count);
    assert!((2.4..3.6).contains(&mean), "mean χ² {mean}");
}

/// Sweeps 5–8 mm apart (about σ_r = 5 mm) seldom scatter apart, nor leave fewer marks when
/// moved and walked again: the extractor moves them only on that evidence (the extractor's and
/// `sweeps`' docs), so it moves few of these scans (at most 10 of 40) although
/// their offset estimate is mostly significant (at least 30 of 40).
#[test]
fn sweeps_slightly_apart_are_moved_only_on_evidence() {
    let mut noise = Noise::new(17);
    let (g, n, sweeps) = variant(0.5);
    let mut ex = Extractor::<401, 128>::new();
    let (mut significant, mut aligned) = (0, 0);
    for k in 0..40 {
        let room = room(&mut noise);
        let d = [5.0, 6.0, 7.0, 8.0][k % 4];
        let pose = |s: usize| (d * s as f64, 0.0, 0.0);
        let (ranges, _) = render(&room.prims, g, n, sweeps, pose, 5.0, &mut noise);
        significant += usize::from(
            estimate(&points(g, &ranges), sweeps, 1, g.angle_step)
                .is_some_and(|e| e.is_significant()),
        );
        let (_, _, stats) = extract(&mut ex, g, &ranges, sweeps as u8);
        aligned += usize::from(stats.sweeps_aligned > 0);
    }
    assert!(
        significant >= 30,
        "{significant} of 40 estimates significant"
    );
    assert!(aligned <= 10, "{aligned} of 40 scans moved");
}

/// `estimate` takes sweeps 1 ≤ `sweep` < `sweeps` (sweep 0 is the reference) and a finite
/// bearing step; anything else has no estimate.
#[test]
fn the_offset_of_sweep_zero_or_beyond_the_last_is_none() {
    let mut noise = Noise::new(19);
    let (g, n, sweeps) = variant(0.5);
    let room = room(&mut noise);
    let (ranges, _) = render(&room.prims, g, n, sweeps, sweep_pose(0.5), 0.0, &mut noise);
    let pts = points(g, &ranges);
    assert!(estimate(&pts, 2, 1, g.angle_step).is_some());
    assert!(estimate(&pts, 2, 0, g.angle_step).is_none());
    assert!(estimate(&pts, 2, 2, g.angle_step).is_none());
    assert!(estimate(&pts, 2, 1, f32::NAN).is_none());
}

/// More sweeps than [`MAX_SWEEPS`] are not aligned at all (rather than some of them moved): a
/// scan of 8 mm / 6 mrad sweeps declared as 8 gives what it gives as one sweep, with or
/// without scrutiny, while declared as 2 it is aligned.
#[test]
fn more_sweeps_than_the_most_are_left_as_they_are() {
    assert_eq!(pfe_core::sweeps::MAX_SWEEPS, 4);
    let mut ex = Extractor::<401, 128>::new();
    let mut noise = Noise::new(31);
    let (g, n, sweeps) = variant(0.5);
    let truth = sweep_pose(0.5);
    let mut aligned_as_two = 0;
    for config in [Config::default(), Config::default().with_scrutiny(false)] {
        let config = config.with_sigma_r(5.0);
        for _ in 0..20 {
            let room = room(&mut noise);
            let (ranges, _) = render(&room.prims, g, n, sweeps, &truth, 5.0, &mut noise);
            let one = extract_with(&mut ex, g, &ranges, 1, &config);
            let eight = extract_with(&mut ex, g, &ranges, 8, &config);
            assert_eq!(eight, one);
            aligned_as_two += extract_with(&mut ex, g, &ranges, 2, &config)
                .2
                .sweeps_aligned;
        }
    }
    assert!(
        aligned_as_two >= 10,
        "{aligned_as_two} of 40 aligned as two sweeps"
    );
}
