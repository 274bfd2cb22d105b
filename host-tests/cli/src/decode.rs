//! `pfe decode`: one JSON object per good 0xB0 telegram of an LMS200 capture.

use std::path::PathBuf;

use serde::Serialize;

use super::input::{flush, guess, nothing_found, open, shown, stdout, write_json};
use super::Failure;
use pfe_formats::{lms200, Format};

/// What `pfe decode` reads: LMS200 captures only (`pfe extract` reads the other formats).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum DecodeFormat {
    /// Raw byte capture of an LMS200 serial line (0xB0 telegrams, damage skipped).
    Lms200,
}

/// Arguments of `pfe decode`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Input format (decode reads raw LMS200 captures only).
    #[arg(long, short, value_enum, default_value_t = DecodeFormat::Lms200)]
    format: DecodeFormat,
    /// Input file (`-` = stdin).
    file: PathBuf,
}

/// One line of `pfe decode` output.
#[derive(Serialize)]
struct TelegramJson<'a> {
    scan: u64,
    unit: &'static str,
    ranges: &'a [u16],
    status: u8,
}

/// Runs `pfe decode`.
pub fn run(a: Args) -> Result<(), Failure> {
    let format = match a.format {
        DecodeFormat::Lms200 => Format::Lms200,
    };
    let file = a.file.as_path();
    let input = open(file, format)?;
    let bar = input.bar.clone();
    let mut out = stdout();
    let mut reader = lms200::Reader::new(input.reader);
    let mut error = None;
    for t in reader.by_ref() {
        let t = match t {
            Ok(t) => t,
            Err(e) => {
                error = Some(Failure::input(format!("{}: {e}", file.display())));
                break;
            }
        };
        let j = TelegramJson {
            scan: t.ordinal,
            unit: t.unit.name(),
            ranges: &t.ranges,
            status: t.status,
        };
        if !write_json(&mut out, &j)? {
            break;
        }
    }
    flush(&mut out)?;
    bar.finish_and_clear();
    let s = reader.summary();
    let bytes = input.bytes.load(std::sync::atomic::Ordering::Relaxed);
    if bytes == 0 && error.is_none() {
        return Err(nothing_found(file, format, "LMS200 telegram", 0));
    }
    eprintln!(
        "pfe: {} bytes: {} telegrams good, {} dropped for CRC, {} bytes skipped \
         ({} dropped for length, {} malformed B0, {} B0 of an unknown value count, {} other telegrams)",
        s.bytes,
        s.good,
        s.crc_errors,
        s.skipped,
        s.bad_length,
        s.malformed,
        s.unknown_count,
        s.other_telegrams
    );
    if let Some(e) = error {
        return Err(e);
    }
    if s.good == 0 {
        let hint = match guess(file, format) {
            Some(g) => format!("; is it {g}? try pfe extract --format {g}"),
            None => String::new(),
        };
        return Err(Failure::input(format!(
            "no LMS200 telegram found in {}{hint}",
            shown(file)
        )));
    }
    Ok(())
}
