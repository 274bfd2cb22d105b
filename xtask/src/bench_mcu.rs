//! `cargo xtask bench-mcu [--scans N]`: instruction counts of the firmware pipeline on QEMU
//! mps2-an386 with `-icount shift=10` (SysTick-measured; instruction counts, not cycles), for
//! pfe-core with libm and with micromath; refreshes docs/PERFORMANCE.md and fails when the
//! whole pipeline needs more than 200 instructions per point (median).
//!
//! Steps: simulated scans → B0 telegrams (`demo_host bench-scans`), built into the
//! `pfe-bench` firmware (`PFE_BENCH_SCANS`), run under QEMU, timing frames decoded and
//! tabulated (`demo_host bench`).

use anyhow::{Context, Result};

use crate::util;

/// Where the firmware builds go (apart from the host's, so features don't thrash).
pub fn target_dir() -> std::path::PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| util::root().join("target"))
}

/// The firmware's optimisation level: the workspace release profile (LTO, one codegen unit)
/// with `opt-level = "s"` (pfe-core at 3, see the workspace Cargo.toml), what the flash
/// budget is measured on.
pub const FIRMWARE_OPT_LEVEL: &str = "s";

/// Builds a firmware-qemu binary in release for thumbv7em into `dir`; returns the ELF.
pub fn build_fw(
    bin: &str,
    features: &[&str],
    env: &[(&str, &std::ffi::OsStr)],
    dir: &std::path::Path,
) -> Result<std::path::PathBuf> {
    let mut c = util::cargo();
    c.args(["build", "--release", "-p", "firmware-qemu", "--bin", bin])
        .args(["--target", "thumbv7em-none-eabihf"])
        .env("CARGO_TARGET_DIR", dir)
        .env("DEFMT_LOG", "info")
        .env("CARGO_PROFILE_RELEASE_OPT_LEVEL", FIRMWARE_OPT_LEVEL)
        .env_remove("RUSTFLAGS");
    if !features.is_empty() {
        c.args(["--features", &features.join(",")]);
    }
    for (k, v) in env {
        c.env(k, v);
    }
    util::run(&mut c)?;
    Ok(dir.join("thumbv7em-none-eabihf").join("release").join(bin))
}

/// Runs `demo_host` (host-tests example) with `args`.
pub fn demo_host(args: &[&std::ffi::OsStr]) -> Result<()> {
    let mut c = util::cargo();
    c.args([
        "run",
        "--quiet",
        "-p",
        "host-tests",
        "--example",
        "demo_host",
        "--",
    ])
    .args(args);
    util::run(&mut c)
}

/// Runs the command.
pub fn run(args: &[String]) -> Result<()> {
    let scans = match args {
        [] => "100".to_string(),
        [flag, n] if flag == "--scans" => n.clone(),
        _ => anyhow::bail!("usage: cargo xtask bench-mcu [--scans N]"),
    };
    util::ensure_target()?;
    util::ensure_apt("qemu-system-arm", "qemu-system-arm")?;
    let base = target_dir().join("bench-mcu");
    std::fs::create_dir_all(&base).context("creating the bench directory")?;
    let scans_file = base.join("scans.bin");
    demo_host(&[
        "bench-scans".as_ref(),
        "--scans".as_ref(),
        scans.as_ref(),
        "--out".as_ref(),
        scans_file.as_os_str(),
    ])?;
    let env = [("PFE_BENCH_SCANS", scans_file.as_os_str())];
    let libm = build_fw("pfe-bench", &[], &env, &base.join("libm"))?;
    let mm = build_fw("pfe-bench", &["micromath"], &env, &base.join("micromath"))?;
    let md = util::root().join("docs").join("PERFORMANCE.md");
    demo_host(&[
        "bench".as_ref(),
        "--elf".as_ref(),
        libm.as_os_str(),
        "--elf-micromath".as_ref(),
        mm.as_os_str(),
        "--md".as_ref(),
        md.as_os_str(),
    ])
}
