//! Range correction and motion de-skew against analytic truth.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

use pfe_core::{
    BeamTiming, Config, Extractor, Feature, FitError, LineFeature, Motion, RangeCorrection, Scan,
    ScanGeometry,
};

/// A smooth systematic error like the LMS200's (±15 mm over 8 m).
fn bias(r: f64) -> f64 {
    15.0 * (r / 8000.0 * 5.0).sin() * (1.0 - r / 16000.0)
}

/// The one feature found in `scan`, which must be a line.
fn one_line(scan: &Scan, config: &Config) -> LineFeature {
    let mut ex = Extractor::<361, 8>::new();
    ex.extract(scan, config).unwrap();
    let [Feature::Line(l)] = ex.features() else {
        panic!("{:?}", ex.features())
    };
    *l
}

/// (measured, true) ranges every 39.5 mm from 100 mm, measured with [`bias`].
fn calibration_pairs() -> Vec<(f32, f32)> {
    (0..200)
        .map(|i| {
            let t = 100.0 + 39.5 * i as f64;
            ((t + bias(t)) as f32, t as f32)
        })
        .collect()
}

#[test]
fn calibration_recovers_a_sixth_order_error_curve() {
    let pairs = calibration_pairs();
    let c = RangeCorrection::calibrate(&pairs).unwrap();
    let worst = pairs
        .iter()
        .map(|&(m, t)| (c.apply(m) - t).abs())
        .fold(0.0f32, f32::max);
    // A degree-6 polynomial fits this curve to well under the 1 mm quantum.
    assert!(worst < 0.5, "worst residual {worst} mm");
    // And it is a polynomial: an exact cubic error is recovered exactly.
    let cubic: Vec<(f32, f32)> = (1..50)
        .map(|i| {
            let t = i as f32 * 150.0;
            let x = t / 7500.0;
            (t + 3.0 - 4.0 * x + 2.0 * x * x * x, t)
        })
        .collect();
    let c = RangeCorrection::calibrate(&cubic).unwrap();
    for &(m, t) in &cubic {
        assert!((c.apply(m) - t).abs() < 0.05);
    }
}

#[test]
fn calibration_rejects_bad_input() {
    assert!(RangeCorrection::calibrate(&[(1.0, 1.0); 3]).is_err());
    assert!(RangeCorrection::calibrate(&[(1000.0, 1000.0); 20]).is_err());
    let mut pairs: Vec<(f32, f32)> = (1..20)
        .map(|i| (i as f32 * 100.0, i as f32 * 100.0))
        .collect();
    pairs[3].0 = f32::NAN;
    assert!(RangeCorrection::calibrate(&pairs).is_err());
    // One non-finite value of a pair, measured or true, is the error that says so.
    for (k, bad) in [(3usize, f32::NAN), (7, f32::INFINITY)] {
        let mut measured = pairs.clone();
        measured[3].0 = 400.0;
        measured[k].0 = bad;
        let mut truth = measured.clone();
        truth[k] = (measured[k].1, bad);
        for p in [measured, truth] {
            assert!(
                matches!(RangeCorrection::calibrate(&p), Err(FitError::NonFinite)),
                "{:?}",
                RangeCorrection::calibrate(&p)
            );
        }
    }
}

#[test]
fn correction_in_the_extractor_removes_the_bias() {
    let g = ScanGeometry::LMS200_180_050;
    let pairs = calibration_pairs();
    let corr = RangeCorrection::calibrate(&pairs).unwrap();
    let ranges: Vec<f32> = (0..361)
        .map(|i| {
            let b = g.bearing(i) as f64;
            if b.abs() < 1.0 {
                let t = 3000.0 / b.cos();
                (t + bias(t)) as f32
            } else {
                f32::NAN
            }
        })
        .collect();
    let l = one_line(
        &Scan::from_mm(g, &ranges),
        &Config::default().with_correction(corr),
    );
    assert!(
        (l.rho - 3000.0).abs() < 0.5 && l.alpha.abs() < 1e-4,
        "{l:?}"
    );
}

#[test]
fn deskew_puts_a_moving_scan_back_on_the_wall() {
    // The robot drives at 1 m/s and turns at 1 rad/s during a scan of 361 beams taken 26.7 µs
    // apart... times 100 to make the skew large (0.96 s): 0.96 m and 55°.
    let g = ScanGeometry::LMS200_180_050;
    let m = Motion::uniform(1000.0, 1.0, 0.002_666);
    let ranges = wall_seen_moving(g, &m, 4000.0);
    let l = one_line(
        &Scan::from_mm(g, &ranges).with_motion(m),
        &Config::default(),
    );
    assert!(
        (l.rho - 4000.0).abs() < 1.0 && l.alpha.abs() < 1e-3,
        "{l:?}"
    );
    // Without de-skew the same readings do not form one wall at x = 4000.
    let mut ex = Extractor::<361, 8>::new();
    ex.extract(&Scan::from_mm(g, &ranges), &Config::default())
        .unwrap();
    let off = ex.features().iter().all(|f| match f {
        Feature::Line(l) => (l.rho - 4000.0).abs() > 50.0 || l.alpha.abs() > 0.05,
        _ => true,
    });
    assert!(off, "{:?}", ex.features());
}

/// Ranges of the wall `x = wall` (frame of beam 0, |y| < 3 m) seen by the beams of `g`, each
/// from the pose `m` gives it (exact ray–line intersection).
fn wall_seen_moving(g: ScanGeometry, m: &Motion, wall: f32) -> Vec<f32> {
    (0..361)
        .map(|i| {
            let p = m.pose(i);
            let b = g.bearing(i) + p.theta;
            let (dx, dy) = (b.cos(), b.sin());
            let t = (wall - p.origin.x) / dx;
            let y = p.origin.y + t * dy;
            if dx > 0.1 && t > 0.0 && y.abs() < 3000.0 {
                t
            } else {
                f32::NAN
            }
        })
        .collect()
}

#[test]
fn beam_timing_of_interleaved_sweeps() {
    let turn = 1.0 / 75.0;
    let deg = turn / 360.0;
    let close = |a: f32, b: f32| (a - b).abs() < 1e-9;
    // 1°: one sweep, 1° apart.
    let t = BeamTiming::lms2xx(1.0);
    assert_eq!(t.sweep_count(), 1);
    assert!(close(t.time(7), 7.0 * deg));
    // 0.5°: even beams in the first turn, odd ones a turn later.
    let t = BeamTiming::lms2xx(0.5);
    assert_eq!((t.sweep_count(), t.sweep(6), t.sweep(7)), (2, 0, 1));
    assert!(close(t.time(6), 3.0 * deg) && close(t.time(7), turn + 3.0 * deg));
    // 0.25°: four sweeps, beam i in sweep i mod 4.
    let t = BeamTiming::lms2xx(0.25);
    assert_eq!((t.sweep_count(), t.sweep(11)), (4, 3));
    assert!(close(t.time(11), 3.0 * turn + 2.0 * deg));
    // Zero sweeps count as one; a NaN time is not valid.
    let t = BeamTiming::interleaved(0, 1.0, 0.5);
    assert!(close(t.time(3), 1.5) && t.is_valid());
    assert!(!BeamTiming::uniform(f32::NAN).is_valid());
    assert!(!Motion {
        v: 1.0,
        omega: 0.0,
        timing: BeamTiming::interleaved(2, f32::INFINITY, 0.1)
    }
    .is_valid());
}

#[test]
fn deskew_with_interleaved_timing_puts_both_sweeps_on_the_wall() {
    // 0.5° LMS200 on a robot at 0.6 m/s turning at 0.45 rad/s: the odd sweep is taken 8 mm
    // further and 6 mrad turned (30 mm sideways at 5 m).
    let g = ScanGeometry::LMS200_180_050;
    let m = Motion {
        v: 600.0,
        omega: 0.45,
        timing: BeamTiming::lms2xx(0.5),
    };
    let ranges = wall_seen_moving(g, &m, 5000.0);
    let mut ex = Extractor::<361, 8>::new();
    ex.extract(
        &Scan::from_mm(g, &ranges).with_motion(m),
        &Config::default(),
    )
    .unwrap();
    let [Feature::Line(l)] = ex.features() else {
        panic!("{:?}", ex.features())
    };
    assert!(
        (l.rho - 5000.0).abs() < 1.0 && l.alpha.abs() < 1e-3,
        "{l:?}"
    );
    // Every point of both sweeps on the wall.
    let worst = farthest_from_wall(&ex, 5000.0);
    assert!(worst < 0.5, "{worst} mm");
    // The same motion taken as one sweep (beam i at i × 26.7 ms / 361) leaves the odd beams
    // off the wall.
    let uniform = Motion::uniform(600.0, 0.45, 2.0 * BeamTiming::LMS2XX_TURN / 361.0);
    ex.extract(
        &Scan::from_mm(g, &ranges).with_motion(uniform),
        &Config::default(),
    )
    .unwrap();
    let worst = farthest_from_wall(&ex, 5000.0);
    assert!(worst > 10.0, "{worst} mm");
}

/// The largest distance of the last extraction's valid points from the wall `x = wall`, mm.
fn farthest_from_wall<const N: usize, const M: usize>(ex: &Extractor<N, M>, wall: f32) -> f32 {
    ex.points()
        .iter()
        .filter(|p| p.is_valid())
        .map(|p| (p.x - wall).abs())
        .fold(0.0f32, f32::max)
}
