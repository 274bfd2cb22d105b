//! ROS 2 bags (MCAP, `sensor_msgs/msg/LaserScan`) read by `formats::ros2`.
//!
//! Bags written independently of this code (`fixtures/ros2/make_bags.py`: the Python `mcap` and
//! `mcap-ros2-support` packages, from the first 50 scans of two shared CARMEN logs) must give
//! the CARMEN reader's scans and, through pfe-core, its features. Without python3 or those
//! packages the Python-backed tests report a skip through `pfe_testkit::skip` and pass, except
//! under `CI=true`, where they fail. Bags written here with the `mcap` crate check the error paths (no LaserScan
//! topic, truncation, damage) everywhere.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: a panic fails the test

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::io::Cursor;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;

use pfe_core::{Config, Feature};
use pfe_eval::methods::{Method, Pfe};
use pfe_formats::ros2::{self, Ros2Scan, TopicError};
use pfe_formats::{self as formats, Format, InputError, Record};
use serde_json::Value;

mod common;

use common::TempDir;

const N_SCANS: usize = 50;

fn shared_carmen() -> Option<PathBuf> {
    let d = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/carmen");
    d.is_dir().then_some(d)
}

/// Reports the skip of the Python-backed test (listed by `cargo xtask test`; a failure under
/// `CI=true`, where python3, the packages and the shared logs are installed).
fn skip(why: &str) -> Option<Value> {
    pfe_testkit::skip::skip(
        "ros2_mcap::independent_bags_read_as_the_carmen_logs",
        &format!("{why} (install python3 and `pip install mcap mcap-ros2-support`)"),
        pfe_testkit::skip::Need::InCi,
    );
    None
}

/// Runs make_bags.py into `dir`; its JSON manifest, or `None` when skipped.
fn make_bags(dir: &Path) -> Option<Value> {
    let Some(logs) = shared_carmen() else {
        return skip("the shared CARMEN logs (../shared/data/carmen) are absent");
    };
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/ros2/make_bags.py");
    let out = match Command::new("python3")
        .arg(&script)
        .arg(dir)
        .arg(&logs)
        .arg(N_SCANS.to_string())
        .output()
    {
        Ok(out) => out,
        Err(e) => return skip(&format!("python3 cannot be run ({e})")),
    };
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        if stderr.contains("ModuleNotFoundError") {
            return skip(&format!(
                "the Python packages mcap and mcap-ros2-support are missing: {}",
                stderr.lines().last().unwrap_or("")
            ));
        }
        panic!("make_bags.py failed: {stderr}");
    }
    Some(serde_json::from_slice(&out.stdout).unwrap())
}

fn carmen_records(log: &Path, n: usize) -> Vec<Record> {
    let input = formats::open_for(log, Format::Carmen, |r| r).unwrap();
    formats::scans(Format::Carmen, input)
        .take(n)
        .map(Result::unwrap)
        .collect()
}

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol * (1.0 + a.abs().max(b.abs()))
}

fn assert_features_match(a: &[Feature], b: &[Feature], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: feature count");
    for (k, (fa, fb)) in a.iter().zip(b).enumerate() {
        match (fa, fb) {
            (Feature::Line(x), Feature::Line(y)) => {
                assert_eq!((x.first, x.last), (y.first, y.last), "{what}: line {k}");
                assert!(
                    close(x.alpha, y.alpha, 1e-5),
                    "{what}: line {k} α {x:?} {y:?}"
                );
                assert!(close(x.rho, y.rho, 1e-5), "{what}: line {k} ρ {x:?} {y:?}");
                assert!(close(x.var_rho, y.var_rho, 1e-3), "{what}: line {k} σρ²");
                assert!(close(x.start.x, y.start.x, 1e-5) && close(x.end.y, y.end.y, 1e-5));
            }
            (Feature::Circle(x), Feature::Circle(y)) => {
                assert_eq!((x.first, x.last), (y.first, y.last), "{what}: circle {k}");
                assert!(
                    close(x.center.x, y.center.x, 1e-5),
                    "{what}: circle {k} {x:?} {y:?}"
                );
                assert!(close(x.center.y, y.center.y, 1e-5), "{what}: circle {k}");
                assert!(close(x.radius, y.radius, 1e-5), "{what}: circle {k} radius");
            }
            (Feature::Object(x), Feature::Object(y)) => {
                assert_eq!((x.first, x.last), (y.first, y.last), "{what}: object {k}");
                assert!(
                    close(x.center.x, y.center.x, 1e-5) && close(x.center.y, y.center.y, 1e-5),
                    "{what}: object {k} {x:?} {y:?}"
                );
                assert!(close(x.extent, y.extent, 1e-5), "{what}: object {k} extent");
            }
            _ => panic!("{what}: feature {k} differs in kind: {fa:?} vs {fb:?}"),
        }
    }
}

/// The bag of `name` gives, scan for scan, the CARMEN reader's geometry, ranges and features,
/// and the stamps and frame the script wrote.
fn check_bag_against_carmen(manifest: &Value, name: &str) {
    let m = &manifest[name];
    let bag = PathBuf::from(m["bag"].as_str().unwrap());
    let expected = carmen_records(Path::new(m["log"].as_str().unwrap()), N_SCANS);
    let scans: Vec<Ros2Scan> = ros2::read_laser_scans(&bag, None)
        .unwrap()
        .map(Result::unwrap)
        .collect();
    assert_eq!(scans.len(), N_SCANS, "{name}: scans in the bag");
    assert_eq!(expected.len(), N_SCANS, "{name}: scans in the log");
    let stamps = m["stamps_ns"].as_array().unwrap();
    let mut pfe_carmen = Pfe::new("carmen", Config::default().with_sigma_r(10.0));
    let mut pfe_bag = Pfe::new("bag", Config::default().with_sigma_r(10.0));
    let mut features = 0;
    for (i, (s, c)) in scans.iter().zip(&expected).enumerate() {
        let what = format!("{name} scan {i}");
        assert_eq!(s.stamp_ns, stamps[i].as_u64().unwrap(), "{what}: stamp");
        assert_eq!(s.frame_id, m["frame_id"].as_str().unwrap(), "{what}: frame");
        let (g, h) = (&s.record.geometry, &c.geometry);
        assert_eq!(s.record.id, i as u64, "{what}: id");
        assert!(
            close(g.start_angle, h.start_angle, 1e-6),
            "{what}: {g:?} vs {h:?}"
        );
        assert!(
            close(g.angle_step, h.angle_step, 1e-6),
            "{what}: {g:?} vs {h:?}"
        );
        assert!(close(g.r_max, h.r_max, 1e-6), "{what}: {g:?} vs {h:?}");
        assert_eq!(s.record.ranges_mm.len(), c.ranges_mm.len(), "{what}: beams");
        for (k, (a, b)) in s.record.ranges_mm.iter().zip(&c.ranges_mm).enumerate() {
            assert!(
                (a.is_nan() && b.is_nan()) || (a - b).abs() <= 0.01,
                "{what} beam {k}: bag {a} mm, log {b} mm"
            );
        }
        let fa = pfe_bag.extract(g, &s.record.ranges_mm).features;
        let fb = pfe_carmen.extract(h, &c.ranges_mm).features;
        assert_features_match(&fa, &fb, &what);
        features += fa.len();
    }
    assert!(
        features > N_SCANS,
        "{name}: only {features} features in {N_SCANS} scans"
    );
    // Some beams are no return in both logs (REP 117 ±inf in intel, raw 81.91 m in csail).
    assert!(scans
        .iter()
        .any(|s| s.record.ranges_mm.iter().any(|r| r.is_nan())));
}

#[test]
fn independent_bags_read_as_the_carmen_logs() {
    let dir = TempDir::new("ros2-bags");
    let Some(manifest) = make_bags(&dir.0) else {
        return;
    };
    check_bag_against_carmen(&manifest, "intel");
    check_bag_against_carmen(&manifest, "csail");

    // intel.mcap also holds /chatter (std_msgs/msg/String): listed, not read.
    let intel = PathBuf::from(manifest["intel"]["bag"].as_str().unwrap());
    let topics = ros2::topics(&intel).unwrap();
    let names: Vec<&str> = topics.iter().map(|t| t.topic.as_str()).collect();
    assert_eq!(names, ["/chatter", "/scan"]);
    assert_eq!(topics[1].messages, N_SCANS as u64);
    assert_eq!(ros2::laser_topics(&intel).unwrap().len(), 1);

    // Two LaserScan topics: a topic must be named.
    let two = PathBuf::from(manifest["two_lasers"]["bag"].as_str().unwrap());
    match ros2::read_laser_scans(&two, None) {
        Err(e @ TopicError::Ambiguous { .. }) => {
            let text = e.to_string();
            assert!(
                text.contains("/scan") && text.contains("/rear/scan"),
                "{text}"
            );
        }
        other => panic!("expected Ambiguous, got {:?}", other.map(|_| ())),
    }
    let rear: Vec<Ros2Scan> = ros2::read_laser_scans(&two, Some("/rear/scan"))
        .unwrap()
        .map(Result::unwrap)
        .collect();
    assert_eq!(rear.len(), 3);
    assert!(rear.iter().all(|s| s.frame_id == "rear"));
    assert!(matches!(
        ros2::read_laser_scans(&two, Some("/chatter")),
        Err(TopicError::NotFound { .. })
    ));

    // No LaserScan topic at all.
    let none = PathBuf::from(manifest["no_laser"]["bag"].as_str().unwrap());
    match ros2::read_laser_scans(&none, None) {
        Err(e @ TopicError::NoLaserScan { .. }) => {
            assert!(e.to_string().contains("/chatter"), "{e}");
        }
        other => panic!("expected NoLaserScan, got {:?}", other.map(|_| ())),
    }

    // A truncated copy keeps the scans of its complete chunks, then says it is truncated.
    let full: Vec<Ros2Scan> = ros2::read_laser_scans(&intel, None)
        .unwrap()
        .map(Result::unwrap)
        .collect();
    let bytes = std::fs::read(&intel).unwrap();
    let cut = dir.0.join("intel-cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() * 6 / 10]).unwrap();
    let (ok, err) = split(ros2::read_laser_scans(&cut, None).unwrap().collect());
    assert!(
        !ok.is_empty() && ok.len() < N_SCANS,
        "{} scans kept",
        ok.len()
    );
    assert!(
        is_prefix(&ok, &full),
        "the kept scans differ from the intact bag's"
    );
    let err = err.expect("a truncated bag ends in an error");
    assert!(err.to_string().contains("truncated"), "{err}");
}

/// Equal scans, NaN ranges included (bit for bit).
fn same(a: &Ros2Scan, b: &Ros2Scan) -> bool {
    let bits = |s: &Ros2Scan| {
        s.record
            .ranges_mm
            .iter()
            .map(|r| r.to_bits())
            .collect::<Vec<_>>()
    };
    (a.stamp_ns, &a.frame_id, a.record.id, a.record.geometry)
        == (b.stamp_ns, &b.frame_id, b.record.id, b.record.geometry)
        && bits(a) == bits(b)
}

/// `ok` is a prefix of `full`.
fn is_prefix(ok: &[Ros2Scan], full: &[Ros2Scan]) -> bool {
    ok.len() <= full.len() && ok.iter().zip(full).all(|(a, b)| same(a, b))
}

/// The scans before the first error, and the error.
fn split(items: Vec<Result<Ros2Scan, InputError>>) -> (Vec<Ros2Scan>, Option<InputError>) {
    let mut ok = Vec::new();
    let mut it = items.into_iter();
    for r in it.by_ref() {
        match r {
            Ok(s) => ok.push(s),
            Err(e) => {
                assert!(it.next().is_none(), "reading goes on after an error");
                return (ok, Some(e));
            }
        }
    }
    (ok, None)
}

// ---- Bags written here with the mcap crate: the error paths, with or without Python. ----

const LASER_SCAN_DEF: &str = "std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\n\
float32 angle_increment\nfloat32 time_increment\nfloat32 scan_time\nfloat32 range_min\n\
float32 range_max\nfloat32[] ranges\nfloat32[] intensities\n";

/// A little-endian CDR LaserScan with `n` beams at 2 m, stamped `sec`.
fn cdr_scan(sec: i32, n: usize) -> Vec<u8> {
    let mut b = vec![0, 1, 0, 0];
    b.extend(sec.to_le_bytes());
    b.extend(0u32.to_le_bytes());
    b.extend(6u32.to_le_bytes());
    b.extend(b"laser\0\0\0");
    let step = std::f32::consts::PI / n as f32;
    for v in [
        -1.5f32,
        -1.5 + step * (n - 1) as f32,
        step,
        0.0,
        0.1,
        0.02,
        30.0,
    ] {
        b.extend(v.to_le_bytes());
    }
    b.extend((n as u32).to_le_bytes());
    for _ in 0..n {
        b.extend(2.0f32.to_le_bytes());
    }
    b.extend(0u32.to_le_bytes());
    b
}

/// A bag with `scans` LaserScans on /scan (if `laser`) and one String on /chatter, small
/// uncompressed chunks.
fn rust_bag(laser: bool, scans: i32) -> Vec<u8> {
    let mut out = Cursor::new(Vec::new());
    let mut w = common::mcap_writer(&mut out, 2048);
    let string = w
        .add_schema("std_msgs/msg/String", "ros2msg", b"string data\n")
        .unwrap();
    let chatter = w
        .add_channel(string, "/chatter", "cdr", &BTreeMap::new())
        .unwrap();
    let mut hello = vec![0, 1, 0, 0];
    hello.extend(3u32.to_le_bytes());
    hello.extend(b"hi\0");
    w.write_to_known_channel(
        &mcap::records::MessageHeader {
            channel_id: chatter,
            sequence: 0,
            log_time: 0,
            publish_time: 0,
        },
        &hello,
    )
    .unwrap();
    if laser {
        let schema = w
            .add_schema(ros2::LASER_SCAN, "ros2msg", LASER_SCAN_DEF.as_bytes())
            .unwrap();
        let scan = w
            .add_channel(schema, "/scan", "cdr", &BTreeMap::new())
            .unwrap();
        for k in 0..scans {
            let header = mcap::records::MessageHeader {
                channel_id: scan,
                sequence: k as u32,
                log_time: k as u64,
                publish_time: k as u64,
            };
            w.write_to_known_channel(&header, &cdr_scan(k + 1, 181))
                .unwrap();
        }
    }
    w.finish().unwrap();
    drop(w);
    out.into_inner()
}

fn read_all(
    bytes: Vec<u8>,
    topic: Option<&str>,
) -> Result<Vec<Result<Ros2Scan, InputError>>, TopicError> {
    Ok(ros2::open_laser_scans(Cursor::new(bytes), topic)?.collect())
}

#[test]
fn rust_written_bag_reads_back() {
    let scans: Vec<Ros2Scan> = read_all(rust_bag(true, 20), None)
        .unwrap()
        .into_iter()
        .map(Result::unwrap)
        .collect();
    assert_eq!(scans.len(), 20);
    for (k, s) in scans.iter().enumerate() {
        assert_eq!(
            (s.record.id, s.stamp_ns),
            (k as u64, (k as u64 + 1) * 1_000_000_000)
        );
        assert_eq!(s.frame_id, "laser");
        assert_eq!(s.record.geometry.r_max, 30_000.0);
        assert!(s.record.ranges_mm.iter().all(|&r| r == 2000.0));
    }
}

#[test]
fn no_laser_scan_topic_is_a_clear_error() {
    let e = read_all(rust_bag(false, 0), None).map(|_| ()).unwrap_err();
    assert!(
        matches!(e, TopicError::NoLaserScan { ref topics } if topics.len() == 1),
        "{e}"
    );
    let text = e.to_string();
    assert!(
        text.contains("no sensor_msgs/msg/LaserScan topic") && text.contains("/chatter"),
        "{text}"
    );
}

#[test]
fn truncated_bag_keeps_earlier_scans() {
    let bytes = rust_bag(true, 40);
    let full: Vec<Ros2Scan> = read_all(bytes.clone(), None)
        .unwrap()
        .into_iter()
        .map(Result::unwrap)
        .collect();
    // Every cut point past the first scan's chunk: earlier scans kept, then one error.
    let mut kept_some = 0;
    for cut in (bytes.len() / 4..bytes.len() - 1).step_by(97) {
        let (ok, err) = split(read_all(bytes[..cut].to_vec(), None).unwrap());
        assert!(is_prefix(&ok, &full), "cut at {cut}: kept scans differ");
        assert!(
            err.is_some() || ok.len() == full.len(),
            "cut at {cut}: no error"
        );
        kept_some += usize::from(!ok.is_empty());
    }
    assert!(kept_some > 5);
    // Cut inside the magic bytes or the header: an error, no scans, no panic.
    for cut in [0, 3, 8, 20] {
        match read_all(bytes[..cut].to_vec(), None) {
            Ok(items) => assert!(items.iter().all(Result::is_err)),
            Err(e) => assert!(
                matches!(e, TopicError::Input(_) | TopicError::NoLaserScan { .. }),
                "{e}"
            ),
        }
    }
}

#[test]
fn corrupted_bag_keeps_earlier_scans() {
    let bytes = rust_bag(true, 40);
    let full: Vec<Ros2Scan> = read_all(bytes.clone(), Some("/scan"))
        .unwrap()
        .into_iter()
        .map(Result::unwrap)
        .collect();
    let mut errors = 0;
    for at in (bytes.len() / 3..bytes.len()).step_by(131) {
        let mut bad = bytes.clone();
        bad[at] ^= 0x5a;
        let Ok(items) = read_all(bad, Some("/scan")) else {
            continue;
        };
        let (ok, err) = split(items);
        // Every scan read is as in the intact bag: damage inside a chunk fails its CRC before
        // any of its messages is used.
        assert!(
            is_prefix(&ok, &full),
            "at {at}: a damaged scan was read as good"
        );
        errors += usize::from(err.is_some());
    }
    assert!(errors > 0);
}

#[test]
fn non_laser_scan_message_on_the_topic_is_an_error() {
    let mut out = Cursor::new(Vec::new());
    let mut w = mcap::Writer::new(&mut out).unwrap();
    let schema = Arc::new(mcap::Schema {
        id: 1,
        name: ros2::LASER_SCAN.into(),
        encoding: "ros2msg".into(),
        data: Cow::Borrowed(LASER_SCAN_DEF.as_bytes()),
    });
    let channel = Arc::new(mcap::Channel {
        id: 1,
        topic: "/scan".into(),
        schema: Some(schema),
        message_encoding: "cdr".into(),
        metadata: BTreeMap::new(),
    });
    for (k, data) in [cdr_scan(1, 10), vec![0, 1, 0, 0, 1, 2]]
        .into_iter()
        .enumerate()
    {
        w.write(&mcap::Message {
            channel: channel.clone(),
            sequence: k as u32,
            log_time: k as u64,
            publish_time: k as u64,
            data: Cow::Owned(data),
        })
        .unwrap();
    }
    w.finish().unwrap();
    drop(w);
    let (ok, err) = split(read_all(out.into_inner(), None).unwrap());
    assert_eq!(ok.len(), 1);
    let err = err.unwrap().to_string();
    assert!(
        err.contains("message 1 on /scan") && err.contains("CDR data ends"),
        "{err}"
    );
}
