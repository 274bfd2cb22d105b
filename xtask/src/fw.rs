//! What the firmware jobs (`bench-mcu`, `size`, `stack`, `demo`, `run-qemu`) share: where
//! and how the firmware is built, the `demo_host` example, and the generated sections of
//! docs/PERFORMANCE.md. Below every job module, so that they do not import each other.

use std::path::Path;

use anyhow::Result;

use crate::util;

/// Where the firmware builds go (apart from the host's, so features don't thrash).
pub fn target_dir() -> std::path::PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| util::root().join("target"))
}

/// The firmware's optimisation level (one value for xtask and the QEMU tests).
pub use pfe_testkit::qemu::FIRMWARE_OPT_LEVEL;

/// Builds a firmware-qemu binary in release for thumbv7em into `dir` at
/// [`FIRMWARE_OPT_LEVEL`] with `DEFMT_LOG=info` (`env` may override both); returns the ELF.
pub fn build_fw(
    bin: &str,
    features: &[&str],
    env: &[(&str, &std::ffi::OsStr)],
    dir: &std::path::Path,
) -> Result<std::path::PathBuf> {
    let mut all: Vec<(&str, &std::ffi::OsStr)> = vec![
        ("DEFMT_LOG", "info".as_ref()),
        (
            "CARGO_PROFILE_RELEASE_OPT_LEVEL",
            FIRMWARE_OPT_LEVEL.as_ref(),
        ),
    ];
    all.extend_from_slice(env);
    eprintln!(
        "$ cargo build --release -p firmware-qemu --bin {bin} (into {})",
        dir.display()
    );
    pfe_testkit::qemu::build_firmware(bin, features, &all, dir)
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

/// Replaces (or appends) the section between `<!-- name:start -->` and `<!-- name:end -->`.
pub fn write_section(path: &Path, name: &str, body: &str) -> Result<()> {
    write_section_titled(path, name, &format!("`cargo xtask {name}`"), name, body)
}

/// [`write_section`] with its own heading, for a section `name` produced by `cargo xtask {command}`.
pub fn write_section_titled(
    path: &Path,
    name: &str,
    heading: &str,
    command: &str,
    body: &str,
) -> Result<()> {
    let body = format!("Reproduce: `cargo xtask {command}`\n\n{body}");
    pfe_formats::docs::write_section(path, name, heading, &body, false)
}
