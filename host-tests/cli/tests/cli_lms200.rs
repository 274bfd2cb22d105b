//! `pfe decode` / `pfe extract --format lms200` on raw LMS200 captures: the committed fixtures
//! (built from the protocol fact sheet's test vectors, see fixtures/make_fixtures.py), damaged
//! captures, and scans encoded here with the firmware's telegram encoder.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: a panic fails the test

use std::io::BufReader;

use lms2xx::codec::frame::{encode_telegram, DEVICE_ADDRESS};
use pfe_formats::lms200::{Reader, Telegram, Unit};
use serde_json::Value;

#[path = "../../tests/common/mod.rs"]
mod common;
use common::{arg, fixture, json_lines, pfe, stderr};

/// The telegrams and the stderr of `pfe decode --format lms200 FIXTURE`, which must succeed.
fn decode(name: &str) -> (Vec<Value>, String) {
    let out = pfe(&["decode", "--format", "lms200", arg(&fixture(name))]);
    assert!(out.status.success());
    (json_lines(&out), stderr(&out))
}

/// The 361 values of lms200-b0-full-180-050-mm.txt: 8191, 8190, 8183, then 1000 + i (the
/// flag bits above the 13 range bits removed).
fn full_values() -> Vec<u64> {
    (0..361u64)
        .map(|i| match i {
            0 => 8191,
            1 => 8190,
            2 => 8183,
            _ => 1000 + i,
        })
        .collect()
}

fn check_telegram(v: &Value, scan: u64, unit: &str, ranges: &[u64]) {
    let o = v.as_object().unwrap();
    let mut keys: Vec<&str> = o.keys().map(|k| k.as_str()).collect();
    keys.sort();
    assert_eq!(keys, ["ranges", "scan", "status", "unit"]);
    assert_eq!(v["scan"].as_u64(), Some(scan));
    assert_eq!(v["unit"], unit);
    assert_eq!(v["status"].as_u64(), Some(0x10));
    let got: Vec<u64> = common::u64s(&v["ranges"]);
    assert_eq!(got, ranges);
}

#[test]
fn decode_test_vectors() {
    let (t, stderr) = decode("lms200-good.bin");
    assert_eq!(t.len(), 3);
    check_telegram(&t[0], 0, "mm", &[1000, 1001, 1002, 1003, 8191]);
    check_telegram(&t[1], 1, "cm", &[100, 200, 300]);
    check_telegram(&t[2], 2, "mm", &full_values());
    // The host command (address 0x00) is skipped: 8 bytes.
    assert!(
        stderr.contains("3 telegrams good, 0 dropped for CRC, 8 bytes skipped"),
        "{stderr}"
    );
}

#[test]
fn damaged_capture_still_decodes_the_good_telegrams() {
    let (t, stderr) = decode("lms200-damaged.bin");
    assert_eq!(t.len(), 3);
    check_telegram(&t[0], 0, "cm", &[100, 200, 300]);
    // Started inside a telegram that was cut off.
    check_telegram(&t[1], 1, "mm", &[1000, 1001, 1002, 1003, 8191]);
    check_telegram(&t[2], 2, "mm", &full_values());
    // Dropped: the telegram with a flipped bit, the one cut off, the one truncated at the end.
    // Skipped: 4 noise bytes + 20 + 300 + 500.
    assert!(
        stderr.contains("3 telegrams good, 3 dropped for CRC, 824 bytes skipped"),
        "{stderr}"
    );
    // extract numbers the same scans; the partial ones (3 and 5 values: no LMS200 variant, so
    // no known beam angles) are not scans, and it says so.
    let path = fixture("lms200-damaged.bin");
    let out = pfe(&["extract", "--format", "lms200", arg(&path)]);
    assert!(out.status.success());
    let ids: Vec<u64> = json_lines(&out)
        .iter()
        .map(|v| v["scan"].as_u64().unwrap())
        .collect();
    assert_eq!(ids, [2]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    for t in ["telegram 0: 3 values", "telegram 1: 5 values"] {
        assert!(stderr.contains(t), "{stderr}");
    }
}

#[test]
fn decode_rejects_other_formats() {
    let out = pfe(&["decode", "--format", "csv", arg(&fixture("room.csv"))]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("lms200"));
}

/// A B0 telegram of `codes` in `unit` with status 0x10, encoded by the firmware's encoder.
fn b0(codes: &[u16], unit: Unit) -> Vec<u8> {
    let unit_bits: u16 = match unit {
        Unit::Mm => 0b01,
        Unit::Cm => 0b00,
    };
    let mut payload = vec![0xB0];
    payload.extend_from_slice(&((unit_bits << 14) | codes.len() as u16).to_le_bytes());
    for c in codes {
        payload.extend_from_slice(&c.to_le_bytes());
    }
    payload.push(0x10);
    let mut out = vec![0u8; 812];
    let n = encode_telegram(DEVICE_ADDRESS, &payload, &mut out).unwrap();
    out.truncate(n);
    out
}

/// A wall at x = 2 m seen by a 180°/0.5° scan: beam i at −90° + i/2, in view for |bearing| < 60°
/// (beams 61–299), no return (8183) elsewhere.
fn wall_codes(mm_per_code: f64) -> Vec<u16> {
    (0..361)
        .map(|i| {
            let b = (-90.0 + 0.5 * i as f64).to_radians();
            if b.abs() < 60f64.to_radians() {
                (2000.0 / b.cos() / mm_per_code).round() as u16
            } else {
                8183
            }
        })
        .collect()
}

#[test]
fn extract_wall_in_mm_and_cm() {
    let dir = std::env::temp_dir().join(format!("pfe-cli-lms-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut capture = vec![0x06];
    capture.extend(b0(&wall_codes(1.0), Unit::Mm));
    capture.extend(b0(&wall_codes(10.0), Unit::Cm));
    let path = dir.join("wall.bin");
    std::fs::write(&path, &capture).unwrap();
    let out = pfe(&["extract", "--format", "lms200", arg(&path)]);
    assert!(out.status.success(), "{}", stderr(&out));
    let scans = json_lines(&out);
    assert_eq!(scans.len(), 2);
    for (scan, tol) in scans.iter().zip([1.0, 10.0]) {
        let f = scan["features"].as_array().unwrap();
        assert_eq!(f.len(), 1, "{scan}");
        let l = &f[0];
        assert_eq!(l["kind"], "line");
        assert!((l["rho"].as_f64().unwrap() - 2000.0).abs() < tol, "{l}");
        assert!(
            l["alpha"].as_f64().unwrap().abs() < 0.01 * tol / 10.0 + 1e-3,
            "{l}"
        );
        // Indices count the no-return beams before the wall.
        let (first, last) = (l["first"].as_u64().unwrap(), l["last"].as_u64().unwrap());
        assert!(
            (61..=62).contains(&first) && (298..=299).contains(&last),
            "{first}..{last}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

fn read_all(bytes: &[u8], chunk: usize) -> Vec<Telegram> {
    let input = BufReader::with_capacity(chunk, std::io::Cursor::new(bytes.to_vec()));
    Reader::new(Box::new(input)).map(|t| t.unwrap()).collect()
}

#[test]
fn any_chunking_gives_the_same_telegrams() {
    let bytes = std::fs::read(fixture("lms200-damaged.bin")).unwrap();
    let whole = read_all(&bytes, 1 << 16);
    assert_eq!(whole.len(), 3);
    for chunk in [1, 2, 3, 7, 64, 731, 732, 733] {
        assert_eq!(read_all(&bytes, chunk), whole, "chunks of {chunk}");
    }
}

#[test]
fn truncation_anywhere_keeps_the_complete_telegrams() {
    let bytes = std::fs::read(fixture("lms200-good.bin")).unwrap();
    let all = read_all(&bytes, 1 << 16);
    // Ends of the B0 telegrams in the capture: 8 + 1 + 9 = 18 bytes before the first.
    let ends = [18 + 20, 18 + 20 + 16, bytes.len()];
    for cut in 0..=bytes.len() {
        let got = read_all(&bytes[..cut], 4096);
        let complete = ends.iter().filter(|&&e| e <= cut).count();
        assert_eq!(got.len(), complete, "cut at {cut}");
        assert_eq!(got, all[..complete], "cut at {cut}");
    }
}

#[test]
fn a_flipped_byte_loses_at_most_its_own_telegram() {
    let bytes = std::fs::read(fixture("lms200-good.bin")).unwrap();
    let all = read_all(&bytes, 1 << 16);
    let spans = [(18, 38), (38, 54), (54, bytes.len())];
    for pos in 0..bytes.len() {
        for flip in [0x01u8, 0x80, 0xFF] {
            let mut damaged = bytes.clone();
            damaged[pos] ^= flip;
            let got = read_all(&damaged, 4096);
            // Every telegram that does not contain the flipped byte is decoded, in order;
            // nothing else is (the CRC catches the change).
            let expected: Vec<&Telegram> = spans
                .iter()
                .zip(&all)
                .filter(|((a, b), _)| !(a..b).contains(&&pos))
                .map(|(_, t)| t)
                .collect();
            let got_payloads: Vec<(Unit, &[u16])> =
                got.iter().map(|t| (t.unit, t.ranges.as_slice())).collect();
            let exp_payloads: Vec<(Unit, &[u16])> = expected
                .iter()
                .map(|t| (t.unit, t.ranges.as_slice()))
                .collect();
            assert_eq!(got_payloads, exp_payloads, "byte {pos} ^ {flip:#x}");
        }
    }
}

/// A B0 telegram whose value count no LMS200 variant sends (3 values, a partial scan: its
/// beams' angles are unknown) is decoded and counted, but `extract` skips it with a message
/// instead of reading it as a guessed 180° field; the scans around it come through.
#[test]
fn a_telegram_of_an_unknown_value_count_is_not_a_scan() {
    let mut capture = b0(&wall_codes(1.0), Unit::Mm);
    capture.extend(b0(&[100, 200, 300], Unit::Mm));
    capture.extend(b0(&wall_codes(1.0), Unit::Mm));
    let input = BufReader::new(std::io::Cursor::new(capture.clone()));
    let mut reader = Reader::new(Box::new(input));
    let telegrams: Vec<Telegram> = reader.by_ref().map(|t| t.unwrap()).collect();
    let scans: Vec<bool> = telegrams.iter().map(|t| t.record().is_some()).collect();
    assert_eq!(scans, [true, false, true]);
    let s = reader.summary();
    assert_eq!((s.good, s.unknown_count, s.crc_errors), (3, 1, 0), "{s:?}");

    let dir = std::env::temp_dir().join(format!("pfe-cli-lms-odd-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("odd.bin");
    std::fs::write(&path, &capture).unwrap();
    let out = pfe(&["extract", "--format", "lms200", path.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let scans = json_lines(&out);
    assert_eq!(scans.len(), 2, "{stderr}");
    assert!(scans
        .iter()
        .all(|s| s["features"].as_array().unwrap().len() == 1));
    assert!(
        stderr.contains("telegram 1: 3 values match no LMS200 variant"),
        "{stderr}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
