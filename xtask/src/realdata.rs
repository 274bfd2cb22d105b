//! `cargo xtask realdata`: the real-data benchmark without ground truth (`pfe realdata`) on
//! the ten shared CARMEN logs; writes docs/REALDATA.md and docs/realdata-*.svg. Arguments
//! pass through (`--max-scans N` for a short check). Skips loudly, exit 0, when the shared
//! data is absent.

use crate::util::{self, cargo};
use anyhow::{Context, Result};

/// The shared logs, relative to the repository root.
const LOGS: &str = "../shared/data/carmen";

/// Runs the command.
pub fn run(args: &[String]) -> Result<()> {
    let dir = util::root().join(LOGS);
    if !dir.is_dir() {
        eprintln!("SKIPPED: realdata: ../shared/data not found");
        println!("SKIPPED: realdata: ../shared/data not found");
        return Ok(());
    }
    let mut logs: Vec<String> = std::fs::read_dir(&dir)
        .with_context(|| format!("reading {}", dir.display()))?
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().to_string())
        .filter(|n| n.ends_with(".log.gz"))
        .map(|n| format!("{LOGS}/{n}"))
        .collect();
    logs.sort();
    let mut named = String::from("cargo xtask realdata");
    for a in args {
        named.push(' ');
        named.push_str(a);
    }
    let mut cmd = cargo();
    cmd.args([
        "run",
        "--release",
        "-q",
        "-p",
        "host-tests",
        "--bin",
        "pfe",
        "--",
    ])
    .arg("realdata")
    .args(&logs)
    .args(["--md", "docs/REALDATA.md", "--command", &named])
    .args(args);
    util::run(&mut cmd)
}
