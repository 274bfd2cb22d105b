//! `cargo xtask pose`: the pose benchmark (`pfe posebench`, issue 40) on the shared CARMEN
//! logs (every CARMEN log in `../shared/data/carmen`); writes docs/POSE.md's generated
//! section, pfe-pose beside the PL-ICP baseline (`--baseline`). `--quick` is CI's short run (the first 100 pairs of each log, printed, no
//! document); other arguments (`--odometry`, `--force`) pass through. Skips loudly, exit 0,
//! when the shared data is absent.

use crate::util;
use anyhow::{Context, Result};

/// The shared logs, relative to the repository root.
const LOGS: &str = "../shared/data/carmen";

/// Runs the command.
pub fn run(args: &[String]) -> Result<()> {
    let dir = util::root().join(LOGS);
    if !dir.is_dir() {
        pfe_testkit::skip::skip(
            "pose",
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
    let mut named = String::from("cargo xtask pose");
    for a in args {
        named.push(' ');
        named.push_str(a);
    }
    // A release build (the table times the host).
    let mut cmd = util::pfe();
    cmd.arg("posebench").arg("--baseline").args(&logs);
    if args.iter().any(|a| a == "--quick") {
        cmd.args(args);
    } else {
        cmd.args(["--md", "docs/POSE.md", "--command", &named])
            .args(args);
    }
    util::run(&mut cmd)
}
