//! `pfe listen` on files: good frames between damage and a frame of another version come out
//! as JSON lines, the rest is counted; bytes without a valid frame exit 2 with a hint.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use std::process::Command;

use pfe_core::{Feature, LineFeature, Point};
use pfe_frame::{write_scan, Counters, ScanHeader};
use pfe_testkit::qemu::VecWriter;
use serde_json::Value;

fn frame(seq: u32) -> Vec<u8> {
    let f = Feature::Line(LineFeature::new(
        3,
        40,
        38,
        0.25,
        1500.0,
        1e-6,
        2.0,
        1e-5,
        Point::new(1.0, -2.0),
        Point::new(3.0, 4.0),
    ));
    let h = ScanHeader {
        seq,
        time_ms: 1000 + seq,
        counters: Counters {
            telegrams_ok: seq + 1,
            ..Counters::default()
        },
        ..ScanHeader::default()
    };
    let mut w = VecWriter(Vec::new());
    write_scan(&mut w, &h, &[f]).unwrap();
    w.0
}

fn listen(input: &[u8], extra: &[&str]) -> (i32, Vec<Value>, String) {
    let path = std::env::temp_dir().join(format!(
        "pfe-cli-listen-{}-{}",
        std::process::id(),
        input.len()
    ));
    std::fs::write(&path, input).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_pfe"))
        .args(["listen", "--input"])
        .arg(&path)
        .args(extra)
        .output()
        .unwrap();
    let _ = std::fs::remove_file(&path);
    let lines = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    (
        out.status.code().unwrap_or(-1),
        lines,
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn damage_and_other_versions_are_counted_and_dropped() {
    // Noise up to a zero (a receiver joining mid-frame), then frames.
    let mut stream = b"noise\0".to_vec();
    stream.extend(frame(0));
    let mut bad = frame(1);
    bad[10] ^= 0x20; // CRC error
    stream.extend(bad);
    // An intact frame of version 5: re-framed with a fresh CRC.
    let good = frame(2);
    let mut raw = cobs::decode_vec(&good[..good.len() - 1]).unwrap();
    raw.truncate(raw.len() - 4);
    raw[0] = 5;
    let crc = crc32fast::hash(&raw);
    raw.extend_from_slice(&crc.to_le_bytes());
    stream.extend(cobs::encode_vec(&raw));
    stream.push(0);
    stream.extend(frame(3));
    let (code, lines, err) = listen(&stream, &[]);
    assert_eq!(code, 0, "{err}");
    let seqs: Vec<u64> = lines.iter().map(|l| l["seq"].as_u64().unwrap()).collect();
    assert_eq!(seqs, [0, 3]);
    assert_eq!(lines[1]["time_ms"], 1003);
    assert_eq!(lines[1]["counters"]["telegrams"], 4);
    assert_eq!(
        lines[1]["features"][0]["cov_alpha_rho"].as_f64().unwrap() as f32,
        1e-5
    );
    assert!(lines[1]["received"].as_f64().unwrap() > 1.6e9);
    assert!(err.contains("2 frames ok"), "{err}");
    assert!(
        err.contains("1 bad CRC, 1 unknown version, 1 other damage"),
        "{err}"
    );

    let (code, lines, _) = listen(&stream, &["--scans", "1"]);
    assert_eq!((code, lines.len()), (0, 1));
}

#[test]
fn bytes_without_a_frame_exit_2_with_a_hint() {
    let (code, lines, err) = listen(b"this is not a frame\0at all\0", &[]);
    assert_eq!(code, 2);
    assert!(lines.is_empty());
    assert!(err.contains("no valid frame"), "{err}");
    let (code, _, _) = listen(&frame(0), &["--seconds", "-1"]);
    assert_eq!(code, 2);
}

/// A frame's pose block comes out as the `odometry` object, shaped as `pfe odometry`'s lines
/// (docs/JSON.md), its numbers exact; a frame without one (version 3) has no `odometry`.
#[test]
fn the_pose_block_is_printed_as_odometry() {
    use pfe_frame::{write_scan_with_pose, PoseBlock, PoseCov, PoseFailure, PoseStatus};
    let cov = |k: f32| [[25.0 * k, 1.5, 0.0], [1.5, 36.0 * k, 0.0], [0.0, 0.0, 4e-5]];
    let block = |status| PoseBlock {
        rel: PoseCov {
            x: 120.5,
            y: -3.25,
            theta: 0.0625,
            cov: cov(1.0),
        },
        pose: PoseCov {
            x: 4321.0,
            y: 17.0,
            theta: -1.5,
            cov: cov(9.0),
        },
        status,
    };
    let mut w = VecWriter(Vec::new());
    let statuses = [
        PoseStatus::Degenerate {
            direction: [0.6, 0.8, 0.0],
        },
        PoseStatus::None(PoseFailure::NoConsensus),
    ];
    for (seq, status) in statuses.into_iter().enumerate() {
        let h = ScanHeader {
            seq: seq as u32,
            ..ScanHeader::default()
        };
        write_scan_with_pose(&mut w, &h, &[], Some(&block(status))).unwrap();
    }
    // Version 3: no pose block.
    let v4 = frame(2);
    let mut raw = cobs::decode_vec(&v4[..v4.len() - 1]).unwrap();
    raw.truncate(raw.len() - 5); // the CRC and the pose block `None`
    raw[0] = 3;
    let crc = crc32fast::hash(&raw);
    raw.extend_from_slice(&crc.to_le_bytes());
    w.0.extend(cobs::encode_vec(&raw));
    w.0.push(0);
    let (code, lines, err) = listen(&w.0, &[]);
    assert_eq!((code, lines.len()), (0, 3), "{err}");
    let o = &lines[0]["odometry"];
    assert_eq!(o["status"], "degenerate");
    assert_eq!(o["rel"]["x"], 120.5);
    assert_eq!(o["pose"]["theta"], -1.5);
    assert_eq!(o["pose"]["cov"][4], 324.0);
    assert_eq!(o["direction"][1].as_f64().unwrap() as f32, 0.8);
    assert!(o.get("reason").is_none());
    let o = &lines[1]["odometry"];
    assert_eq!(
        (o["status"].clone(), o["reason"].clone()),
        ("none".into(), "NoConsensus".into())
    );
    assert!(o.get("direction").is_none());
    assert!(lines[2].get("odometry").is_none(), "{}", lines[2]);
    assert_eq!(lines[2]["seq"], 2);
}
