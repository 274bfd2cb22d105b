//! `pfe odometry` and `pfe posebench`: poses against the exact truth of an analytic room seen
//! from known poses (CARMEN and csv written here), bad input, and the shared logs (skipped,
//! with a message, when `../shared/data` is absent).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: a panic fails the test

use std::path::PathBuf;

#[path = "../../tests/common/mod.rs"]
mod common;
use common::{arg, json_lines, metadata, pfe, read_foxglove, stderr, TempDir};
use serde_json::Value;

/// A convex room of seven walls (mm, counter-clockwise) and three pillars (centre, radius).
const WALLS: [(f64, f64); 7] = [
    (-4000.0, -3000.0),
    (5000.0, -3500.0),
    (6000.0, 2000.0),
    (2000.0, 3500.0),
    (-1000.0, 3000.0),
    (-3500.0, 2500.0),
    (-4500.0, 0.0),
];
const PILLARS: [(f64, f64, f64); 3] = [
    (2000.0, -1500.0, 150.0),
    (-2000.0, 1500.0, 150.0),
    (3500.0, 1500.0, 200.0),
];

/// The range (mm) from `p` along the world direction `a`: nearest wall or pillar.
fn cast(p: (f64, f64), a: f64) -> f64 {
    let (dx, dy) = (a.cos(), a.sin());
    let mut best = f64::INFINITY;
    for i in 0..WALLS.len() {
        let (a0, a1) = (WALLS[i], WALLS[(i + 1) % WALLS.len()]);
        let (ex, ey) = (a1.0 - a0.0, a1.1 - a0.1);
        let den = dx * ey - dy * ex;
        if den.abs() < 1e-12 {
            continue;
        }
        let (wx, wy) = (a0.0 - p.0, a0.1 - p.1);
        let t = (wx * ey - wy * ex) / den;
        let u = (wx * dy - wy * dx) / den;
        if t > 0.0 && (0.0..=1.0).contains(&u) {
            best = best.min(t);
        }
    }
    for &(cx, cy, r) in &PILLARS {
        let (wx, wy) = (cx - p.0, cy - p.1);
        let b = wx * dx + wy * dy;
        let disc = b * b - (wx * wx + wy * wy - r * r);
        if disc >= 0.0 {
            let t = b - disc.sqrt();
            if t > 0.0 {
                best = best.min(t);
            }
        }
    }
    best
}

/// Deterministic Gaussian noise (xorshift + Box–Muller).
struct Noise(u64);

impl Noise {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn gauss(&mut self, sigma: f64) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        sigma * (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

/// The true poses (mm, rad): a drive through the room, 150–250 mm and up to 0.08 rad a step.
fn truth() -> Vec<[f64; 3]> {
    (0..40)
        .map(|k| {
            let s = k as f64;
            [
                -2500.0 + 110.0 * s,
                -800.0 + 600.0 * (0.12 * s).sin(),
                0.25 * (0.2 * s).sin() + 0.004 * s,
            ]
        })
        .collect()
}

/// 361 ranges (mm) over 180° from pose `p`, with σ noise.
fn ranges(p: &[f64; 3], noise: &mut Noise, sigma: f64) -> Vec<f64> {
    (0..361)
        .map(|i| {
            let b = (-90.0 + 0.5 * i as f64).to_radians();
            cast((p[0], p[1]), p[2] + b) + noise.gauss(sigma)
        })
        .collect()
}

/// A CARMEN log of the drive: FLASER lines with the true pose and odometry `odom` (m, rad).
fn carmen(poses: &[[f64; 3]], odom: &[[f64; 3]]) -> String {
    let mut noise = Noise(0x9e37_79b9_7f4a_7c15);
    let mut s = String::from("PARAM robot_front_laser_max 50.0\n");
    for (k, (p, o)) in poses.iter().zip(odom).enumerate() {
        let r: Vec<String> = ranges(p, &mut noise, 5.0)
            .iter()
            .map(|r| format!("{:.4}", r / 1000.0))
            .collect();
        s += &format!(
            "FLASER 361 {} {:.6} {:.6} {:.6} {:.6} {:.6} {:.6} {}.0 host {}.0\n",
            r.join(" "),
            p[0] / 1000.0,
            p[1] / 1000.0,
            p[2],
            o[0] / 1000.0,
            o[1] / 1000.0,
            o[2],
            k,
            k
        );
    }
    s
}

/// The csv of the same drive (ranges in mm, no pose).
fn csv(poses: &[[f64; 3]]) -> String {
    let mut noise = Noise(0x1234_5678_9abc_def1);
    let mut s = String::new();
    for (k, p) in poses.iter().enumerate() {
        let r: Vec<String> = ranges(p, &mut noise, 5.0)
            .iter()
            .map(|r| format!("{r:.1}"))
            .collect();
        s += &format!("{k},-90,0.5,{}\n", r.join(","));
    }
    s
}

/// `a⁻¹ ⊕ b` (mm, rad).
fn between(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    let (s, c) = a[2].sin_cos();
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let t = b[2] - a[2];
    [c * dx + s * dy, -s * dx + c * dy, t.sin().atan2(t.cos())]
}

/// (x, y, θ, the 3×3 covariance) of a printed pose.
fn pose_of(v: &Value) -> ([f64; 3], [f64; 9]) {
    let f = |k: &str| v[k].as_f64().unwrap();
    let cov: Vec<f64> = v["cov"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_f64().unwrap())
        .collect();
    ([f("x"), f("y"), f("theta")], cov.try_into().unwrap())
}

/// Components (rel and pose, x y θ) beyond their stated 3σ, of how many; every scan
/// registered with rel σ under 25 mm and 0.01 rad; the worst rel error (mm, rad).
fn check_against_truth(lines: &[Value], poses: &[[f64; 3]]) -> (usize, usize, f64, f64) {
    assert_eq!(lines.len(), poses.len());
    let (mut beyond, mut total, mut worst_t, mut worst_r) = (0, 0, 0.0f64, 0.0f64);
    for (k, l) in lines.iter().enumerate().skip(1) {
        let status = l["status"].as_str().unwrap();
        assert_eq!(status, "ok", "scan {k}: {l}");
        let (rel, rel_cov) = pose_of(&l["rel"]);
        let (pose, cov) = pose_of(&l["pose"]);
        // The stated uncertainty is informative (pfe-pose's model floor is 15 mm and 0.46°
        // a line), so that 3σ is a real bound.
        assert!(
            rel_cov[0].sqrt() < 25.0 && rel_cov[4].sqrt() < 25.0 && rel_cov[8].sqrt() < 0.01,
            "scan {k}: {l}"
        );
        let truth_rel = between(&poses[k - 1], &poses[k]);
        let truth_pose = between(&poses[0], &poses[k]);
        for (est, c, t) in [(rel, rel_cov, truth_rel), (pose, cov, truth_pose)] {
            for i in 0..3 {
                let mut e = est[i] - t[i];
                if i == 2 {
                    e = e.sin().atan2(e.cos());
                }
                let sd = c[4 * i].sqrt();
                assert!(sd.is_finite() && sd > 0.0, "scan {k}: {l}");
                total += 1;
                if e.abs() > 3.0 * sd {
                    beyond += 1;
                    eprintln!("scan {k} component {i}: error {e} beyond 3σ = {}", 3.0 * sd);
                }
            }
        }
        worst_t = worst_t.max((rel[0] - truth_rel[0]).hypot(rel[1] - truth_rel[1]));
        worst_r = worst_r.max((rel[2] - truth_rel[2]).abs());
    }
    (beyond, total, worst_t, worst_r)
}

fn write(dir: &TempDir, name: &str, text: &str) -> PathBuf {
    let p = dir.0.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

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

/// The drive of [`truth`] turned by 0.6 rad at every pose (it starts at a heading other than
/// 0, so that the frames' rotations show).
fn turned() -> Vec<[f64; 3]> {
    truth()
        .into_iter()
        .map(|p| [p[0], p[1], p[2] + 0.6])
        .collect()
}

/// Distance (mm) from `p` to the nearest wall or pillar surface of the analytic room.
fn to_room(p: (f64, f64)) -> f64 {
    let mut best = f64::INFINITY;
    for i in 0..WALLS.len() {
        let (a, b) = (WALLS[i], WALLS[(i + 1) % WALLS.len()]);
        let (ex, ey) = (b.0 - a.0, b.1 - a.1);
        let u = (((p.0 - a.0) * ex + (p.1 - a.1) * ey) / (ex * ex + ey * ey)).clamp(0.0, 1.0);
        best = best.min((p.0 - a.0 - u * ex).hypot(p.1 - a.1 - u * ey));
    }
    for &(cx, cy, r) in &PILLARS {
        best = best.min(((p.0 - cx).hypot(p.1 - cy) - r).abs());
    }
    best
}

/// The value of attribute `name` in `tag`.
fn attr<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let key = format!(" {name}=\"");
    let start = tag.find(&key)? + key.len();
    Some(&tag[start..start + tag[start..].find('"')?])
}

/// The data-to-pixel mapping of a plot read from its tick labels alone: (x px of x mm, y px
/// of y mm) as `px = a + b · mm`, from its first and last tick on each axis.
fn axes_of(svg: &str) -> ((f64, f64), (f64, f64)) {
    let unit = if svg.contains("world (m)") || svg.contains("odometry (m)") {
        1000.0
    } else {
        1.0
    };
    let (mut xs, mut ys) = (Vec::new(), Vec::new());
    for part in svg.split("<text ").skip(1) {
        let tag = &format!(" {}", &part[..part.find('>').unwrap()]);
        let label = &part[part.find('>').unwrap() + 1..part.find("</text>").unwrap()];
        let Ok(v) = label.parse::<f64>() else {
            continue;
        };
        match attr(tag, "text-anchor") {
            Some("middle") => xs.push((v * unit, attr(tag, "x").unwrap().parse::<f64>().unwrap())),
            // A y tick's label sits 4 px below the tick.
            Some("end") => ys.push((
                v * unit,
                attr(tag, "y").unwrap().parse::<f64>().unwrap() - 4.0,
            )),
            _ => {}
        }
    }
    let fit = |t: &[(f64, f64)]| {
        let (p, q) = (t[0], t[t.len() - 1]);
        let b = (q.1 - p.1) / (q.0 - p.0);
        (p.1 - b * p.0, b)
    };
    assert!(xs.len() >= 2 && ys.len() >= 2, "ticks {xs:?} {ys:?}");
    (fit(&xs), fit(&ys))
}

/// The points `M x,y …` of a path's or polyline's data in pixels.
fn pixels(data: &str) -> Vec<(f64, f64)> {
    data.split(['M', ' '])
        .filter_map(|t| {
            let t = t.trim_end_matches("h0");
            let (x, y) = t.split_once(',')?;
            Some((x.parse().ok()?, y.parse().ok()?))
        })
        .collect()
}

/// `pfe plot --world --odometry` on the analytic drive (a CARMEN log with the true poses):
/// every drawn point lands on the room's walls and pillars (read back through the figure's
/// own tick labels), the log's trajectory is the truth, the odometry's within 50 mm of it;
/// a csv (no poses) is refused without --odometry and drawn in the odometry's frame with it;
/// a file pfe did not write is never replaced.
#[test]
fn world_plot_puts_the_points_on_the_walls() {
    let dir = TempDir::new("odometry-world");
    let poses = turned();
    let log = write(&dir, "room.log", &carmen(&poses, &poses));
    let svg_path = dir.0.join("world.svg");
    let out = pfe(&[
        "plot",
        "--format",
        "carmen",
        arg(&log),
        "--world",
        arg(&svg_path),
        "--odometry",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let svg = std::fs::read_to_string(&svg_path).unwrap();
    let ((ax, bx), (ay, by)) = axes_of(&svg);
    let world = |(px, py): (f64, f64)| ((px - ax) / bx, (py - ay) / by);
    // Equal scales, y up.
    assert!((bx + by).abs() < 1e-3 * bx.abs() && bx > 0.0, "{bx} {by}");
    let points_tag = svg
        .split("<path ")
        .find(|t| t.contains(r##"stroke="#5a6b7d""##))
        .unwrap();
    let points = pixels(attr(&format!(" {points_tag}"), "d").unwrap());
    // 40 scans, every one drawn, 361 returns each.
    assert_eq!(points.len(), 40 * 361);
    let worst = points
        .iter()
        .map(|&p| to_room(world(p)))
        .fold(0.0f64, f64::max);
    // 5 mm range noise, 0.05 px of rounding (under 1 mm here).
    eprintln!("points: worst {worst:.1} mm off the room");
    assert!(worst < 30.0, "a point {worst} mm off the room");
    let polyline = |class: &str| -> Vec<(f64, f64)> {
        let tag = svg
            .split("<polyline ")
            .find(|t| t.contains(&format!(r#"class="{class}""#)))
            .unwrap();
        pixels(attr(&format!(" {tag}"), "points").unwrap())
            .into_iter()
            .map(world)
            .collect()
    };
    let (log_track, odo_track) = (polyline("log-trajectory"), polyline("odometry-trajectory"));
    assert_eq!((log_track.len(), odo_track.len()), (40, 40));
    let mut worst_odo = 0.0f64;
    for ((l, o), t) in log_track.iter().zip(&odo_track).zip(&poses) {
        assert!((l.0 - t[0]).hypot(l.1 - t[1]) < 2.0, "{l:?} vs {t:?}");
        worst_odo = worst_odo.max((o.0 - t[0]).hypot(o.1 - t[1]));
    }
    eprintln!("odometry: worst {worst_odo:.1} mm from the truth");
    assert!(worst_odo < 50.0, "odometry {worst_odo} mm off");
    assert!(svg.contains("placed by the log") && svg.contains("40 ok, 0 degenerate, 0 none"));

    // No poses: refused alone, in the odometry's frame with --odometry.
    let csv = write(&dir, "room.csv", &csv(&poses));
    let other = dir.0.join("csv.svg");
    let out = pfe(&["plot", "--format", "csv", arg(&csv), "--world", arg(&other)]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("no scan has a pose"),
        "{}",
        stderr(&out)
    );
    assert!(!other.exists());
    let out = pfe(&[
        "plot",
        "--format",
        "csv",
        arg(&csv),
        "--world",
        arg(&other),
        "--odometry",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(std::fs::read_to_string(&other)
        .unwrap()
        .contains("placed by the odometry"));

    // A file of the user's: left alone (exit 2), replaced with --force; pfe's own: replaced.
    let mine = write(&dir, "mine.svg", "<svg>mine</svg>");
    let args = [
        "plot",
        "--format",
        "carmen",
        arg(&log),
        "--world",
        arg(&mine),
    ];
    let out = pfe(&args);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert_eq!(std::fs::read_to_string(&mine).unwrap(), "<svg>mine</svg>");
    let out = pfe(&[
        "plot",
        "--format",
        "carmen",
        arg(&log),
        "--world",
        arg(&svg_path),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let out = pfe(&[&args[..], &["--force"]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
}

/// `pfe odometry --mcap` on the analytic drive, read back by Python's `mcap`: per scan the
/// scan, its features, the frames (odom → laser: the pose printed on stdout; world → odom:
/// the log's first pose), the pose, the map and the trajectories; the map's lines lie on the
/// room's walls once the odometry frame is put at the first true pose; an existing file is
/// left alone without --force.
#[test]
fn odometry_mcap_holds_trajectory_and_map() {
    const TEST: &str = "cli_odometry::odometry_mcap_holds_trajectory_and_map";
    let dir = TempDir::new("odometry-mcap");
    let poses = turned();
    let log = write(&dir, "room.log", &carmen(&poses, &poses));
    let path = dir.0.join("run.mcap");
    let out = pfe(&[
        "odometry",
        "--format",
        "carmen",
        arg(&log),
        "--mcap",
        arg(&path),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let lines = json_lines(&out);
    assert_eq!(lines.len(), 40);
    // Never over an existing file without --force.
    let again = pfe(&[
        "odometry",
        "--format",
        "carmen",
        arg(&log),
        "--mcap",
        arg(&path),
    ]);
    assert_eq!(again.status.code(), Some(2), "{}", stderr(&again));
    assert!(again.stdout.is_empty());
    let Some(back) = read_foxglove(TEST, &path) else {
        return;
    };
    let messages = back["messages"].as_array().unwrap();
    let on = |topic: &str| -> Vec<&Value> {
        messages
            .iter()
            .filter(|m| m["topic"] == topic)
            .map(|m| &m["data"])
            .collect()
    };
    for (topic, n) in [
        ("/scan", 40),
        ("/features", 40),
        ("/tf", 80),
        ("/odometry/pose", 40),
        ("/odometry/map", 40),
        ("/odometry/trajectory", 40),
        ("/log/trajectory", 40),
    ] {
        assert_eq!(on(topic).len(), n, "{topic}");
    }
    let schema = |topic: &str| {
        back["channels"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["topic"] == topic)
            .map(|c| c["schema"].as_str().unwrap().to_string())
    };
    assert_eq!(schema("/tf").as_deref(), Some("foxglove.FrameTransform"));
    assert_eq!(
        schema("/odometry/pose").as_deref(),
        Some("foxglove.PoseInFrame")
    );
    assert_eq!(
        schema("/odometry/trajectory").as_deref(),
        Some("foxglove.PosesInFrame")
    );
    assert_eq!(
        schema("/odometry/map").as_deref(),
        Some("foxglove.SceneUpdate")
    );
    let f = |v: &Value| v.as_f64().unwrap();
    let yaw = |q: &Value| 2.0 * f(&q["z"]).atan2(f(&q["w"]));
    let tf = on("/tf");
    for (k, l) in lines.iter().enumerate() {
        let (p, _) = pose_of(&l["pose"]);
        let (odom, world) = (tf[2 * k], tf[2 * k + 1]);
        assert_eq!(
            (&odom["parent_frame_id"], &odom["child_frame_id"]),
            (&Value::from("odom"), &Value::from("laser"))
        );
        assert!(
            (f(&odom["translation"]["x"]) * 1000.0 - p[0]).abs() < 0.01,
            "{odom}"
        );
        assert!(
            (f(&odom["translation"]["y"]) * 1000.0 - p[1]).abs() < 0.01,
            "{odom}"
        );
        assert!((yaw(&odom["rotation"]) - p[2]).abs() < 1e-6, "{odom}");
        assert_eq!(world["parent_frame_id"], "world");
        assert!((f(&world["translation"]["x"]) * 1000.0 - poses[0][0]).abs() < 0.01);
        assert!((yaw(&world["rotation"]) - poses[0][2]).abs() < 1e-6);
        let pose = on("/odometry/pose")[k];
        assert_eq!(pose["frame_id"], "odom");
        assert!((f(&pose["pose"]["position"]["x"]) * 1000.0 - p[0]).abs() < 0.01);
    }
    let trajectory = on("/odometry/trajectory");
    assert_eq!(trajectory[39]["poses"].as_array().unwrap().len(), 40);
    let log_track = on("/log/trajectory")[39]["poses"]
        .as_array()
        .unwrap()
        .clone();
    assert!((f(&log_track[39]["position"]["x"]) * 1000.0 - poses[39][0]).abs() < 0.01);
    // The map at the end: lines on the walls, in the world through the first true pose.
    let map = on("/odometry/map")[39]["entities"]
        .as_array()
        .unwrap()
        .clone();
    let (s0, c0) = poses[0][2].sin_cos();
    let to_world = |p: &Value| {
        let (x, y) = (f(&p["x"]) * 1000.0, f(&p["y"]) * 1000.0);
        (poses[0][0] + c0 * x - s0 * y, poses[0][1] + s0 * x + c0 * y)
    };
    let mut n_lines = 0;
    let mut worst = 0.0f64;
    for e in &map {
        match metadata(e, "kind").as_str() {
            "line" => {
                n_lines += 1;
                for p in e["lines"][0]["points"].as_array().unwrap() {
                    worst = worst.max(to_room(to_world(p)));
                }
            }
            "pose" => assert_eq!(metadata(e, "status"), "ok"),
            _ => {}
        }
    }
    eprintln!("map: {n_lines} lines, their ends at most {worst:.1} mm off the walls");
    assert!(n_lines >= 4 && worst < 50.0, "{n_lines} lines, {worst} mm");
}
