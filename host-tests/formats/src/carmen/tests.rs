//! The CARMEN reader's unit tests.

use super::*;
use crate::{Location, Record};

fn first(log: &'static str) -> Record {
    match Reader::new(Box::new(log.as_bytes())).next() {
        Some(Ok(r)) => r,
        other => panic!("no scan: {other:?}"),
    }
}

#[test]
fn pose_and_time_are_the_first_pose_and_the_timestamp() {
    let r = first("FLASER 5 1 2 3 4 5 1.5 -2.25 0.5 9 9 9 32.9068 host 33.5\n");
    assert_eq!(r.pose, Some([1.5, -2.25, 0.5]));
    assert_eq!(r.time, Some(32.9068));
}

/// A `ROBOTLASER1` line of the CARMEN logger: 5 beams from −45° a quarter of π apart,
/// 8 m maximum (the 8.5 m reading and the 0 are no return), 2 remissions, the laser's pose
/// (1, 2, 0.5) and the robot's (0.9, 2, 0.5), then tv rv, the safety distances, the turn
/// axis, and the timestamp.
const ROBOT: &str = "ROBOTLASER1 0 -0.785398 3.141593 0.785398 8.0 0.01 0 5 \
    1.0 8.5 2.5 0 3.0 2 7 9 1.0 2.0 0.5 0.9 2.0 0.5 0.1 0.0 0.3 0.2 0.0 12.5 host 12.6\n";

#[test]
fn robotlaser1_gives_its_own_geometry_and_the_laser_pose() {
    let r = first(ROBOT);
    assert!((r.geometry.start_angle + std::f32::consts::FRAC_PI_4).abs() < 1e-6);
    assert!((r.geometry.angle_step - std::f32::consts::FRAC_PI_4).abs() < 1e-6);
    assert_eq!(r.geometry.r_max, 8000.0);
    let valid: Vec<bool> = r.ranges_mm.iter().map(|v| v.is_finite()).collect();
    assert_eq!(valid, [true, false, true, false, true]);
    assert_eq!((r.ranges_mm[0], r.ranges_mm[4]), (1000.0, 3000.0));
    assert_eq!(r.pose, Some([1.0, 2.0, 0.5]));
    assert_eq!(r.time, Some(12.5));
    // Beam 4 lies at +135°.
    let (x, y) = r.point(4).unwrap_or_default();
    assert!(
        (x + 2121.32).abs() < 0.1 && (y - 2121.32).abs() < 0.1,
        "{x} {y}"
    );
}

/// Older `ROBOTLASER1` lines have no remissions and no turn axis.
#[test]
fn robotlaser1_without_remissions_is_read_too() {
    let r = first(
        "ROBOTLASER1 0 -1.570796 3.141593 0.017453 81.9 0.01 0 3 1 2 3 \
         4.0 -1.5 0.25 3.9 -1.5 0.25 0.0 0.0 0.3 0.2 77.25 host 77.3\n",
    );
    assert_eq!(r.pose, Some([4.0, -1.5, 0.25]));
    assert_eq!(r.time, Some(77.25));
    assert_eq!(r.geometry.r_max, LONG_MAX_RANGE_MM);
    // A laser x written as an integer is not a remission count: 13 fields follow the
    // ranges, as in a line without remissions.
    let r = first(
        "ROBOTLASER1 0 -1.570796 3.141593 0.785398 8.0 0.01 0 5 1 2 3 2 1 \
         0 1.5 0.25 0.1 1.5 0.25 0.0 0.0 0.3 0.2 77.25 host 77.3\n",
    );
    assert_eq!((r.pose, r.time), (Some([0.0, 1.5, 0.25]), Some(77.25)));
    // The count and its remissions, then 13 fields (no turn axis).
    let r = first(
        "ROBOTLASER1 0 -1.570796 3.141593 0.785398 8.0 0.01 0 5 1 2 3 2 1 \
         2 7 8 3 1.5 0.25 0.1 1.5 0.25 0.0 0.0 0.3 0.2 77.25 host 77.3\n",
    );
    assert_eq!((r.pose, r.time), (Some([3.0, 1.5, 0.25]), Some(77.25)));
    // Nothing after the ranges, fewer remissions than declared, fields missing: errors.
    for line in [
        "ROBOTLASER1 0 -1.5 3.1 0.01 8 0.01 0 3 1 2 3\n",
        "ROBOTLASER1 0 -1.5 3.1 0.01 8 0.01 0 3 1 2 3 9 1 2\n",
        "ROBOTLASER1 0 -1.5 3.1 0.01 8 0.01 0 3 1 2 3 0 1 2 3 4 5 6 7 8 9 1 2\n",
        "RAWLASER1 0 -1.5 3.1 0.01 8 0.01 0 3 1 2 3\n",
        "RAWLASER1 0 -1.5 3.1 0.01 8 0.01 0 3 1 2 3 2 7 8 1.5 h\n",
    ] {
        let r: Vec<_> = Reader::new(Box::new(line.as_bytes())).collect();
        assert!(
            matches!(&r[..], [Err(e)] if e.message.contains("fields after the ranges")),
            "{line}: {r:?}"
        );
    }
}

/// A SICK LMS (laser type 0) at 0.5° is left to the format's rule (two sweeps); a Hokuyo URG
/// (type 2) at the same step is one sweep.
#[test]
fn rawlaser1_gives_its_geometry_and_time_but_no_pose() {
    let r = first("RAWLASER1 0 -1.570796 3.141593 0.008727 81.9 0.01 0 3 1 2 3 0 5.5 h 5.6\n");
    assert!((r.geometry.angle_step - 0.5f32.to_radians()).abs() < 1e-6);
    assert_eq!((r.pose, r.time, r.sweeps), (None, Some(5.5), None));
    let r = first("RAWLASER1 2 -1.570796 3.141593 0.008727 5.6 0.01 0 3 1 2 3 0 5.5 h 5.6\n");
    assert_eq!(r.sweeps, Some(1));
}

/// One kind of laser message per log: the first with a pose; `RAWLASER1` only when no
/// message with a pose comes among the first [`HOLD`] of them. Scans are numbered from 0.
#[test]
fn each_scan_is_read_once_from_one_kind_of_message() {
    let kinds = |log: String| -> Vec<(u64, Option<f64>)> {
        let reader = Reader::new(Box::new(std::io::Cursor::new(log.into_bytes())));
        reader
            .map(|r| r.map(|r| (r.id, r.time)))
            .collect::<Result<_, _>>()
            .unwrap_or_else(|e| panic!("{e}"))
    };
    let flaser = |t: u32| format!("FLASER 5 1 2 3 4 5 0 0 0 0 0 0 {t} h {t}\n");
    let robot = |t: u32| {
        format!("ROBOTLASER1 0 -1.5 3.1 0.01 8 0.01 0 3 1 2 3 0 0 0 0 0 0 0 0 0 0 0 0 {t} h {t}\n")
    };
    let raw = |t: u32| format!("RAWLASER1 0 -1.5 3.1 0.01 8 0.01 0 3 1 2 3 0 {t} h {t}\n");
    let log = |f: &dyn Fn(u32) -> String, g: &dyn Fn(u32) -> String, n: u32| {
        (0..n).map(|t| f(t) + &g(t + 100)).collect::<String>()
    };
    let times =
        |v: &[(u64, Option<f64>)]| v.iter().map(|(_, t)| t.unwrap_or(-1.0)).collect::<Vec<_>>();
    let ids = |v: &[(u64, Option<f64>)]| v.iter().map(|(i, _)| *i).collect::<Vec<_>>();
    let a = kinds(log(&flaser, &robot, 3));
    assert_eq!(times(&a), [0.0, 1.0, 2.0]);
    let b = kinds(log(&robot, &flaser, 3));
    assert_eq!(times(&b), [0.0, 1.0, 2.0]);
    // RAWLASER1 before ROBOTLASER1: the robot's scans, numbered from 0.
    let c = kinds(log(&raw, &robot, 3));
    assert_eq!(
        (times(&c), ids(&c)),
        (vec![100.0, 101.0, 102.0], vec![0, 1, 2])
    );
    // Only RAWLASER1: all of them, fewer or more than HOLD. A ROBOTLASER1 after HOLD − 1 of
    // them is read; after HOLD, not.
    let d = kinds((0..3).map(raw).collect());
    assert_eq!(times(&d), [0.0, 1.0, 2.0]);
    let n = HOLD as u32;
    let e = kinds((0..n).map(raw).collect::<String>() + &robot(9999));
    assert_eq!(ids(&e), (0..u64::from(n)).collect::<Vec<_>>());
    let f = kinds((0..n - 1).map(raw).collect::<String>() + &robot(9999));
    assert_eq!(times(&f), [9999.0]);
}

/// A malformed line after held `RAWLASER1` lines comes after their scans, as in a log of
/// one kind; a malformed `RAWLASER1` line among the lines of the kind read is not read.
#[test]
fn an_error_comes_after_the_scans_before_it() {
    let raw = |t: u32| format!("RAWLASER1 0 -1.5 3.1 0.01 8 0.01 0 3 1 2 3 0 {t} h {t}\n");
    let robot = |t: u32| {
        format!("ROBOTLASER1 0 -1.5 3.1 0.01 8 0.01 0 3 1 2 3 0 0 0 0 0 0 0 0 0 0 0 0 {t} h {t}\n")
    };
    let log = raw(0) + &raw(1) + "oops\n" + &raw(2);
    let r: Vec<_> = Reader::new(Box::new(std::io::Cursor::new(log.into_bytes()))).collect();
    assert!(
        matches!(&r[..], [Ok(a), Ok(b), Err(e)]
        if a.time == Some(0.0) && b.time == Some(1.0) && e.location == Location::Line(3)),
        "{r:?}"
    );
    let log = robot(0) + "RAWLASER1 0 x\n" + &robot(1);
    let r: Vec<_> = Reader::new(Box::new(std::io::Cursor::new(log.into_bytes()))).collect();
    assert!(
        matches!(&r[..], [Ok(_), Ok(b)] if b.time == Some(1.0)),
        "{r:?}"
    );
}

#[test]
fn missing_or_bad_pose_fields_give_none() {
    let r = first("FLASER 5 1 2 3 4 5 1.5 nan\n");
    assert_eq!((r.pose, r.time), (None, None));
    let r = first("FLASER 5 1 2 3 4 5 1.5 2 x 0 0 0 t host 0\n");
    assert_eq!((r.pose, r.time), (None, None));
}

/// The odometry of a `FLASER` line follows each scan; a `ROBOTLASER1` line has none, and
/// non-numeric odometry fields give none.
#[test]
fn odometry_of_each_scan() {
    let log = "FLASER 5 1 2 3 4 5 0.5 0 0 1 2 0.5 7.0 host 7.0\n\
               FLASER 5 1 2 3 4 5 0.5 0 0 x 2 0.5 8.0 host 8.0\n\
               FLASER 5 1 2 3 4 5 0.5 0 0 3 4 -0.5 9.0 host 9.0\n";
    let mut r = Reader::new(Box::new(log.as_bytes()));
    let mut seen = Vec::new();
    while let Some(s) = r.next() {
        assert!(s.is_ok());
        seen.push(r.odometry());
    }
    assert_eq!(seen, [Some([1.0, 2.0, 0.5]), None, Some([3.0, 4.0, -0.5])]);
    let mut r = Reader::new(Box::new(ROBOT.as_bytes()));
    assert!(r.next().is_some_and(|s| s.is_ok()));
    assert_eq!(r.odometry(), None);
}
