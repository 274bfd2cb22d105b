//! `cargo xtask realdata`: the real-data benchmark without ground truth (`pfe realdata`) on
//! the shared CARMEN logs (every `*.log`, `*.clf`, gzipped or not, in `../shared/data/carmen`:
//! the ten of docs/REALDATA.md and any added there); writes docs/REALDATA.md and docs/realdata-*.svg. Arguments
//! pass through; `--check` is CI's short run (60 scans a log, printed, no document). Skips loudly, exit 0, when the shared
//! data is absent.

use crate::util;
use anyhow::{Context, Result};

/// The shared logs, relative to the repository root.
const LOGS: &str = "../shared/data/carmen";

/// Runs the command.
pub fn run(args: &[String]) -> Result<()> {
    let dir = util::root().join(LOGS);
    if !dir.is_dir() {
        // Listed with the test step's skips; under CI (which has the data) a failure.
        pfe_testkit::skip::skip(
            "realdata",
            "../shared/data not found",
            pfe_testkit::skip::Need::InCi,
        );
        return Ok(());
    }
    let mut logs: Vec<String> = std::fs::read_dir(&dir)
        .with_context(|| format!("reading {}", dir.display()))?
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().to_string())
        .filter(|n| pfe_formats::carmen::is_log_name(n))
        .map(|n| format!("{LOGS}/{n}"))
        .collect();
    logs.sort();
    let mut named = String::from("cargo xtask realdata");
    for a in args {
        named.push(' ');
        named.push_str(a);
    }
    let mut cmd = util::pfe();
    cmd.arg("realdata").args(&logs);
    if args.iter().any(|a| a == "--check") {
        // CI's shortened run: the first scans of every log, printed, no document written.
        cmd.args(["--max-scans", "60"]);
    } else {
        cmd.args(["--md", "docs/REALDATA.md", "--command", &named])
            .args(args);
    }
    util::run(&mut cmd)
}
