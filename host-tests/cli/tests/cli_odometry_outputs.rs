//! `pfe odometry`'s outputs beyond its JSON lines: `pfe plot --world` (the log in the world
//! frame beside the odometry) and `pfe odometry --mcap` (trajectory and map for Foxglove), on
//! the analytic room of `cli_odometry`.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: a panic fails the test

#[path = "../../tests/common/mod.rs"]
mod common;
#[path = "room/mod.rs"]
mod room;
use common::{arg, json_lines, metadata, pfe, read_foxglove, stderr, TempDir};
use room::*;
use serde_json::Value;

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

/// Runs `pfe plot --format FORMAT FILE --world SVG` with `extra` arguments.
fn world_plot(
    format: &str,
    file: &std::path::Path,
    svg: &std::path::Path,
    extra: &[&str],
) -> std::process::Output {
    pfe(&[
        &["plot", "--format", format, arg(file), "--world", arg(svg)],
        extra,
    ]
    .concat())
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
    let out = world_plot("carmen", &log, &svg_path, &["--odometry"]);
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
    let out = world_plot("csv", &csv, &other, &[]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("no scan has a pose"),
        "{}",
        stderr(&out)
    );
    assert!(!other.exists());
    let out = world_plot("csv", &csv, &other, &["--odometry"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(std::fs::read_to_string(&other)
        .unwrap()
        .contains("placed by the odometry"));

    // A file of the user's: left alone (exit 2), replaced with --force; pfe's own: replaced.
    let mine = write(&dir, "mine.svg", "<svg>mine</svg>");
    let out = world_plot("carmen", &log, &mine, &[]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert_eq!(std::fs::read_to_string(&mine).unwrap(), "<svg>mine</svg>");
    let out = world_plot("carmen", &log, &svg_path, &[]);
    assert!(out.status.success(), "{}", stderr(&out));
    let out = world_plot("carmen", &log, &mine, &["--force"]);
    assert!(out.status.success(), "{}", stderr(&out));
}

/// `pfe plot --world --odometry --points` draws the odometry `pfe odometry --points` prints
/// (its trajectory, placed at the log's first pose, within 5 mm of those poses; named "with
/// points" in the legend; without `--points` "features"); `--points` without `--odometry` is
/// refused.
#[test]
fn world_plot_draws_the_odometry_with_points_when_asked() {
    let dir = TempDir::new("odometry-world-points");
    let poses = turned();
    let log = write(&dir, "room.log", &carmen(&poses, &poses));
    for points in [false, true] {
        let svg_path = dir.0.join(format!("world-{points}.svg"));
        let mut odometry = vec!["odometry", "--format", "carmen", arg(&log)];
        let extra: &[&str] = if points {
            odometry.push("--points");
            &["--odometry", "--points"]
        } else {
            &["--odometry"]
        };
        let out = world_plot("carmen", &log, &svg_path, extra);
        assert!(out.status.success(), "{}", stderr(&out));
        let svg = std::fs::read_to_string(&svg_path).unwrap();
        let label = if points {
            "odometry with points (40 scans)"
        } else {
            "odometry, features (40 scans)"
        };
        assert!(svg.contains(label), "{points}: no {label:?}");
        let ((ax, bx), (ay, by)) = axes_of(&svg);
        let tag = svg
            .split("<polyline ")
            .find(|t| t.contains(r#"class="odometry-trajectory""#))
            .unwrap();
        let drawn: Vec<(f64, f64)> = pixels(attr(&format!(" {tag}"), "points").unwrap())
            .into_iter()
            .map(|(px, py)| ((px - ax) / bx, (py - ay) / by))
            .collect();
        let out = pfe(&odometry);
        assert!(out.status.success(), "{}", stderr(&out));
        let printed: Vec<[f64; 3]> = json_lines(&out)
            .iter()
            .map(|l| pose_of(&l["pose"]).0)
            .collect();
        assert_eq!((drawn.len(), printed.len()), (40, 40));
        let (s, c) = poses[0][2].sin_cos();
        for (d, p) in drawn.iter().zip(&printed) {
            let w = (
                poses[0][0] + c * p[0] - s * p[1],
                poses[0][1] + s * p[0] + c * p[1],
            );
            assert!(
                (d.0 - w.0).hypot(d.1 - w.1) < 5.0,
                "{points}: drawn {d:?}, printed {w:?}"
            );
        }
    }
    let svg_path = dir.0.join("alone.svg");
    let out = world_plot("carmen", &log, &svg_path, &["--points"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(!svg_path.exists());
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
