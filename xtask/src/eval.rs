//! `cargo xtask eval`: PFE paper/default vs ACF and split-and-merge on simulated scans with
//! ground truth; writes docs/EVALUATION.md and docs/eval-*.svg. Runs the `eval` example of
//! host-tests in release (arguments pass through; see `cargo xtask eval --help`).

use crate::util::{self, cargo};
use anyhow::Result;

/// Runs the command.
pub fn run(args: &[String]) -> Result<()> {
    let mut cmd = cargo();
    cmd.args([
        "run",
        "--release",
        "-p",
        "host-tests",
        "--example",
        "eval",
        "--",
    ]);
    let mut named = String::from("cargo xtask eval");
    for a in args {
        named.push(' ');
        named.push_str(a);
    }
    if !args.iter().any(|a| a == "--command") {
        cmd.args(["--command", &named]);
    }
    // `pfe eval` writes nothing without --out: the repository's docs/ unless told otherwise.
    if !args.iter().any(|a| {
        a == "--no-write" || a == "--out" || a.starts_with("--out=") || a == "--help" || a == "-h"
    }) {
        cmd.arg("--out").arg(crate::util::root().join("docs"));
    }
    cmd.args(args);
    util::run(&mut cmd)
}
