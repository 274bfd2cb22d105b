//! `cargo xtask test`: everything CI checks, in order, stopping at the first failure.
//!
//! Installs what it needs (the thumbv7em target; as root, Debian's qemu-system-arm, and
//! libmrpt-hwdrivers-dev for the conformance step), then: formatting, clippy, rustdoc, the no_std
//! builds, every host test (unit, integration, doc, the end-to-end QEMU and emulator runs), the
//! fuzz targets' bodies over the committed regression inputs and generated seeds,
//! firmware sizes and their budgets, the instruction-count budget (`cargo xtask bench-mcu`:
//! counts under `-icount` are deterministic), the host speed against the baselines (`pfe
//! bench --report-only`: timings depend on the machine, so they are printed, not asserted),
//! MRPT conformance, the no-panic build, a sampled mutation run of pfe-core (1 mutant in 100,
//! round-robin; fails below the 90 % target), fuzzing (60 s per target under `CI`, 10 s
//! otherwise) and a short soak. `--quick` stops after the host tests and skips the QEMU end-to-end test.
//! It ends with the list of the tests that were skipped and why ([`pfe_testkit::skip`]), or
//! "skipped: none".

use anyhow::Result;

use crate::util::{cargo, ensure_apt, ensure_target, run as sh};

/// The shared CARMEN logs, from the workspace root (`pfe bench --carmen`).
const CARMEN_LOGS: &str = "../shared/data/carmen";

const THUMB: &str = "thumbv7em-none-eabihf";

/// Runs every step, then lists what was skipped (also after a failure).
pub fn run_all(quick: bool) -> Result<()> {
    let skips = pfe_testkit::skip::skips_file();
    let _ = std::fs::remove_file(&skips);
    let result = steps(quick, &skips);
    eprintln!("\n{}", skipped_summary(&pfe_testkit::skip::listed()));
    result
}

/// The end-of-run list of skipped tests.
fn skipped_summary(lines: &[String]) -> String {
    if lines.is_empty() {
        "skipped: none".to_string()
    } else {
        let mut s = format!("skipped: {}", lines.len());
        for l in lines {
            s.push_str("\n  ");
            s.push_str(l);
        }
        s
    }
}

fn steps(quick: bool, skips: &std::path::Path) -> Result<()> {
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
    step("rustdoc (broken links are errors)", || {
        sh(cargo()
            .args([
                "doc",
                "--no-deps",
                "-p",
                "pfe-core",
                "-p",
                "lms2xx",
                "-p",
                "pfe-frame",
                "-p",
                "firmware",
                "-p",
                "host-tests",
                "-p",
                "pfe-cli",
                "-p",
                "pfe-formats",
                "-p",
                "pfe-eval",
                "-p",
                "lms200-emulator",
                "-p",
                "pfe-testkit",
                "-p",
                "pfe-pose",
                "-p",
                "pfe-capi",
            ])
            .env("RUSTDOCFLAGS", "-D warnings"))
    })?;
    step(
        "no_std builds of pfe-core (libm, micromath) and the firmware library",
        || {
            sh(cargo().args(["build", "--release", "-p", "pfe-core", "--target", THUMB]))?;
            sh(cargo()
                .args(["build", "--release", "-p", "pfe-core", "--target", THUMB])
                .args(["--no-default-features", "--features", "micromath"]))?;
            sh(cargo().args([
                "build",
                "--release",
                "-p",
                "lms2xx",
                "-p",
                "pfe-frame",
                "-p",
                "firmware",
                "-p",
                "pfe-pose",
                "-p",
                "pfe-capi",
                "--lib",
                "--target",
                THUMB,
            ]))?;
            sh(cargo()
                .args([
                    "build",
                    "--release",
                    "-p",
                    "lms2xx",
                    "--lib",
                    "--target",
                    THUMB,
                ])
                .args(["--features", "async"]))
        },
    )?;
    step(
        "the async LMS2xx driver: its tests and clippy (feature `async`)",
        || {
            sh(cargo().args(["test", "-p", "lms2xx", "--features", "async"]))?;
            sh(cargo()
                .args([
                    "clippy",
                    "-p",
                    "lms2xx",
                    "--features",
                    "async",
                    "--all-targets",
                ])
                .args(["--", "-D", "warnings"]))?;
            // The QEMU binaries, blocking and async, for their target (the workspace's clippy
            // runs on the host only).
            sh(cargo()
                .args(["clippy", "-p", "firmware-qemu", "--target", THUMB])
                .args([
                    "--features",
                    "async",
                    "--lib",
                    "--bins",
                    "--",
                    "-D",
                    "warnings",
                ]))
        },
    )?;
    if !quick {
        step(
            "the embassy firmware (firmware/embassy, its own workspace) for the STM32F411",
            || {
                sh(cargo()
                    .args(["clippy", "--release", "--locked", "--target", THUMB])
                    .args(["--manifest-path", "firmware/embassy/Cargo.toml"])
                    .args(["--", "-D", "warnings"]))?;
                sh(cargo()
                    .args(["build", "--release", "--locked", "--target", THUMB])
                    .args(["--manifest-path", "firmware/embassy/Cargo.toml"]))
            },
        )?;
    }
    if !quick {
        step(
            "MSRV: the published crates and the firmware library build with the declared rust-version",
            msrv,
        )?;
        ensure_apt("qemu-system-arm", "qemu-system-arm")?;
    }
    step("host tests (unit, integration, doc, end to end)", || {
        let mut c = cargo();
        c.args(["test", "--workspace"]).env("PFE_SKIPS_FILE", skips);
        if quick {
            c.env("PFE_SKIP_QEMU", "1");
        }
        sh(&mut c)
    })?;
    step(
        "pfe-core's micromath build against its error budget; its build without scrutiny",
        || {
            sh(cargo()
                .args(["test", "-p", "pfe-core", "--no-default-features"])
                .args(["--features", "micromath,scrutiny", "--test", "micromath"]))?;
            sh(cargo()
                .args(["test", "-p", "pfe-core", "--no-default-features"])
                .args(["--features", "libm", "--test", "lean"]))
        },
    )?;
    step("unit tests of the examples (the demo's checks)", || {
        sh(cargo().args(["test", "-p", "host-tests", "--examples"]))
    })?;
    step(
        "fuzz regressions and seeds replayed (cargo test --manifest-path fuzz/Cargo.toml)",
        || crate::fuzz::replay_regressions(skips),
    )?;
    if quick {
        return Ok(());
    }
    step("firmware binaries: sizes, stack and budgets", || {
        crate::size::run(&[])
    })?;
    step("firmware instruction counts and their budget", || {
        crate::bench_mcu::run(&[])
    })?;
    step("firmware worst case per scan and its budget", || {
        crate::bench_mcu::run(&["--worst".into()])
    })?;
    step(
        "host speed against the baselines (reported, not asserted)",
        || {
            // The real-data part needs the shared CARMEN logs, named explicitly.
            let mut bench = crate::util::pfe();
            bench.args(["bench", "--reps", "5", "--report-only"]);
            if crate::util::root().join(CARMEN_LOGS).is_dir() {
                bench.args(["--carmen", CARMEN_LOGS]);
            }
            sh(&mut bench)
        },
    )?;
    step("MRPT conformance", || crate::conformance::run(&[]))?;
    step(
        "no panic path in the firmware",
        || crate::no_panic::run(&[]),
    )?;
    step(
        "mutation testing: a sample of pfe-core (cargo xtask mutants --shard 0/100 --min-score 90)",
        || {
            crate::mutants::run(&[
                "--shard".into(),
                "0/100".into(),
                "--timeout".into(),
                "30".into(),
                "--min-score".into(),
                "90".into(),
            ])
        },
    )?;
    let seconds = if std::env::var_os("CI").is_some() {
        "60"
    } else {
        "10"
    };
    step("fuzzing", || {
        crate::fuzz::run(&["--seconds".into(), seconds.into()])
    })?;
    step("real-data benchmark (shortened)", || {
        crate::realdata::run(&["--check".into()])
    })?;
    step("soak (short)", || {
        crate::soak::run(&["--scans".into(), "2000".into()])
    })?;
    eprintln!("\nall checks passed");
    Ok(())
}

/// The crates users build, on the host; the `no_std` ones also for the Cortex-M target.
const PUBLISHED: [&str; 8] = [
    "pfe-pose",
    "pfe-core",
    "lms2xx",
    "pfe-frame",
    "pfe-formats",
    "pfe-eval",
    "lms200-emulator",
    "pfe-cli",
];
const NO_STD: [&str; 6] = [
    "pfe-core",
    "lms2xx",
    "pfe-frame",
    "firmware",
    "pfe-pose",
    "pfe-capi",
];

/// The workspace's `rust-version` (the root Cargo.toml's `[workspace.package]`).
fn declared_msrv() -> Result<String> {
    let manifest = std::fs::read_to_string(crate::util::root().join("Cargo.toml"))?;
    manifest
        .lines()
        .find_map(|l| l.trim().strip_prefix("rust-version"))
        .and_then(|rest| rest.split('"').nth(1))
        .map(str::to_string)
        .ok_or_else(|| anyhow::anyhow!("no rust-version in the workspace's Cargo.toml"))
}

/// `cargo xtask msrv`: installs the declared MSRV toolchain (rustup, minimal profile, with the
/// thumbv7em target) and checks the published crates on the host and the `no_std` crates for
/// the Cortex-M target with it, against Cargo.lock (`--locked`), in `target/msrv`.
pub fn msrv() -> Result<()> {
    let v = declared_msrv()?;
    sh(std::process::Command::new("rustup")
        .args(["toolchain", "install", &v, "--profile", "minimal"])
        .args(["--target", THUMB]))?;
    let check = |extra: &[&str], crates: &[&str]| {
        let mut c = std::process::Command::new("rustup");
        c.current_dir(crate::util::root())
            .args([
                "run",
                &v,
                "cargo",
                "check",
                "--locked",
                "--target-dir",
                "target/msrv",
            ])
            .args(extra);
        for p in crates {
            c.args(["-p", p]);
        }
        sh(&mut c)
    };
    check(&[], &PUBLISHED)?;
    check(&["--lib", "--target", THUMB], &NO_STD)
}

/// Entry point: `cargo xtask test [--quick]`.
pub fn run(args: &[String]) -> Result<()> {
    run_all(args.iter().any(|a| a == "--quick"))
}

fn step(name: &str, f: impl FnOnce() -> Result<()>) -> Result<()> {
    eprintln!("\n=== {name} ===");
    let start = std::time::Instant::now();
    let result = f().map_err(|e| e.context(format!("step `{name}` failed")));
    // CI's time budget is spent step by step: each step says what it took.
    eprintln!("=== {name}: {:.0} s ===", start.elapsed().as_secs_f64());
    result
}

#[cfg(test)]
mod tests {
    use super::skipped_summary;

    #[test]
    fn summary_lists_every_skip_or_says_none() {
        assert_eq!(skipped_summary(&[]), "skipped: none");
        let s = skipped_summary(&["e2e_qemu: no qemu".into(), "emulator_mrpt: no g++".into()]);
        assert_eq!(
            s,
            "skipped: 2\n  e2e_qemu: no qemu\n  emulator_mrpt: no g++"
        );
    }
}
