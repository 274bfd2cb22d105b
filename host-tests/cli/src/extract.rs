//! `pfe extract`: one JSON object per scan on stdout.

use std::io;
use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use super::input::{bad_input, flush, nothing_found, open_scans, stdout, write_json, MethodArgs};
use super::{interrupt, Failure};
use crate::foxglove::FoxgloveWriter;
use pfe_eval::methods::Method;
use pfe_formats::{ScanJson, StatusJson};

/// Arguments of `pfe extract`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    method: MethodArgs,
    /// Input file (gzip is read transparently; `-` = stdin).
    file: PathBuf,
    /// Also write a Foxglove MCAP file: per scan, the scan (`foxglove.LaserScan` on /scan) and
    /// its features (`foxglove.SceneUpdate` on /features). A bag's scans keep their stamps and
    /// frames; other inputs get frame "laser" and stamps 0.1 s apart from 0 (one scan per
    /// 100 ms, as from a 10 Hz scanner). Never replaces an existing file without --force.
    #[arg(long, value_name = "OUT.mcap")]
    mcap: Option<PathBuf>,
    /// Let --mcap replace an existing file.
    #[arg(long, requires = "mcap")]
    force: bool,
}

/// Spacing of the stamps given to scans that have none (Foxglove output), ns.
pub const SYNTHETIC_PERIOD_NS: u64 = 100_000_000;

/// Frame of scans that have none (Foxglove output).
pub const DEFAULT_FRAME: &str = "laser";

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
    let mut foxglove = match &a.mcap {
        Some(path) => Some(create_foxglove(path, a.force)?),
        None => None,
    };
    let input = open_scans(file, format, a.method.topic.as_deref())?;
    let bar = input.bar.clone();
    let mut out = stdout();
    let t0 = Instant::now();
    let (mut scans, mut features) = (0u64, 0u64);
    let mut error = None;
    let mut interrupted = false;
    let mut auto = a.method.auto_sweeps();
    for scan in input.scans {
        if interrupt::requested() {
            interrupted = true;
            break;
        }
        let scan = match scan {
            Ok(s) => s,
            Err(e) => {
                error = Some(bad_input(file, format, scans, &e));
                break;
            }
        };
        let record = &scan.record;
        let context = a.method.context(record, &mut auto);
        let ex = method.extract_in(&record.geometry, &record.ranges_mm, &context);
        scans += 1;
        features += ex.features.len() as u64;
        if scans % 256 == 0 {
            bar.set_message(format!("{scans} scans"));
        }
        if let Some(w) = foxglove.as_mut() {
            let stamp = scan
                .stamp_ns
                .unwrap_or((scans - 1).saturating_mul(SYNTHETIC_PERIOD_NS));
            let frame = scan.frame_id.as_deref().unwrap_or(DEFAULT_FRAME);
            if let Err(e) = w.write_scan(stamp, frame, record, &ex.features) {
                error = Some(mcap_failure(a.mcap.as_deref(), &e));
                break;
            }
        }
        let line = Line {
            scan: ScanJson::new(record.id, &ex)
                .with_status(StatusJson::of(&method.last_result()))
                .with_veils(method.veils())
                .with_input(record),
            stamp_ns: scan.stamp_ns,
            frame_id: scan.frame_id.as_deref(),
        };
        if !write_json(&mut out, &line)? {
            break;
        }
    }
    flush(&mut out)?;
    bar.finish_and_clear();
    if interrupted && error.is_none() {
        error = Some(Failure {
            code: 130,
            message: format!("interrupted after {scans} scans"),
        });
    }
    // The scans read before an error or Ctrl-C are kept in the Foxglove file too.
    if let Some(w) = foxglove {
        match w.finish() {
            Ok(path) => eprintln!("pfe: wrote {} ({scans} scans)", path.display()),
            Err(e) => {
                error.get_or_insert(mcap_failure(a.mcap.as_deref(), &e));
            }
        }
    }
    if let Some(e) = error {
        return Err(e);
    }
    if scans == 0 {
        let bytes = input.bytes.load(std::sync::atomic::Ordering::Relaxed);
        return Err(nothing_found(file, format, "scan", bytes));
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

/// Starts the Foxglove file `path`: an existing file is bad input unless `force`.
pub(crate) fn create_foxglove(path: &Path, force: bool) -> Result<FoxgloveWriter, Failure> {
    pfe_formats::outfile::check_dir(path).map_err(|e| Failure::input(format!("--mcap {e}")))?;
    let w = if force {
        FoxgloveWriter::create_overwriting(path)
    } else {
        FoxgloveWriter::create(path)
    };
    w.map_err(|e| mcap_failure(Some(path), &e))
}

/// A failure writing the Foxglove file: an existing file is bad input (exit 2).
pub(crate) fn mcap_failure(path: Option<&Path>, e: &io::Error) -> Failure {
    let name = path.map(|p| p.display().to_string()).unwrap_or_default();
    if e.kind() == io::ErrorKind::AlreadyExists {
        Failure::input(format!(
            "--mcap {name}: the file exists (not overwritten; --force replaces it)"
        ))
    } else {
        Failure::other(format!("--mcap {name}: cannot write: {e}"))
    }
}
