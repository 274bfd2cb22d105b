//! `pfe emulate`: an emulated LMS200 on a pseudo-terminal or a TCP socket.

use std::net::TcpListener;
use std::path::PathBuf;
use std::time::Duration;

use anyhow::{Context, Result};

use super::lms_args::LmsArgs;
use super::Exit;
use lms200_emulator::serve::clear_stale_link;
use lms200_emulator::{serve_pty, serve_tcp, Emulator, EmulatorConfig, RunLimits, SourceKind};

const USAGE: &str = "pfe emulate (--pty PATH | --tcp ADDR) [--scans N] [--seconds S] [--seed N]
    [--baud 9600|19200|38400|500000] [--variant 180/0.5] [--unit mm|cm] [--source room|tagged] [--trace]

Emulates a SICK LMS200 on a pseudo-terminal (symlink PATH to the slave) or on a TCP socket
(listens on ADDR and serves one connection). Prints a JSON summary on exit, Ctrl-C included.
PATH must be free or a stale link of a previous run (a symlink to a /dev/pts/N that is gone):
anything else there is refused. The link is removed on exit.";

/// Arguments of `pfe emulate`.
#[derive(clap::Args, Debug)]
#[command(override_help = USAGE, args_override_self = true)]
pub struct Args {
    #[arg(long)]
    pty: Option<PathBuf>,
    #[arg(long)]
    tcp: Option<String>,
    #[arg(long)]
    scans: Option<u32>,
    #[arg(long)]
    seconds: Option<f64>,
    #[arg(long)]
    seed: Option<u64>,
    #[command(flatten)]
    lms: LmsArgs,
    #[arg(long, value_parser = source)]
    source: Option<SourceKind>,
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
            return Err(Exit::bad_input(format!(
                "give exactly one of --pty PATH or --tcp ADDR\n\n{USAGE}"
            ))
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
