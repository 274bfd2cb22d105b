//! `docs/FRAME.md` cannot drift: its test vector is what the firmware's app sends for a fixed
//! scan, the firmware's decoder reads it as the doc's JSON, and so does a minimal decoder
//! written here from the spec alone (COBS, CRC-32 by crc32fast, varints by hand).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

use firmware::app::{App, ConfigChoice, RawScan};
use host_tests::qemu::VecWriter;
use pfe_cli::link::listen::ListenJson;
use pfe_frame::{Counters, Feed, FrameDecoder};
use serde_json::{json, Value};

fn doc() -> String {
    std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/FRAME.md")).unwrap()
}

/// The first fenced block with info string `lang` after the heading `## Test vector`.
fn block(doc: &str, lang: &str) -> String {
    let from = doc.find("## Test vector").expect("a Test vector section");
    let rest = &doc[from..];
    let open = format!("```{lang}\n");
    let start = rest
        .find(&open)
        .unwrap_or_else(|| panic!("no {lang} block"))
        + open.len();
    let end = start + rest[start..].find("```").unwrap();
    rest[start..end].to_string()
}

fn doc_bytes() -> Vec<u8> {
    let hex: String = block(&doc(), "hex")
        .chars()
        .filter(|c| c.is_ascii_hexdigit())
        .collect();
    (0..hex.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&hex[i..i + 2], 16).unwrap())
        .collect()
}

/// The fixed scan of the vector: LMS200 180°/0.5°, a wall 2 m ahead over ±34°, a pillar of
/// radius 150 mm centred at (1200, 900) mm, nothing else in range; the frame of the second
/// time the app sees it (seq 1: its pose block tells that two features cannot be registered).
fn vector_frame() -> Vec<u8> {
    let g = pfe_core::ScanGeometry::LMS200_180_050;
    let codes: Vec<u16> = (0..361)
        .map(|i| {
            let b = g.bearing(i);
            let (c, s) = (f64::from(b).cos(), f64::from(b).sin());
            // Ray to the pillar: |t·u − p| = r.
            let (px, py, r) = (1200.0f64, 900.0f64, 150.0f64);
            let tc = c * px + s * py;
            let d2 = px * px + py * py - tc * tc;
            let pillar = (d2 <= r * r).then(|| tc - (r * r - d2).sqrt());
            let wall = (f64::from(b).abs() < 0.6).then(|| 2000.0 / c);
            match (pillar, wall) {
                (Some(p), _) => p.round() as u16,
                (None, Some(w)) => w.round() as u16,
                _ => 8183,
            }
        })
        .collect();
    let mut app = Box::new(App::<361, 48>::new(ConfigChoice::Default));
    let mut scan = RawScan::lms_8m(g, &codes, 1.0);
    scan.time_ms = 123_456;
    let counters = Counters {
        telegrams_ok: 300,
        crc_dropped: 2,
        bytes_skipped: 17,
        reinits: 1,
    };
    let mut first = VecWriter(Vec::new());
    app.process(&scan, Counters::default(), &mut first).unwrap();
    let mut out = VecWriter(Vec::new());
    app.process(&scan, counters, &mut out).unwrap();
    out.0
}

fn hex(bytes: &[u8]) -> String {
    bytes
        .chunks(32)
        .map(|c| {
            c.iter()
                .map(|b| format!("{b:02x}"))
                .collect::<Vec<_>>()
                .join(" ")
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Numbers equal as f32 (the doc's decimals are f32's shortest representations), the rest
/// exactly.
fn same(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => match (x.as_i64(), y.as_i64()) {
            (Some(i), Some(j)) => i == j,
            _ => x.as_f64().map(|v| v as f32) == y.as_f64().map(|v| v as f32),
        },
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(p, q)| same(p, q))
        }
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len() && x.iter().all(|(k, v)| y.get(k).is_some_and(|w| same(v, w)))
        }
        _ => a == b,
    }
}

#[test]
fn the_vector_is_what_the_firmware_app_sends() {
    let want = vector_frame();
    let got = doc_bytes();
    if got != want {
        let mut dec = FrameDecoder::<4096>::new();
        let Feed::Frame { frame, .. } = dec.feed(&want) else {
            panic!("the app's frame does not decode")
        };
        panic!(
            "docs/FRAME.md's test vector is stale; the app sends\n```hex\n{}\n```\ndecoded:\n```json\n{}\n```",
            hex(&want),
            serde_json::to_string_pretty(&ListenJson::from_frame(&frame, None)).unwrap()
        );
    }
}

/// The length the text gives the vector is the vector's.
#[test]
fn the_vectors_stated_length_is_its_length() {
    let doc = doc();
    let from = doc.find("## Test vector").expect("a Test vector section");
    let said = doc[from..]
        .split("The frame, ")
        .nth(1)
        .and_then(|t| t.split(' ').next())
        .and_then(|n| n.parse::<usize>().ok())
        .expect("\"The frame, N bytes\" in the Test vector section");
    assert_eq!(
        said,
        doc_bytes().len(),
        "docs/FRAME.md states the wrong length"
    );
    assert_eq!(
        doc_bytes().last(),
        Some(&0),
        "the vector ends with its terminator"
    );
}

#[test]
fn firmware_decoder_reads_the_docs_json() {
    let bytes = doc_bytes();
    let want: Value = serde_json::from_str(&block(&doc(), "json")).unwrap();
    let mut dec = FrameDecoder::<4096>::new();
    let Feed::Frame { frame, remaining } = dec.feed(&bytes) else {
        panic!("the vector does not decode")
    };
    assert!(remaining.is_empty());
    let got = serde_json::to_value(ListenJson::from_frame(&frame, None)).unwrap();
    assert!(same(&got, &want), "got {got:#}\nwant {want:#}");
}

/// The spec, implemented from `docs/FRAME.md` alone.
mod spec {
    use super::*;

    pub fn cobs_decode(data: &[u8]) -> Option<Vec<u8>> {
        let mut out = Vec::new();
        let mut i = 0;
        while i < data.len() {
            let code = usize::from(data[i]);
            if code == 0 || i + code > data.len() {
                return None;
            }
            out.extend_from_slice(&data[i + 1..i + code]);
            i += code;
            if code < 0xFF && i < data.len() {
                out.push(0);
            }
        }
        Some(out)
    }

    pub struct R<'a>(pub &'a [u8]);
    impl R<'_> {
        pub fn u8(&mut self) -> u8 {
            let b = self.0[0];
            self.0 = &self.0[1..];
            b
        }
        pub fn varint(&mut self) -> u64 {
            let (mut v, mut shift) = (0u64, 0);
            loop {
                let b = self.u8();
                v |= u64::from(b & 0x7F) << shift;
                if b & 0x80 == 0 {
                    return v;
                }
                shift += 7;
            }
        }
        pub fn f32(&mut self) -> Value {
            let x = f32::from_le_bytes(self.0[..4].try_into().unwrap());
            self.0 = &self.0[4..];
            json!(f64::from(x))
        }
        pub fn point(&mut self) -> Value {
            json!([self.f32(), self.f32()])
        }
    }

    /// The frame (with its 0x00) as the JSON of `docs/JSON.md` (without `received`).
    pub fn decode(frame: &[u8]) -> Value {
        assert_eq!(frame.last(), Some(&0));
        assert!(!frame[..frame.len() - 1].contains(&0));
        let raw = cobs_decode(&frame[..frame.len() - 1]).unwrap();
        let (payload, crc) = raw.split_at(raw.len() - 4);
        assert_eq!(
            u32::from_le_bytes(crc.try_into().unwrap()),
            crc32fast::hash(payload)
        );
        let mut r = R(payload);
        assert_eq!(r.u8(), 4, "version");
        assert_eq!(r.varint(), 0, "Header::Scan");
        let seq = r.varint();
        let time_ms = r.varint();
        let counters = json!({
            "telegrams": r.varint(), "crc_dropped": r.varint(),
            "bytes_skipped": r.varint(), "reinits": r.varint(),
        });
        let (valid, segments, dropped, n) = (r.varint(), r.varint(), r.varint(), r.varint());
        let error = match r.varint() {
            0 => Value::Null,
            1 => json!("feature_capacity"),
            2 => json!("too_many_readings"),
            3 => json!("invalid_input"),
            s => panic!("status {s}"),
        };
        let mut features = Vec::new();
        for _ in 0..n {
            let tag = r.varint();
            let (first, last, points) = (r.varint(), r.varint(), r.varint());
            features.push(if tag == 0 {
                json!({"kind": "line", "first": first, "last": last, "points": points,
                    "alpha": r.f32(), "rho": r.f32(), "var_alpha": r.f32(), "var_rho": r.f32(),
                    "cov_alpha_rho": r.f32(), "start": r.point(), "end": r.point()})
            } else {
                assert_eq!(tag, 1);
                let (center, radius) = (r.point(), r.f32());
                // docs/JSON.md: the JSON's covariance is symmetrised, (c_ij + c_ji) / 2 in f32.
                let c: Vec<f32> = (0..9).map(|_| r.f32().as_f64().unwrap() as f32).collect();
                let at = |i: usize, j: usize| f64::from(0.5 * (c[3 * i + j] + c[3 * j + i]));
                let cov: Vec<Value> = (0..3)
                    .map(|i| json!([at(i, 0), at(i, 1), at(i, 2)]))
                    .collect();
                let (start_angle, end_angle) = (r.f32(), r.f32());
                json!({"kind": "circle", "first": first, "last": last, "points": points,
                    "center": center, "radius": radius, "cov": cov,
                    "start_angle": start_angle, "end_angle": end_angle})
            });
        }
        // The pose block: an option (00 none, 01 some), two poses, the status.
        let odometry = (r.u8() == 1).then(|| {
            let mut pose = || {
                let (x, y, theta) = (r.f32(), r.f32(), r.f32());
                let cov: Vec<Value> = (0..9).map(|_| r.f32()).collect();
                json!({"x": x, "y": y, "theta": theta, "cov": cov})
            };
            let (rel, pose) = (pose(), pose());
            let mut o = json!({"rel": rel, "pose": pose});
            match r.varint() {
                0 => o["status"] = json!("ok"),
                1 => {
                    o["status"] = json!("degenerate");
                    o["direction"] = json!([r.f32(), r.f32(), r.f32()]);
                }
                2 => {
                    o["status"] = json!("none");
                    let reasons = [
                        "TooFewFeatures",
                        "NoHypothesis",
                        "NoConsensus",
                        "Ambiguous",
                        "InvalidPrior",
                        "Other",
                    ];
                    o["reason"] = json!(reasons[r.varint() as usize]);
                }
                s => panic!("pose status {s}"),
            }
            o
        });
        assert!(r.0.is_empty(), "trailing bytes");
        let mut out = json!({
            "scan": seq, "features": features,
            "status": {"error": error, "dropped": dropped},
            "seq": seq, "time_ms": time_ms, "valid": valid, "segments": segments,
            "counters": counters,
        });
        if let Some(o) = odometry {
            out["odometry"] = o;
        }
        out
    }
}

#[test]
fn a_decoder_written_from_the_spec_reads_the_docs_json() {
    let want: Value = serde_json::from_str(&block(&doc(), "json")).unwrap();
    let got = spec::decode(&doc_bytes());
    assert!(same(&got, &want), "got {got:#}\nwant {want:#}");
}
