//! The Foxglove MCAP file of `pfe_cli::foxglove`, read back by an independent reader
//! (`fixtures/foxglove/read_foxglove.py`: the PyPI `mcap` package and `json`) and compared field
//! by field with what was written. Without python3 or `mcap` it reports a skip through
//! `pfe_testkit::skip` and passes, except under `CI=true`, where it fails.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: a panic fails the test

mod common;
use std::path::{Path, PathBuf};

use pfe_cli::foxglove::{FoxgloveWriter, FEATURES_TOPIC, NO_RETURN_M, SCAN_TOPIC};
use pfe_core::{Config, Feature};
use pfe_eval::methods::{Method, Pfe};
use pfe_formats::{self as formats, Format, Record};
use serde_json::Value;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

fn records(name: &str, format: Format) -> Vec<Record> {
    let input = formats::open_for(&fixture(name), format, |r| r).unwrap();
    formats::scans(format, input).map(Result::unwrap).collect()
}

fn read_back(path: &Path) -> Option<Value> {
    common::read_foxglove(
        "foxglove_mcap::foxglove_file_reads_back_message_for_message",
        path,
    )
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

fn near(v: &Value, expected: f64) -> bool {
    (f(v) - expected).abs() <= 1e-9 * (1.0 + expected.abs())
}

fn xy(p: &Value) -> (f64, f64) {
    assert!(near(&p["z"], 0.0));
    (f(&p["x"]), f(&p["y"]))
}

#[test]
fn foxglove_file_reads_back_message_for_message() {
    // A room (lines) and a Hokuyo scan of a wall with a cylinder (a circle).
    let mut scans = records("room.log", Format::Carmen);
    scans.extend(records("cylinder.txt", Format::Hokuyo));
    let mut pfe = Pfe::new("pfe", Config::default().with_sigma_r(10.0));
    let features: Vec<Vec<Feature>> = scans
        .iter()
        .map(|r| pfe.extract(&r.geometry, &r.ranges_mm).features)
        .collect();
    let all = features.iter().flatten();
    assert!(all.clone().any(Feature::is_line) && all.clone().any(|f| !f.is_line()));
    let stamps: Vec<u64> = (0..scans.len() as u64)
        .map(|k| 1_700_000_000_000_000_000 + k * 133_333_333)
        .collect();

    let dir = std::env::temp_dir().join(format!("pfe-foxglove-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("out.mcap");
    let mut w = FoxgloveWriter::create(&path).unwrap();
    for ((r, fs), &t) in scans.iter().zip(&features).zip(&stamps) {
        w.write_scan(t, "laser", r, fs).unwrap();
    }
    assert_eq!(w.finish().unwrap(), path);
    let back = read_back(&path);
    std::fs::remove_dir_all(&dir).unwrap();
    let Some(back) = back else {
        return;
    };

    let channels = back["channels"].as_array().unwrap();
    let names: Vec<(&str, &str)> = channels
        .iter()
        .map(|c| (c["topic"].as_str().unwrap(), c["schema"].as_str().unwrap()))
        .collect();
    assert_eq!(
        names,
        [
            (SCAN_TOPIC, "foxglove.LaserScan"),
            (FEATURES_TOPIC, "foxglove.SceneUpdate")
        ]
    );
    assert!(channels.iter().all(|c| c["schema_encoding"] == "jsonschema"
        && c["schema_is_json"] == true
        && c["message_encoding"] == "json"));
    let messages = back["messages"].as_array().unwrap();
    assert_eq!(messages.len(), 2 * scans.len());
    assert_eq!(back["statistics"]["message_count"], 2 * scans.len());

    let mut no_returns = 0;
    for (k, (r, fs)) in scans.iter().zip(&features).enumerate() {
        let (scan, scene) = (&messages[2 * k], &messages[2 * k + 1]);
        let t = stamps[k];
        for m in [scan, scene] {
            assert_eq!(
                (m["log_time"].as_u64(), m["publish_time"].as_u64()),
                (Some(t), Some(t))
            );
            assert_eq!(m["sequence"], k);
        }
        let time = |v: &Value| (v["sec"].as_u64().unwrap(), v["nsec"].as_u64().unwrap());
        let expected_time = (t / 1_000_000_000, t % 1_000_000_000);

        // The scan.
        assert_eq!(scan["topic"], SCAN_TOPIC);
        let d = &scan["data"];
        assert_eq!(time(&d["timestamp"]), expected_time);
        assert_eq!(d["frame_id"], "laser");
        let n = r.ranges_mm.len();
        assert!(near(&d["start_angle"], f64::from(r.geometry.start_angle)));
        assert!(near(&d["end_angle"], f64::from(r.geometry.bearing(n - 1))));
        let ranges = d["ranges"].as_array().unwrap();
        assert_eq!(ranges.len(), n);
        for (i, v) in ranges.iter().enumerate() {
            // Every range is a number (the schema's float64[]; never null).
            assert!(v.is_number(), "scan {k} beam {i}: {v}");
            match r.point(i) {
                Some(_) => assert!(
                    near(v, f64::from(r.ranges_mm[i]) * 1e-3),
                    "scan {k} beam {i}"
                ),
                None => {
                    assert_eq!(f(v), NO_RETURN_M, "scan {k} beam {i}: {v}");
                    no_returns += 1;
                }
            }
        }

        // The features.
        assert_eq!(scene["topic"], FEATURES_TOPIC);
        let d = &scene["data"];
        assert_eq!(d["deletions"].as_array().unwrap().len(), 1);
        assert_eq!(d["deletions"][0]["type"], 1);
        let entities = d["entities"].as_array().unwrap();
        assert_eq!(entities.len(), fs.len(), "scan {k}");
        for (j, (e, feature)) in entities.iter().zip(fs).enumerate() {
            assert_eq!(e["id"], format!("feature-{j}"));
            assert_eq!(time(&e["timestamp"]), expected_time);
            assert_eq!(e["frame_id"], "laser");
            let meta = |key: &str| common::metadata(e, key);
            assert_eq!(meta("first"), feature.first().to_string());
            assert_eq!(meta("last"), feature.last().to_string());
            assert_eq!(e["texts"].as_array().unwrap().len(), 1);
            match feature {
                Feature::Line(l) => {
                    assert_eq!(meta("kind"), "line");
                    assert_eq!(meta("rho_mm").parse::<f32>().unwrap(), l.rho);
                    let seg = e["lines"][0]["points"].as_array().unwrap();
                    assert_eq!(seg.len(), 2);
                    let (a, b) = (xy(&seg[0]), xy(&seg[1]));
                    let mm = |v: f32| f64::from(v) * 1e-3;
                    assert!(
                        (a.0 - mm(l.start.x)).abs() < 1e-9 && (a.1 - mm(l.start.y)).abs() < 1e-9
                    );
                    assert!((b.0 - mm(l.end.x)).abs() < 1e-9 && (b.1 - mm(l.end.y)).abs() < 1e-9);
                    // The σ band: 4 corners on both sides of the line, each within 20 σ_ρ-scale
                    // of it (the band is narrow for real fits).
                    let band = e["lines"][1]["points"].as_array().unwrap();
                    assert_eq!((band.len(), &e["lines"][1]["type"]), (4, &Value::from(1)));
                    let side = |p: (f64, f64)| {
                        p.0 * f64::from(l.alpha).cos() + p.1 * f64::from(l.alpha).sin()
                            - f64::from(l.rho) * 1e-3
                    };
                    assert!(side(xy(&band[0])) >= 0.0 && side(xy(&band[3])) <= 0.0);
                }
                Feature::Circle(c) => {
                    assert_eq!(meta("kind"), "circle");
                    let cyl = &e["cylinders"][0];
                    let (x, y) = xy(&cyl["pose"]["position"]);
                    assert!((x - f64::from(c.center.x) * 1e-3).abs() < 1e-9);
                    assert!((y - f64::from(c.center.y) * 1e-3).abs() < 1e-9);
                    assert!(near(&cyl["size"]["x"], 2.0 * f64::from(c.radius) * 1e-3));
                    assert!(near(&cyl["size"]["y"], 2.0 * f64::from(c.radius) * 1e-3));
                    // The outline: every point at the radius from the centre.
                    let outline = e["lines"][0]["points"].as_array().unwrap();
                    assert_eq!(outline.len(), 48);
                    for p in outline {
                        let (px, py) = xy(p);
                        let d = ((px - x).powi(2) + (py - y).powi(2)).sqrt();
                        assert!((d - f64::from(c.radius) * 1e-3).abs() < 1e-9);
                    }
                    assert_eq!(e["lines"].as_array().unwrap().len(), 4);
                }
                Feature::Object(o) => {
                    assert_eq!(meta("kind"), "object");
                    assert_eq!(meta("extent_mm").parse::<f32>().unwrap(), o.extent);
                }
                _ => {}
            }
        }
    }
    // The no-return check above ran (the fixtures have beams with no return).
    assert!(no_returns > 0, "no no-return beam in the fixtures");
}
