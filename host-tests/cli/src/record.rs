//! `pfe record`: raw LMS200 bytes from a serial port, through the firmware driver.

use std::path::PathBuf;

use anyhow::Result;
use lms2xx::driver::Config;

use super::lms_args::LmsArgs;
use super::Exit;
use crate::device::record::{record, RecordOptions};

/// What `pfe record --help` says after the options.
const AFTER_HELP: &str = "Initialises the LMS200 on --port with the firmware driver, streams \
--scans scans and writes the raw bytes received, up to the end of the last scan, to FILE \
(pfe decode and pfe extract --format lms200 read it). Prints a JSON summary (driver counters) \
on stdout.

An existing FILE is refused (exit 2) unless --force. The port is opened first and the bytes go \
to a temporary file beside FILE, renamed to FILE at the end: a port that cannot be opened \
leaves FILE untouched, and Ctrl-C (exit 130) or a device failure halfway keeps what was \
received.";

/// Arguments of `pfe record`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = AFTER_HELP,
    args_override_self = true,
    mut_arg("baud", |a| a.help(
        "Rate the driver switches the device to: 9600, 19200, 38400 or 500000 \
         [default: 38400]"
    )),
    mut_arg("variant", |a| a.help(
        "Angle/resolution the driver sets: 100/1, 100/0.5, 100/0.25, 180/1 or 180/0.5 \
         [default: 180/0.5]"
    )),
    mut_arg("unit", |a| a.help("Range unit the driver sets: mm or cm [default: mm]")),
)]
pub struct Args {
    /// Serial port of the LMS200 (a tty; it starts at 9600 Bd).
    #[arg(long, value_name = "PATH", required = true)]
    port: Option<PathBuf>,
    /// The capture file (in a directory that exists).
    #[arg(short = 'o', long = "output", value_name = "FILE", required = true)]
    output: Option<PathBuf>,
    /// Scans to record.
    #[arg(long, value_name = "N", default_value_t = 10)]
    scans: u32,
    /// Replace an existing FILE.
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
        return Err(Exit::bad_input("--port and -o are required (see pfe record --help)").into());
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
