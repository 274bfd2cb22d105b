//! `pfe extract`: one JSON object per scan on stdout.

use std::path::PathBuf;
use std::time::Instant;

use super::input::{flush, open, stdout, write_json, MethodArgs};
use super::Failure;
use crate::formats::{self, ScanJson, StatusJson};
use crate::methods::Method;

/// Arguments of `pfe extract`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    method: MethodArgs,
    /// Input file (gzip is read transparently; `-` = stdin).
    file: PathBuf,
}

/// Runs `pfe extract`.
pub fn run(a: Args) -> Result<(), Failure> {
    let (format, file) = (a.method.format, a.file.as_path());
    let mut method = a.method.method();
    let (input, bar) = open(file, format)?;
    let mut out = stdout();
    let t0 = Instant::now();
    let (mut scans, mut features) = (0u64, 0u64);
    let mut error = None;
    for record in formats::scans(format, input) {
        let record = match record {
            Ok(r) => r,
            Err(e) => {
                error = Some(Failure::input(format!("{}: {e}", file.display())));
                break;
            }
        };
        let ex = method.extract(&record.geometry, &record.ranges_mm);
        scans += 1;
        features += ex.features.len() as u64;
        if scans % 256 == 0 {
            bar.set_message(format!("{scans} scans"));
        }
        if !write_json(
            &mut out,
            &ScanJson::new(record.id, &ex).with_status(StatusJson::of(&method.last_result())),
        )? {
            break;
        }
    }
    flush(&mut out)?;
    bar.finish_and_clear();
    if let Some(e) = error {
        return Err(e);
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
