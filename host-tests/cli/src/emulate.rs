//! `pfe emulate`: an emulated LMS200 on a pseudo-terminal or a TCP socket.

use std::net::TcpListener;
use std::path::PathBuf;
use std::time::Duration;

use anyhow::{Context, Result};

use super::lms_args::LmsArgs;
use super::Exit;
use lms200_emulator::serve::clear_stale_link;
use lms200_emulator::{serve_pty, serve_tcp, Emulator, EmulatorConfig, RunLimits, SourceKind};

/// What `pfe emulate --help` says after the options.
const AFTER_HELP: &str = "Emulates a SICK LMS200 on a pseudo-terminal (--pty) or a TCP socket \
(--tcp), until --scans, --seconds or Ctrl-C, then prints a JSON summary on stdout. The --pty \
PATH must be free or a stale link of an earlier run (a symlink to a /dev/pts/N that is gone): \
anything else there is refused (exit 2). The link is removed on exit.";

/// Arguments of `pfe emulate`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = AFTER_HELP,
    args_override_self = true,
    mut_arg("baud", |a| a.help(
        "Rate the device starts at (9600, 19200, 38400 or 500000; a driver switches it) \
         [default: 9600]"
    )),
    mut_arg("variant", |a| a.help(
        "Angle/resolution the device starts with: 100/1, 100/0.5, 100/0.25, 180/1 or \
         180/0.5 [default: 180/0.5]"
    )),
    mut_arg("unit", |a| a.help("Range unit the device starts with: mm or cm [default: mm]")),
)]
pub struct Args {
    /// Serve on a pseudo-terminal: PATH becomes a symlink to its slave side (open it as the
    /// scanner's serial port).
    #[arg(long, value_name = "PATH")]
    pty: Option<PathBuf>,
    /// Serve one connection on a TCP socket listening on ADDR (e.g. 127.0.0.1:2111; port 0:
    /// any free port, printed on stderr).
    #[arg(long, value_name = "ADDR")]
    tcp: Option<String>,
    /// Stop after N scans sent [default: no limit].
    #[arg(long, value_name = "N")]
    scans: Option<u32>,
    /// Stop after S seconds [default: no limit].
    #[arg(long, value_name = "S")]
    seconds: Option<f64>,
    /// Seed of the emulated scans' noise [default: 1].
    #[arg(long, value_name = "N")]
    seed: Option<u64>,
    #[command(flatten)]
    lms: LmsArgs,
    /// What the scans show: room (a simulated room) or tagged (every scan distinct and
    /// recognisable, for tests) [default: room].
    #[arg(long, value_parser = source, value_name = "room|tagged")]
    source: Option<SourceKind>,
    /// Print every command received on stderr.
    #[arg(long)]
    trace: bool,
}

fn source(s: &str) -> Result<SourceKind, String> {
    match s {
        "room" => Ok(SourceKind::Room),
        "tagged" => Ok(SourceKind::Tagged),
        other => Err(format!("unknown source {other}")),
    }
}

/// `pfe emulate` from an argument list.
pub fn cli(args: &[String]) -> Result<()> {
    super::parse_sub::<Args>("pfe emulate", args)?.map_or(Ok(()), run)
}

/// Runs `pfe emulate`.
pub fn run(a: Args) -> Result<()> {
    let mut cfg = EmulatorConfig::default();
    let limits = RunLimits {
        scans: a.scans,
        max_time: a.seconds.map(Duration::from_secs_f64),
        trace: a.trace,
        stop: Some(super::interrupt::flag()),
    };
    if let Some(seed) = a.seed {
        cfg.seed = seed;
    }
    if let Some(b) = a.lms.baud {
        cfg.initial_baud = b;
    }
    if let Some(v) = a.lms.variant {
        cfg.variant = v;
    }
    if let Some(u) = a.lms.unit {
        cfg.config.set_unit(u);
    }
    if let Some(s) = a.source {
        cfg.source = s;
    }
    let report = match (a.pty, a.tcp) {
        (Some(p), None) => {
            clear_stale_link(&p).map_err(|e| Exit::bad_input(format!("--pty: {e:#}")))?;
            eprintln!("emulating an LMS200 on {}", p.display());
            serve_pty(&p, Emulator::from_config(cfg), limits)?
        }
        (None, Some(addr)) => {
            let l = TcpListener::bind(&addr).with_context(|| format!("binding {addr}"))?;
            eprintln!("emulating an LMS200 on tcp {}", l.local_addr()?);
            serve_tcp(l, cfg, limits)?
        }
        _ => {
            return Err(Exit::bad_input(
                "give exactly one of --pty PATH or --tcp ADDR (see pfe emulate --help)",
            )
            .into())
        }
    };
    println!(
        "{}",
        serde_json::json!({
            "scans_sent": report.scans.len(),
            "scans_damaged": report.scans.iter().filter(|s| s.damaged).count(),
            "commands": report.commands.len(),
            "bad_commands": report.bad_commands,
            "garbled_in": report.garbled_in,
            "garbled_out": report.garbled_out,
            "bytes_out": report.bytes_out,
            "resets": report.resets,
        })
    );
    Ok(())
}
