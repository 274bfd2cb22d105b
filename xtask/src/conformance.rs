//! `cargo xtask conformance`: MRPT's `CSickLaserSerial` (an independent LMS200 client from
//! Debian's libmrpt-hwdrivers-dev) against the emulator on a pseudo-terminal.
//!
//! Installs g++ and libmrpt-hwdrivers-dev when missing (as root), then runs the test
//! `host-tests/tests/emulator_mrpt.rs` with `PFE_CONFORMANCE_REQUIRED=1`, so a missing
//! toolchain fails instead of skipping. The test compiles `xtask/conformance/mrpt_client.cpp`,
//! lets MRPT initialise (trace E: baud probe, 38400, installation mode, 77 with mm and the 32 m
//! mode, 3B, continuous) and checks every range MRPT returns against the emulator's log.

use anyhow::{bail, Result};
use std::path::Path;
use std::process::Command;

use crate::util;

const MRPT_HEADER: &str = "/usr/include/mrpt/hwdrivers/include/mrpt/hwdrivers/CSickLaserSerial.h";

/// Runs the command. Extra arguments go to the test harness (e.g. `--nocapture`).
pub fn run(args: &[String]) -> Result<()> {
    util::ensure_apt("g++", "g++")?;
    if !Path::new(MRPT_HEADER).exists() {
        ensure_apt_package("libmrpt-hwdrivers-dev")?;
        if !Path::new(MRPT_HEADER).exists() {
            bail!("installed libmrpt-hwdrivers-dev but {MRPT_HEADER} is still missing");
        }
    }
    let mut cmd = util::cargo();
    cmd.args([
        "test",
        "-p",
        "host-tests",
        "--test",
        "emulator_mrpt",
        "--",
        "--nocapture",
    ])
    .args(args)
    .env("PFE_CONFORMANCE_REQUIRED", "1");
    util::run(&mut cmd)
}

fn ensure_apt_package(package: &str) -> Result<()> {
    let root = Command::new("id")
        .arg("-u")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
        .unwrap_or(false);
    if !root || !util::have("apt-get") {
        bail!(
            "MRPT is missing: install the Debian package `{package}` (apt-get install {package})"
        );
    }
    let _ = util::run(Command::new("apt-get").arg("update"));
    util::run(
        Command::new("apt-get")
            .args(["install", "-y", "--no-install-recommends", package])
            .env("DEBIAN_FRONTEND", "noninteractive"),
    )
}
