//! `pfe odometry` and `pfe posebench`: poses against the exact truth of an analytic room seen
//! from known poses (CARMEN and csv written here), bad input, and the shared logs (skipped,
//! with a message, when `../shared/data` is absent).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: a panic fails the test

use std::path::PathBuf;

#[path = "../../tests/common/mod.rs"]
mod common;
#[path = "room/mod.rs"]
mod room;
use common::{arg, json_lines, pfe, stderr, TempDir};
use room::*;

/// Without a prior, on the analytic room, CARMEN and csv: every scan "ok", the relative and
/// accumulated poses within their stated 3σ of the truth (at most 2 % of the components
/// beyond, as a Gaussian would put 0.3 %), relative errors under 30 mm and 0.5°; the log's
/// pose printed for CARMEN only.
#[test]
fn odometry_matches_the_truth_within_its_covariance() {
    let dir = TempDir::new("odometry-truth");
    let poses = truth();
    let log = write(&dir, "room.log", &carmen(&poses, &poses));
    let csv = write(&dir, "room.csv", &csv(&poses));
    for (file, format) in [(&log, "carmen"), (&csv, "csv")] {
        let out = pfe(&["odometry", "--format", format, arg(file)]);
        assert!(out.status.success(), "{format}: {}", stderr(&out));
        let lines = json_lines(&out);
        let (beyond, total, worst_t, worst_r) = check_against_truth(&lines, &poses);
        eprintln!(
            "{format}: {beyond} of {total} beyond 3σ; worst rel {worst_t:.1} mm {worst_r:.4} rad"
        );
        assert!(
            beyond * 50 <= total,
            "{format}: {beyond} of {total} beyond 3σ"
        );
        assert!(
            worst_t < 30.0 && worst_r < 0.5f64.to_radians(),
            "{format}: {worst_t} {worst_r}"
        );
        assert_eq!(lines[0]["scan"], 0);
        assert!(lines.iter().all(|l| l["prior"] == false));
        for (l, p) in lines.iter().zip(&poses) {
            if format == "carmen" {
                let lp: Vec<f64> = l["log_pose"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|v| v.as_f64().unwrap())
                    .collect();
                assert!(
                    (lp[0] * 1000.0 - p[0]).abs() < 0.01 && (lp[2] - p[2]).abs() < 1e-5,
                    "{l}"
                );
            } else {
                assert!(l.get("log_pose").is_none(), "{l}");
            }
        }
    }
}

/// `--prior odometry` uses the FLASER odometry (the truth drifting by 2 % in translation and
/// 0.01 rad a step): every scan after the first has a prior and the poses still match the
/// truth within 3σ; a csv has no odometry, so no prior, said on stderr.
#[test]
fn odometry_prior_from_the_log() {
    let dir = TempDir::new("odometry-prior");
    let poses = truth();
    let mut odom = vec![poses[0]];
    for k in 1..poses.len() {
        let d = between(&poses[k - 1], &poses[k]);
        let o = odom[k - 1];
        let (s, c) = o[2].sin_cos();
        let (dx, dy, dt) = (d[0] * 1.02, d[1] * 1.02, d[2] + 0.01);
        odom.push([o[0] + c * dx - s * dy, o[1] + s * dx + c * dy, o[2] + dt]);
    }
    let log = write(&dir, "room.log", &carmen(&poses, &odom));
    let out = pfe(&[
        "odometry",
        "--format",
        "carmen",
        "--prior",
        "odometry",
        arg(&log),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let lines = json_lines(&out);
    assert!(lines.iter().skip(1).all(|l| l["prior"] == true));
    let (beyond, total, worst_t, worst_r) = check_against_truth(&lines, &poses);
    assert!(beyond * 50 <= total, "{beyond} of {total} beyond 3σ");
    assert!(
        worst_t < 30.0 && worst_r < 0.5f64.to_radians(),
        "{worst_t} {worst_r}"
    );
    let csv = write(&dir, "room.csv", &csv(&poses));
    let out = pfe(&[
        "odometry",
        "--format",
        "csv",
        "--prior",
        "odometry",
        arg(&csv),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(json_lines(&out).iter().all(|l| l["prior"] == false));
    assert!(stderr(&out).contains("no odometry"), "{}", stderr(&out));
}

/// Bad input exits 2 with a one-line error: a malformed line (the scans before it printed),
/// an empty file, a csv read as CARMEN, a bad σ.
#[test]
fn odometry_bad_input_exits_2() {
    let dir = TempDir::new("odometry-bad");
    let poses = truth();
    let good = carmen(&poses[..3], &poses[..3]);
    let bad = write(&dir, "bad.log", &format!("{good}this is not a log line\n"));
    let out = pfe(&["odometry", "--format", "carmen", arg(&bad)]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let err = stderr(&out);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("line 5"), "{err}");
    assert_eq!(json_lines(&out).len(), 3);
    let empty = write(&dir, "empty.log", "");
    let csv = write(&dir, "room.csv", &csv(&poses[..2]));
    for (file, format) in [(&empty, "carmen"), (&csv, "carmen")] {
        let out = pfe(&["odometry", "--format", format, arg(file)]);
        assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
        assert_eq!(
            stderr(&out).trim_end().lines().count(),
            1,
            "{}",
            stderr(&out)
        );
        assert!(out.stdout.is_empty());
    }
    let out = pfe(&[
        "odometry",
        "--format",
        "carmen",
        "--prior-sigma-xy",
        "-1",
        arg(&bad),
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
}

fn shared_carmen(test: &str) -> Option<PathBuf> {
    let d = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/carmen");
    if d.is_dir() {
        Some(d)
    } else {
        pfe_testkit::skip::skip(
            test,
            &format!("real data folder {} is absent", d.display()),
            pfe_testkit::skip::Need::InCi,
        );
        None
    }
}

/// On intel: one line per scan, statuses among the three, every number finite, most scans
/// registered, the log's pose on every line.
#[test]
fn odometry_on_intel() {
    let Some(d) = shared_carmen("odometry_on_intel") else {
        return;
    };
    let log = d.join("intel-corrected.log.gz");
    let out = pfe(&["odometry", "--format", "carmen", arg(&log)]);
    assert!(out.status.success(), "{}", stderr(&out));
    let lines = json_lines(&out);
    assert_eq!(lines.len(), 910);
    let mut ok = 0;
    for l in &lines {
        let s = l["status"].as_str().unwrap();
        assert!(["ok", "degenerate", "none"].contains(&s), "{l}");
        ok += usize::from(s == "ok");
        for key in ["rel", "pose"] {
            let (p, c) = pose_of(&l[key]);
            assert!(p.iter().chain(&c).all(|v| v.is_finite()), "{l}");
        }
        assert_eq!(l["log_pose"].as_array().map(Vec::len), Some(3), "{l}");
    }
    assert!(ok * 100 >= lines.len() * 80, "{ok} of {} ok", lines.len());
}

/// `--points` on intel (the scans' own points verify and complete the registration): fewer
/// scans unregistered than with the features alone, every number finite, and over windows of
/// 50 scans the odometry's motion within 0.1 m per metre travelled of the log's corrected
/// poses, pooled (measured 0.057 by `cargo xtask pose --odometry`; the features alone 0.148).
#[test]
fn odometry_points_on_intel() {
    let Some(d) = shared_carmen("odometry_points_on_intel") else {
        return;
    };
    let log = d.join("intel-corrected.log.gz");
    let run = |points: bool| {
        let mut args = vec!["odometry", "--format", "carmen", arg(&log)];
        if points {
            args.push("--points");
        }
        let out = pfe(&args);
        assert!(out.status.success(), "{}", stderr(&out));
        json_lines(&out)
    };
    let none = |lines: &[serde_json::Value]| lines.iter().filter(|l| l["status"] == "none").count();
    let (with, without) = (run(true), run(false));
    assert_eq!(with.len(), 910);
    assert!(
        none(&with) < none(&without),
        "{} vs {}",
        none(&with),
        none(&without)
    );
    // (x, y, θ) composition: a ∘ b, and a⁻¹.
    let compose = |a: [f64; 3], b: [f64; 3]| {
        let (s, c) = a[2].sin_cos();
        [
            a[0] + c * b[0] - s * b[1],
            a[1] + s * b[0] + c * b[1],
            a[2] + b[2],
        ]
    };
    let inverse = |a: [f64; 3]| {
        let (s, c) = a[2].sin_cos();
        [-(c * a[0] + s * a[1]), s * a[0] - c * a[1], -a[2]]
    };
    let (mut err, mut dist) = (0.0, 0.0);
    let poses: Vec<([f64; 3], [f64; 3])> = with
        .iter()
        .map(|l| {
            let (p, c) = pose_of(&l["pose"]);
            assert!(p.iter().chain(&c).all(|v| v.is_finite()), "{l}");
            let r: Vec<f64> = l["log_pose"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect();
            ([p[0] / 1000.0, p[1] / 1000.0, p[2]], [r[0], r[1], r[2]])
        })
        .collect();
    for w in (0..poses.len() - 50).step_by(50) {
        let est = compose(inverse(poses[w].0), poses[w + 50].0);
        let truth = compose(inverse(poses[w].1), poses[w + 50].1);
        err += (est[0] - truth[0]).hypot(est[1] - truth[1]);
        for k in w..w + 50 {
            let d = compose(inverse(poses[k].1), poses[k + 1].1);
            dist += d[0].hypot(d[1]);
        }
    }
    assert!(dist > 10.0, "{dist} m");
    assert!(err / dist < 0.1, "{} m per m over {dist} m", err / dist);
}

/// `pfe posebench --quick --baseline` on two shared logs: 100 pairs each and the pooled row,
/// with sane figures (failures under 25 %, median errors under 10 cm and 1°, NIS median 1–5);
/// then PL-ICP's rows: from the noisy prior it fails on under 15 % of the pairs, from the
/// identity on more (these logs' scans are up to 1.8 m and 1.4 rad apart).
#[test]
fn posebench_quick_on_two_logs() {
    let Some(d) = shared_carmen("posebench_quick_on_two_logs") else {
        return;
    };
    let logs = [
        d.join("intel-corrected.log.gz"),
        d.join("fhw-corrected.log.gz"),
    ];
    let out = pfe(&[
        "posebench",
        "--quick",
        "--baseline",
        arg(&logs[0]),
        arg(&logs[1]),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8(out.stdout).unwrap();
    let rows: Vec<Vec<&str>> = text
        .lines()
        .skip(2)
        .map(|l| l.trim_matches('|').split('|').map(str::trim).collect())
        .collect();
    assert_eq!(rows.len(), 9, "{text}");
    assert_eq!(
        [rows[0][0], rows[1][0], rows[2][0]],
        ["intel", "fhw", "pooled"]
    );
    assert_eq!(rows[5][0], "pooled · PL-ICP, identity", "{text}");
    assert_eq!(rows[8][0], "pooled · PL-ICP, noisy prior", "{text}");
    let fail = |r: &Vec<&str>| r[2].parse::<f64>().unwrap();
    assert!(
        fail(&rows[8]) < 15.0 && fail(&rows[5]) > fail(&rows[8]),
        "{text}"
    );
    for r in &rows[..3] {
        let num = |i: usize| r[i].parse::<f64>().unwrap();
        let median = |i: usize| {
            r[i].split('/')
                .next()
                .unwrap()
                .trim()
                .parse::<f64>()
                .unwrap()
        };
        assert!(r[1] == "100" || r[1] == "200", "{text}");
        assert!(num(2) < 25.0, "fail % {text}");
        assert!(median(6) < 10.0 && median(7) < 1.0, "{text}");
        assert!((1.0..5.0).contains(&num(8)), "{text}");
    }
}
