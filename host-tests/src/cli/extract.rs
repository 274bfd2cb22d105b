//! `pfe extract`: one JSON object per scan on stdout.

use std::path::PathBuf;
use std::time::Instant;

use serde::Serialize;

use super::input::{bad_input, flush, nothing_found, open_scans, stdout, write_json, MethodArgs};
use super::Failure;
use crate::formats::ScanJson;
use crate::methods::Method;

/// Arguments of `pfe extract`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    method: MethodArgs,
    /// Input file (gzip is read transparently; `-` = stdin).
    file: PathBuf,
}

/// One output line: the scan's JSON, plus the stamp and frame of a ROS 2 bag's scan.
#[derive(Serialize)]
struct Line<'a> {
    #[serde(flatten)]
    scan: ScanJson,
    /// `header.stamp`, ns since the epoch (bags only).
    #[serde(skip_serializing_if = "Option::is_none")]
    stamp_ns: Option<u64>,
    /// `header.frame_id` (bags only).
    #[serde(skip_serializing_if = "Option::is_none")]
    frame_id: Option<&'a str>,
}

/// Runs `pfe extract`.
pub fn run(a: Args) -> Result<(), Failure> {
    let (format, file) = (a.method.format, a.file.as_path());
    let mut method = a.method.method();
    let input = open_scans(file, format, a.method.topic.as_deref())?;
    let bar = input.bar.clone();
    let mut out = stdout();
    let t0 = Instant::now();
    let (mut scans, mut features) = (0u64, 0u64);
    let mut error = None;
    for scan in input.scans {
        let scan = match scan {
            Ok(s) => s,
            Err(e) => {
                error = Some(bad_input(file, format, scans, &e));
                break;
            }
        };
        let record = &scan.record;
        let ex = method.extract(&record.geometry, &record.ranges_mm);
        scans += 1;
        features += ex.features.len() as u64;
        if scans % 256 == 0 {
            bar.set_message(format!("{scans} scans"));
        }
        let line = Line {
            scan: ScanJson::new(record.id, &ex),
            stamp_ns: scan.stamp_ns,
            frame_id: scan.frame_id.as_deref(),
        };
        if !write_json(&mut out, &line)? {
            break;
        }
    }
    flush(&mut out)?;
    bar.finish_and_clear();
    if let Some(e) = error {
        return Err(e);
    }
    if scans == 0 && input.bytes.load(std::sync::atomic::Ordering::Relaxed) > 0 {
        return Err(nothing_found(file, format, "scan"));
    }
    let s = t0.elapsed().as_secs_f64();
    eprintln!(
        "pfe: {scans} scans, {features} features ({:.2} per scan), {:.3} s, {:.0} scans/s",
        features as f64 / scans.max(1) as f64,
        s,
        scans as f64 / s.max(1e-9)
    );
    Ok(())
}
