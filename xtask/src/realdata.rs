//! `cargo xtask realdata`: the real-data benchmark without ground truth (`pfe realdata`) on
//! the shared CARMEN logs (every `*.log`, `*.clf`, gzipped or not, in `../shared/data/carmen`:
//! the ten of docs/REALDATA.md and any added there); writes docs/REALDATA.md and docs/realdata-*.svg. Arguments
//! pass through; `--check` is CI's short run (60 scans a log, printed, no document). Skips loudly, exit 0, when the shared
//! data is absent.

use crate::util;
use anyhow::Result;

/// Runs the command.
pub fn run(args: &[String]) -> Result<()> {
    let Some(logs) = util::shared_carmen_logs("realdata")? else {
        return Ok(());
    };
    let named = util::xtask_command("realdata", args);
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
