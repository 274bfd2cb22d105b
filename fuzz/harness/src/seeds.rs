//! Seed corpora for the fuzz targets, generated from the protocol test vectors
//! (`shared/docs/lms200-test-vectors.txt`, the full B0 telegram) and a few scans of each real
//! log in `shared/data` (skipped, with a message, when the folder is absent).

use std::fs;
use std::io::{self, BufRead};
use std::path::{Path, PathBuf};

use lms2xx::codec::frame::{encode_parts, ACK, DEVICE_ADDRESS, MAX_TELEGRAM};
use pfe_formats::{self as formats, Format, Record};
use pfe_core::{Config, Extractor, Scan};
use pfe_frame::{write_report, write_scan, Report, ScanHeader};

use crate::ExtractorInput;

/// Scans taken from each real log.
pub const SCANS_PER_LOG: usize = 3;

/// Parses the hex bytes of a test-vector line (`name   02 00 ... (crc=...)`).
pub fn vector_bytes(line: &str) -> Vec<u8> {
    let body = line.split("(crc").next().unwrap_or("");
    let tokens: Vec<&str> = body.split_whitespace().collect();
    // The bytes are the trailing run of two-digit hex tokens starting with STX.
    let mut bytes: Vec<u8> = Vec::new();
    for t in tokens.iter().rev() {
        match (t.len(), u8::from_str_radix(t, 16)) {
            (2, Ok(b)) => bytes.push(b),
            _ => break,
        }
    }
    bytes.reverse();
    match bytes.iter().position(|&b| b == 0x02) {
        Some(p) => bytes.split_off(p),
        None => Vec::new(),
    }
}

/// The telegrams of the test-vector file and the full B0 telegram.
pub fn protocol_vectors(docs: &Path) -> io::Result<Vec<Vec<u8>>> {
    let mut out = Vec::new();
    let text = fs::read_to_string(docs.join("lms200-test-vectors.txt"))?;
    out.extend(text.lines().map(vector_bytes).filter(|v| v.len() >= 7));
    let full = fs::read_to_string(docs.join("lms200-b0-full-180-050-mm.txt"))?;
    let b0: Vec<u8> = full
        .split_whitespace()
        .filter_map(|t| u8::from_str_radix(t, 16).ok())
        .collect();
    out.push(b0);
    Ok(out)
}

/// A few records of each real log (empty, with a message on stderr, when `data` is absent).
pub fn real_records(data: &Path) -> Vec<(String, Format, Vec<String>, Vec<Record>)> {
    let mut out = Vec::new();
    if !data.is_dir() {
        eprintln!(
            "seeds: {} is absent: real-log seeds skipped",
            data.display()
        );
        return out;
    }
    let mut files: Vec<(PathBuf, Format)> = Vec::new();
    if let Ok(dir) = fs::read_dir(data.join("carmen")) {
        let mut v: Vec<PathBuf> = dir.filter_map(|e| e.ok().map(|e| e.path())).collect();
        v.sort();
        files.extend(v.into_iter().map(|p| (p, Format::Carmen)));
    }
    files.push((data.join("hokuyo-cylinders/scans.txt.gz"), Format::Hokuyo));
    for (path, format) in files {
        let Ok(input) = formats::open(&path, |r| r) else {
            continue;
        };
        // Keep the first lines that hold scans (and whatever comes before them).
        let mut lines = Vec::new();
        let mut scans = 0;
        for line in input.lines() {
            let Ok(line) = line else { break };
            let is_scan = format != Format::Carmen || line.starts_with("FLASER");
            if lines.len() < 4 || is_scan {
                lines.push(line);
            }
            scans += usize::from(is_scan);
            if scans >= SCANS_PER_LOG {
                break;
            }
        }
        let text = lines.join("\n") + "\n";
        let records: Vec<Record> =
            formats::scans(format, Box::new(io::Cursor::new(text.into_bytes())))
                .filter_map(Result::ok)
                .collect();
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().replace(".gz", ""))
            .unwrap_or_default();
        out.push((name, format, lines, records));
    }
    out
}

/// A CARMEN `FLASER` line as a `RAWLASER1` and a `ROBOTLASER1` line (180°, n odd: 180° /
/// (n − 1) apart, n even: 180° / n; two remissions), any other line as it is.
fn newer_carmen(line: &str) -> String {
    let t: Vec<&str> = line.split_ascii_whitespace().collect();
    let n: usize = match (t.first(), t.get(1).and_then(|n| n.parse().ok())) {
        (Some(&"FLASER"), Some(n)) => n,
        _ => return format!("{line}\n"),
    };
    let (Some(ranges), Some(rest)) = (t.get(2..2 + n), t.get(2 + n..)) else {
        return format!("{line}\n");
    };
    let step = std::f64::consts::PI / if n % 2 == 1 { n - 1 } else { n }.max(1) as f64;
    let head = format!(
        "0 -1.570796 3.141593 {step:.9} 81.9 0.01 1 {n} {} 2 0.5 0.7",
        ranges.join(" ")
    );
    let field = |k: usize| rest.get(k).copied().unwrap_or("0");
    let poses: Vec<&str> = (0..6).map(field).collect();
    let stamp: Vec<&str> = (6..9).map(field).collect();
    format!(
        "RAWLASER1 {head} {}\nROBOTLASER1 {head} {} 0.4 0.1 0.5 0.3 0 {}\n",
        stamp.join(" "),
        poses.join(" "),
        stamp.join(" ")
    )
}

fn mm_u16(r: f32) -> u16 {
    if r.is_finite() && r > 0.0 {
        r.round().min(65535.0) as u16
    } else {
        0
    }
}

fn b0_telegram(codes: &[u16]) -> Vec<u8> {
    let count = (codes.len() as u16 & 0x3FF) | 0x4000; // unit bits 14-15 = 01: mm
    let mut data = Vec::new();
    for c in codes {
        data.extend(c.to_le_bytes());
    }
    let mut buf = [0u8; MAX_TELEGRAM];
    let head = [0xB0, count.to_le_bytes()[0], count.to_le_bytes()[1]];
    match encode_parts(DEVICE_ADDRESS, &[&head, &data, &[0x10]], &mut buf) {
        Ok(n) => buf[..n].to_vec(),
        Err(_) => Vec::new(),
    }
}

/// Writes every target's seed corpus under `out/<target>/`; returns the number of files.
pub fn generate(out: &Path, shared: &Path) -> io::Result<usize> {
    let mut written = 0usize;
    let mut put = |target: &str, name: &str, bytes: &[u8]| -> io::Result<()> {
        let dir = out.join(target);
        fs::create_dir_all(&dir)?;
        fs::write(dir.join(name), bytes)?;
        written += 1;
        Ok(())
    };
    let vectors = protocol_vectors(&shared.join("docs"))?;
    let records = real_records(&shared.join("data"));
    let all_records: Vec<&Record> = records.iter().flat_map(|r| &r.3).collect();
    let b0s: Vec<Vec<u8>> = all_records
        .iter()
        .filter(|r| r.ranges_mm.len() <= 401)
        .map(|r| {
            b0_telegram(
                &r.ranges_mm
                    .iter()
                    .map(|&x| mm_u16(x).min(8191))
                    .collect::<Vec<_>>(),
            )
        })
        .collect();

    // lms_decoder: chunking bytes + stream. Each vector whole, each real B0 in random chunks.
    let singles = vectors
        .iter()
        .enumerate()
        .map(|(i, v)| (format!("vector-{i:02}"), [0u8, 0], v))
        .chain(
            b0s.iter()
                .enumerate()
                .map(|(i, t)| (format!("real-b0-{i:02}"), [0x03u8, 0x42], t)),
        );
    for (name, chunking, t) in singles {
        put("lms_decoder", &name, &[&chunking[..], t].concat())?;
    }
    let mut all = Vec::new();
    for v in vectors.iter().chain(&b0s) {
        all.extend_from_slice(v);
        all.push(ACK);
    }
    put(
        "lms_decoder",
        "all-bytewise",
        &[&[1u8, 0][..], &all].concat(),
    )?;
    put(
        "lms_decoder",
        "all-random-chunks",
        &[&[0x7Fu8, 0x55][..], &all].concat(),
    )?;
    if let Some(b0) = vectors.last() {
        let mut damaged = b0.clone();
        if let Some(x) = damaged.get_mut(100) {
            *x ^= 0x08;
        }
        let stream = [
            &[0xFFu8, 0x02, 0x80, 0xFF, 0xFF][..],
            &damaged,
            b0,
            &b0[..b0.len() / 2],
        ]
        .concat();
        put(
            "lms_decoder",
            "damaged-then-good",
            &[&[0x0Bu8, 0x11][..], &stream].concat(),
        )?;
    }

    // lms_driver: sessions with the emulator, refusals, raw vectors, a wrapping clock.
    for (name, bytes) in crate::lms_driver::seeds(&vectors) {
        put("lms_driver", &name, &bytes)?;
    }

    // extractor: real scans in the sane layout, mm and raw codes.
    let deg = |x: f32| x.to_degrees();
    for (i, r) in all_records.iter().enumerate() {
        let g = r.geometry;
        let start = (deg(g.start_angle) * 100.0).round() as i16;
        let step = (deg(g.angle_step) * 1000.0).round() as i16;
        let rmax = g.r_max.min(65535.0) as u16;
        let values: Vec<u16> = r.ranges_mm.iter().map(|&x| mm_u16(x)).collect();
        put(
            "extractor",
            &format!("real-{i:02}-mm"),
            &ExtractorInput::encode_sane(start, step, rmax, false, &values),
        )?;
        let codes: Vec<u16> = values
            .iter()
            .map(|&v| if v == 0 { 8183 } else { v.min(8183) })
            .collect();
        let mut raw = ExtractorInput::encode_sane(start, step, 8000, true, &codes);
        raw[0] |= ExtractorInput::VARIANTS;
        put("extractor", &format!("real-{i:02}-raw"), &raw)?;
    }
    if let Some(b0) = vectors.last() {
        let codes: Vec<u16> = b0[7..b0.len() - 3]
            .chunks_exact(2)
            .map(|w| u16::from_le_bytes([w[0], w[1]]) & 0x1FFF)
            .collect();
        put(
            "extractor",
            "vector-b0",
            &ExtractorInput::encode_sane(-9000, 500, 8000, true, &codes),
        )?;
    }

    // readers: format selector + text.
    for (name, format, lines, records) in &records {
        let sel = match format {
            Format::Csv => 0u8,
            Format::Carmen => 1,
            Format::Hokuyo => 2,
            Format::Lms200 => 3,
            // Bags are binary containers, read by path: not a text reader's seed.
            Format::Mcap => continue,
        };
        put(
            "readers",
            name,
            &[&[sel][..], lines.join("\n").as_bytes(), b"\n"].concat(),
        )?;
        if *format == Format::Carmen {
            // The same scans as the newer logger writes them (RAWLASER1, ROBOTLASER1).
            let newer: String = lines.iter().map(|l| newer_carmen(l)).collect();
            put(
                "readers",
                &format!("{name}.robotlaser1"),
                &[&[sel][..], newer.as_bytes()].concat(),
            )?;
        }
        let csv: String = records
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let ranges: Vec<String> = r
                    .ranges_mm
                    .iter()
                    .map(|&x| format!("{}", mm_u16(x)))
                    .collect();
                format!(
                    "{i},{},{},{}\n",
                    deg(r.geometry.start_angle),
                    deg(r.geometry.angle_step),
                    ranges.join(",")
                )
            })
            .collect();
        put(
            "readers",
            &format!("{name}.csv"),
            &[&[0u8][..], csv.as_bytes()].concat(),
        )?;
    }
    for (i, t) in b0s.iter().chain(vectors.last()).enumerate() {
        put(
            "readers",
            &format!("lms200-{i:02}"),
            &[&[3u8][..], t].concat(),
        )?;
    }

    // frame_decoder: frames the firmware encodes for real scans (both configurations).
    let mut ex = Box::new(Extractor::<2048, 64>::new());
    let mut stream = Vec::new();
    for (i, r) in all_records.iter().enumerate() {
        for (k, config) in [Config::paper(), Config::default()].iter().enumerate() {
            if ex
                .extract(&Scan::from_mm(r.geometry, &r.ranges_mm), config)
                .is_err()
            {
                continue;
            }
            let header = ScanHeader {
                seq: i as u32,
                ..ScanHeader::default()
            };
            let mut frame = Vec::new();
            if write_scan(&mut frame, &header, ex.features()).is_ok() {
                if i < 6 {
                    put(
                        "frame_decoder",
                        &format!("real-{i:02}-{k}"),
                        &[&[0u8, 0][..], &frame].concat(),
                    )?;
                }
                stream.extend_from_slice(&frame);
            }
        }
    }
    let mut report = Vec::new();
    if write_report(
        &mut report,
        &Report::Stack {
            used: 1234,
            size: 8192,
        },
    )
    .is_ok()
    {
        put(
            "frame_decoder",
            "report",
            &[&[0u8, 0][..], &report].concat(),
        )?;
        stream.extend_from_slice(&report);
    }
    stream.truncate(60_000);
    put(
        "frame_decoder",
        "stream-chunked",
        &[&[0x3Fu8, 0x21][..], &stream].concat(),
    )?;
    Ok(written)
}
