//! `pfe record`: raw LMS200 bytes from a serial port, through the firmware driver.

use std::path::PathBuf;

use anyhow::Result;
use lms2xx::driver::Config;

use super::lms_args::LmsArgs;
use super::Exit;
use crate::device::record::{record, RecordOptions};

const USAGE: &str = "pfe record --port PATH [--baud 38400] [--scans N] -o FILE [--force]
    [--variant 180/0.5] [--unit mm|cm]

Initialises the LMS200 on PATH with the firmware driver, streams N scans (default 10) and writes
the raw bytes received up to the end of the last scan to FILE. Prints a JSON summary (driver counters).

An existing FILE is refused (exit 2) unless --force. The port is opened first and the bytes go
to a temporary file beside FILE, renamed to FILE at the end: a port that cannot be opened leaves
FILE untouched, and Ctrl-C (exit 130) or a device failure halfway keeps what was received.";

/// Arguments of `pfe record`.
#[derive(clap::Args, Debug)]
#[command(override_help = USAGE, args_override_self = true)]
pub struct Args {
    #[arg(long)]
    port: Option<PathBuf>,
    #[arg(short = 'o', long = "output")]
    output: Option<PathBuf>,
    #[arg(long, default_value_t = 10)]
    scans: u32,
    #[arg(long)]
    force: bool,
    #[command(flatten)]
    lms: LmsArgs,
}

/// `pfe record` from an argument list.
pub fn cli(args: &[String]) -> Result<()> {
    super::parse_sub::<Args>("pfe record", args)?.map_or(Ok(()), run)
}

/// Runs `pfe record`.
pub fn run(a: Args) -> Result<()> {
    let mut cfg = Config::default();
    if let Some(b) = a.lms.baud {
        cfg.baud = b;
    }
    if let Some(v) = a.lms.variant {
        cfg.variant = v;
    }
    if let Some(u) = a.lms.unit {
        cfg.unit = u;
    }
    let (Some(port), Some(out)) = (a.port, a.output) else {
        return Err(Exit::bad_input(format!("--port and -o are required\n\n{USAGE}")).into());
    };
    let opts = RecordOptions {
        overwrite: a.force,
        stop: Some(super::interrupt::flag()),
    };
    let s = record(&port, cfg, a.scans, &out, &opts)?;
    println!("{}", serde_json::to_string(&s)?);
    if s.interrupted {
        return Err(super::Exit::interrupted(format!(
            "interrupted after {} scans; the {} bytes received are in {}",
            s.scans,
            s.bytes,
            out.display()
        ))
        .into());
    }
    Ok(())
}
