//! `cargo xtask pose`: the pose benchmark (`pfe posebench`, issue 40) on the shared CARMEN
//! logs (every CARMEN log in `../shared/data/carmen`); writes docs/POSE.md's generated
//! section, pfe-pose beside the PL-ICP baseline (`--baseline`). `--quick` is CI's short run (the first 100 pairs of each log, printed, no
//! document); other arguments (`--odometry`, `--force`) pass through. Skips loudly, exit 0,
//! when the shared data is absent.

use crate::util;
use anyhow::Result;

/// Runs the command.
pub fn run(args: &[String]) -> Result<()> {
    let Some(logs) = util::shared_carmen_logs("pose")? else {
        return Ok(());
    };
    let named = util::xtask_command("pose", args);
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
