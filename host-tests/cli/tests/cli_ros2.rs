//! `pfe extract --format mcap` and `--mcap OUT` from the command line: a bag written by
//! `fixtures/ros2/make_bags.py` (Python `mcap-ros2-support`) gives the CARMEN reader's features;
//! several LaserScan topics are listed (exit 2); an existing `--mcap` file is kept; the Foxglove
//! file reads back (`fixtures/foxglove/read_foxglove.py`) with one LaserScan and one SceneUpdate
//! per scan. The Python-backed checks report a skip through `pfe_testkit::skip` without python3
//! or its packages (a failure under `CI=true`); the bags written here with the `mcap` crate run
//! everywhere.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: a panic fails the test

use std::collections::BTreeMap;
use std::io::Cursor;
use std::path::{Path, PathBuf};

use pfe_testkit::skip::{skip, Need};
use serde_json::Value;

const N_SCANS: usize = 30;

#[path = "../../tests/common/mod.rs"]
mod common;
use common::{arg, fixture, json_lines, pfe, python, read_foxglove, stderr, TempDir};

#[test]
fn a_bag_extracts_as_the_carmen_log_it_was_made_from() {
    const TEST: &str = "cli_ros2::a_bag_extracts_as_the_carmen_log_it_was_made_from";
    let logs = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/carmen");
    if !logs.is_dir() {
        skip(
            TEST,
            "the shared CARMEN logs (../shared/data/carmen) are absent",
            Need::InCi,
        );
        return;
    }
    let dir = TempDir::new("bags");
    let n = N_SCANS.to_string();
    let args = [arg(&dir.0), arg(&logs), n.as_str()];
    let Some(manifest) = python(TEST, "ros2/make_bags.py", &args, "mcap mcap-ros2-support") else {
        return;
    };
    // A LaserScan bag does not say that its scanner interleaves sweeps: `--sweeps auto`
    // detects them from the scans (csail, 0.5°: 2 once the robot moves; intel, 1°: 1), as the
    // CARMEN reader's format rule takes them for these SICK logs.
    for name in ["intel", "csail"] {
        let m = &manifest[name];
        let bag = pfe(&["extract", "--format", "mcap", m["bag"].as_str().unwrap()]);
        assert!(bag.status.success(), "{name}: {}", stderr(&bag));
        let log = pfe(&["extract", "--format", "carmen", m["log"].as_str().unwrap()]);
        assert!(log.status.success(), "{name}: {}", stderr(&log));
        let (bag, log) = (json_lines(&bag), json_lines(&log));
        assert_eq!(bag.len(), N_SCANS, "{name}");
        let stamps = m["stamps_ns"].as_array().unwrap();
        let mut features = 0;
        for (k, (b, c)) in bag.iter().zip(&log).enumerate() {
            // The same scan, marks and features, bit for bit (σ_r 10 mm for both by default;
            // the bag's float32 metres give the CARMEN reader's mm).
            assert_eq!(
                (&b["scan"], &b["marks"], &b["features"]),
                (&c["scan"], &c["marks"], &c["features"]),
                "{name} scan {k}"
            );
            features += b["features"].as_array().unwrap().len();
            // The bag's stamp and frame are kept; CARMEN lines have neither.
            assert_eq!(b["stamp_ns"], stamps[k], "{name} scan {k}");
            assert_eq!(b["frame_id"], m["frame_id"], "{name} scan {k}");
            assert!(c.get("stamp_ns").is_none() && c.get("frame_id").is_none());
        }
        assert!(features > N_SCANS, "{name}: {features} features");
    }
    // No LaserScan topic: a clear error, exit 2.
    let none = pfe(&[
        "extract",
        "--format",
        "mcap",
        manifest["no_laser"]["bag"].as_str().unwrap(),
    ]);
    assert_eq!(none.status.code(), Some(2));
    assert!(
        stderr(&none).contains("no sensor_msgs/msg/LaserScan topic"),
        "{}",
        stderr(&none)
    );
}

// ---- Bags written here with the mcap crate. ----

/// A little-endian CDR LaserScan, frame `frame`, stamped `sec` s, 181 beams over 180° at 2 m
/// with a 1 m box in front (beams 80..100) and beam 5 out of range.
fn cdr_scan(sec: i32, frame: &str) -> Vec<u8> {
    let mut b = vec![0, 1, 0, 0];
    b.extend(sec.to_le_bytes());
    b.extend(0u32.to_le_bytes());
    let name_len = frame.len() + 1;
    b.extend((name_len as u32).to_le_bytes());
    b.extend(frame.as_bytes());
    b.push(0);
    while b.len() % 4 != 0 {
        b.push(0);
    }
    let n = 181usize;
    let step = std::f32::consts::PI / (n - 1) as f32;
    let min = -std::f32::consts::FRAC_PI_2;
    for v in [min, min + step * (n - 1) as f32, step, 0.0, 0.1, 0.02, 30.0] {
        b.extend(v.to_le_bytes());
    }
    b.extend((n as u32).to_le_bytes());
    for i in 0..n {
        let bearing = min + step * i as f32;
        let r = match i {
            5 => 40.0,
            80..=100 => 1.0 / bearing.cos(),
            _ => 2.0,
        };
        b.extend(r.to_le_bytes());
    }
    b.extend(0u32.to_le_bytes());
    b
}

const LASER_SCAN_DEF: &str = "std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\n\
float32 angle_increment\nfloat32 time_increment\nfloat32 scan_time\nfloat32 range_min\n\
float32 range_max\nfloat32[] ranges\nfloat32[] intensities\n";

/// A bag with `scans` LaserScans on each of `topics` (frame = the topic's last name part
/// before `/scan`, or "laser"), stamped 1 s, 2 s, ….
fn bag(topics: &[&str], scans: i32) -> Vec<u8> {
    let mut out = Cursor::new(Vec::new());
    let mut w = common::mcap_writer(&mut out, 4096);
    let schema = w
        .add_schema(
            "sensor_msgs/msg/LaserScan",
            "ros2msg",
            LASER_SCAN_DEF.as_bytes(),
        )
        .unwrap();
    for topic in topics {
        let channel = w
            .add_channel(schema, topic, "cdr", &BTreeMap::new())
            .unwrap();
        let frame = match topic.trim_end_matches("/scan").trim_start_matches('/') {
            "" => "laser",
            f => f,
        };
        for k in 0..scans {
            let t = (k as u64 + 1) * 1_000_000_000;
            let header = mcap::records::MessageHeader {
                channel_id: channel,
                sequence: k as u32,
                log_time: t,
                publish_time: t,
            };
            w.write_to_known_channel(&header, &cdr_scan(k + 1, frame))
                .unwrap();
        }
    }
    w.finish().unwrap();
    drop(w);
    out.into_inner()
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> String {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    arg(&p).to_string()
}

#[test]
fn two_laser_topics_are_listed_and_one_is_chosen_with_topic() {
    let dir = TempDir::new("topics");
    let two = write(&dir.0, "two.mcap", &bag(&["/scan", "/rear/scan"], 4));
    let out = pfe(&["extract", "--format", "mcap", &two]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(out.stdout.is_empty());
    let err = stderr(&out);
    assert!(
        err.contains("choose one with --topic")
            && err.contains("/scan [")
            && err.contains("/rear/scan ["),
        "{err}"
    );
    let rear = pfe(&["extract", "--format", "mcap", "--topic", "/rear/scan", &two]);
    assert!(rear.status.success(), "{}", stderr(&rear));
    let rear = json_lines(&rear);
    assert_eq!(rear.len(), 4);
    assert!(rear.iter().all(|l| l["frame_id"] == "rear"));
    assert_eq!(rear[3]["stamp_ns"], 4_000_000_000u64);
    let missing = pfe(&["extract", "--format", "mcap", "--topic", "/front", &two]);
    assert_eq!(missing.status.code(), Some(2));
    assert!(stderr(&missing).contains("/front is not a sensor_msgs/msg/LaserScan topic"));
    // The only topic is chosen without --topic; plot reads bags too.
    let one = write(&dir.0, "one.mcap", &bag(&["/scan"], 3));
    let out = pfe(&["extract", "--format", "mcap", &one]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(json_lines(&out).len(), 3);
    let svg = pfe(&["plot", "--format", "mcap", &one, "--scan", "2", "-o", "-"]);
    assert!(svg.status.success(), "{}", stderr(&svg));
    assert!(String::from_utf8_lossy(&svg.stdout).contains("(laser, 3.000000000 s)"));
}

#[test]
fn a_truncated_bag_prints_its_earlier_scans_then_fails() {
    let dir = TempDir::new("cut");
    let bytes = bag(&["/scan"], 40);
    let cut = write(&dir.0, "cut.mcap", &bytes[..bytes.len() / 2]);
    let out = pfe(&["extract", "--format", "mcap", &cut]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let kept = json_lines(&out);
    assert!(!kept.is_empty() && kept.len() < 40, "{} scans", kept.len());
    assert!(stderr(&out).contains("truncated"), "{}", stderr(&out));
    // Not a bag at all: named, with a hint at the right format.
    let log = fixture("room.log");
    let out = pfe(&["extract", "--format", "mcap", arg(&log)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("not an MCAP file") && stderr(&out).contains("try --format carmen")
    );
    // A bag read as another format: the hint names mcap.
    let whole = write(&dir.0, "whole.mcap", &bytes);
    let out = pfe(&["extract", "--format", "carmen", &whole]);
    assert_eq!(out.status.code(), Some(2));
    let err = stderr(&out);
    assert!(err.contains("try --format mcap"), "{err}");
}

#[test]
fn mcap_output_never_replaces_a_file_without_force() {
    let dir = TempDir::new("force");
    let one = write(&dir.0, "one.mcap", &bag(&["/scan"], 3));
    let out_path = dir.0.join("features.mcap");
    std::fs::write(&out_path, b"mine").unwrap();
    let out_arg = arg(&out_path);
    let out = pfe(&["extract", "--format", "mcap", &one, "--mcap", out_arg]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("--force"), "{}", stderr(&out));
    assert!(out.stdout.is_empty(), "scans were read before refusing");
    assert_eq!(std::fs::read(&out_path).unwrap(), b"mine");
    let out = pfe(&[
        "extract", "--format", "mcap", &one, "--mcap", out_arg, "--force",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(std::fs::read(&out_path).unwrap().starts_with(mcap::MAGIC));
    // --force alone is a bad argument.
    let out = pfe(&["extract", "--format", "mcap", &one, "--force"]);
    assert_eq!(out.status.code(), Some(2));
    // No temporary file left beside it.
    let mut names: Vec<_> = std::fs::read_dir(&dir.0)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    names.sort();
    assert_eq!(names, ["features.mcap", "one.mcap"]);
}

/// The messages of the Foxglove file: (scan, scene) pairs, in order.
fn pairs(back: &Value) -> Vec<(&Value, &Value)> {
    let m = back["messages"].as_array().unwrap();
    assert_eq!(m.len() % 2, 0);
    m.chunks(2).map(|c| (&c[0], &c[1])).collect()
}

#[test]
fn foxglove_output_holds_one_laser_scan_and_one_scene_update_per_scan() {
    const TEST: &str =
        "cli_ros2::foxglove_output_holds_one_laser_scan_and_one_scene_update_per_scan";
    let dir = TempDir::new("foxglove");
    // A bag: its stamps and frame.
    let one = write(&dir.0, "one.mcap", &bag(&["/scan"], 5));
    let fox = dir.0.join("bag-features.mcap");
    let out = pfe(&["extract", "--format", "mcap", &one, "--mcap", arg(&fox)]);
    assert!(out.status.success(), "{}", stderr(&out));
    let json = json_lines(&out);
    let Some(back) = read_foxglove(TEST, &fox) else {
        return;
    };
    let names: Vec<(&str, &str)> = back["channels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| (c["topic"].as_str().unwrap(), c["schema"].as_str().unwrap()))
        .collect();
    assert_eq!(
        names,
        [
            ("/scan", "foxglove.LaserScan"),
            ("/features", "foxglove.SceneUpdate")
        ]
    );
    let p = pairs(&back);
    assert_eq!(p.len(), 5);
    for (k, ((scan, scene), line)) in p.iter().zip(&json).enumerate() {
        let t = (k as u64 + 1) * 1_000_000_000;
        assert_eq!(
            (scan["topic"].as_str(), scene["topic"].as_str()),
            (Some("/scan"), Some("/features"))
        );
        assert_eq!(
            (scan["log_time"].as_u64(), scene["log_time"].as_u64()),
            (Some(t), Some(t))
        );
        assert_eq!(scan["data"]["frame_id"], "laser");
        let ranges = scan["data"]["ranges"].as_array().unwrap();
        assert_eq!(ranges.len(), 181);
        assert_eq!(ranges[5], 0.0, "out of range: 0 m");
        let entities = scene["data"]["entities"].as_array().unwrap();
        assert_eq!(
            entities.len(),
            line["features"].as_array().unwrap().len(),
            "scan {k}"
        );
        assert!(!entities.is_empty());
    }

    // CARMEN: frame "laser", stamps 0.1 s apart from 0.
    let fox = dir.0.join("room-features.mcap");
    let room = fixture("room.log");
    let out = pfe(&[
        "extract",
        "--format",
        "carmen",
        arg(&room),
        "--mcap",
        arg(&fox),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let json = json_lines(&out);
    let back = read_foxglove(TEST, &fox).unwrap();
    let p = pairs(&back);
    assert_eq!(p.len(), json.len());
    for (k, ((scan, scene), line)) in p.iter().zip(&json).enumerate() {
        let t = k as u64 * 100_000_000;
        assert_eq!(
            (scan["log_time"].as_u64(), scene["log_time"].as_u64()),
            (Some(t), Some(t))
        );
        assert_eq!(scan["data"]["frame_id"], "laser");
        assert_eq!(
            scene["data"]["entities"].as_array().unwrap().len(),
            line["features"].as_array().unwrap().len()
        );
    }
}
