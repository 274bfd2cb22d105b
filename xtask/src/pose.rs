//! `cargo xtask pose`: the pose benchmark (`pfe posebench`, issue 40) on the shared CARMEN
//! logs (every CARMEN log in `../shared/data/carmen`); writes docs/POSE.md's generated
//! section, pfe-pose beside the PL-ICP baseline (`--baseline`), and its pictures
//! (docs/pose-intel.svg, -fhw.svg, -freiburg-campus.svg: `pfe plot --world --odometry --points`). `--quick` is CI's short run (the first 100 pairs of each log, printed, no
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
        return util::run(&mut cmd);
    }
    cmd.args(["--md", "docs/POSE.md", "--command", &named])
        .args(args);
    util::run(&mut cmd)?;
    pictures(&logs, args)
}

/// Logs drawn in docs/POSE.md (`docs/pose-LOG.svg`): a building's loops (intel), a crowded
/// hall (fhw), an outdoor campus (freiburg-campus).
const PICTURED: [&str; 3] = ["intel", "fhw", "freiburg-campus"];

/// `pfe plot --world --odometry --points` of the [`PICTURED`] logs: the host's odometry (the
/// features and the scans' own points, as the table measures it) beside the log's corrected
/// poses.
fn pictures(logs: &[String], args: &[String]) -> Result<()> {
    for name in PICTURED {
        let Some(log) = logs.iter().find(|l| {
            l.rsplit('/').next().is_some_and(|f| {
                f.starts_with(&format!("{name}-")) || f.starts_with(&format!("{name}."))
            })
        }) else {
            continue;
        };
        let mut cmd = util::pfe();
        cmd.args([
            "plot",
            "--format",
            "carmen",
            log,
            "--odometry",
            "--points",
            "--world",
        ])
        .arg(format!("docs/pose-{name}.svg"))
        .args(args.iter().filter(|a| *a == "--force"));
        util::run(&mut cmd)?;
    }
    Ok(())
}
