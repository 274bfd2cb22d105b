//! `cargo xtask test`: everything CI checks, in order, stopping at the first failure.
//!
//! Installs what it needs (the thumbv7em target; as root, Debian's qemu-system-arm and
//! libmrpt-hwdrivers-dev), then: formatting, clippy, every host test, the no_std builds,
//! the firmware binaries and their budgets, the end-to-end QEMU run, MRPT conformance, the
//! no-panic build and short fuzzing runs. `--quick` skips the QEMU, MRPT and fuzz steps.

use anyhow::Result;

use crate::util::{cargo, ensure_apt, ensure_target, run as sh};

/// Runs the command.
pub fn run_all(quick: bool) -> Result<()> {
    ensure_target()?;
    step("format", || {
        sh(cargo().args(["fmt", "--all", "--", "--check"]))
    })?;
    step("clippy", || {
        sh(cargo().args([
            "clippy",
            "--workspace",
            "--all-targets",
            "--",
            "-D",
            "warnings",
        ]))
    })?;
    step(
        "no_std builds of pfe-core (libm and micromath) and firmware",
        || {
            for features in [
                &["--features", "libm"][..],
                &["--no-default-features", "--features", "micromath"],
            ] {
                sh(cargo()
                    .args([
                        "build",
                        "--release",
                        "-p",
                        "pfe-core",
                        "--target",
                        "thumbv7em-none-eabihf",
                    ])
                    .args(features))?;
            }
            sh(cargo().args([
                "build",
                "--release",
                "-p",
                "firmware",
                "--lib",
                "--target",
                "thumbv7em-none-eabihf",
            ]))
        },
    )?;
    if !quick {
        ensure_apt("qemu-system-arm", "qemu-system-arm")?;
    }
    step("host tests (unit, integration, doc, end to end)", || {
        let mut c = cargo();
        c.args(["test", "--workspace"]);
        if quick {
            c.env("PFE_SKIP_QEMU", "1");
        }
        sh(&mut c)
    })?;
    if quick {
        return Ok(());
    }
    step("firmware sizes and budgets", || crate::size::run(&[]))?;
    step("instruction counts on the Cortex-M4F and budgets", || {
        crate::bench_mcu::run(&[])
    })?;
    step(
        "no panic path in the firmware",
        || crate::no_panic::run(&[]),
    )?;
    step("MRPT conformance", || crate::conformance::run(&[]))?;
    let seconds = if std::env::var_os("CI").is_some() {
        "60"
    } else {
        "10"
    };
    step("fuzzing", || {
        crate::fuzz::run(&["--seconds".into(), seconds.into()])
    })?;
    step("soak (short)", || {
        crate::soak::run(&["--scans".into(), "2000".into()])
    })?;
    eprintln!("\nall checks passed");
    Ok(())
}

/// Entry point: `cargo xtask test [--quick]`.
pub fn run(args: &[String]) -> Result<()> {
    run_all(args.iter().any(|a| a == "--quick"))
}

fn step(name: &str, f: impl FnOnce() -> Result<()>) -> Result<()> {
    eprintln!("\n=== {name} ===");
    f().map_err(|e| e.context(format!("step `{name}` failed")))
}
