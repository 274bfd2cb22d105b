//! `cargo xtask soak [--scans N] [--pty-scans M] [--qemu-scans Q] [--seed S] [--damage P]`:
//! the long run.
//!
//! Builds and runs the release example `host-tests/examples/soak.rs`: tagged scans → emulated
//! LMS200 with ~1 % damage (bit flips, dropped/duplicated bytes, truncation, garbage, device
//! resets, silences) → firmware driver → pfe-core (paper and default) → output frames, over the
//! in-process virtual-time link for N scans (default 100 000; CI uses 2000; 0 to skip), then
//! a shorter run over a pseudo-terminal in real time (M scans, default 300, 0 to skip), then the real
//! firmware (`pfe-qemu`) under QEMU against the emulator on a pty (Q scans, default 2000, 0 to
//! skip; skipped with a notice when qemu-system-arm or the target is missing). Each prints its
//! account (sent, delivered intact, dropped as damaged, missing, duplicated, damaged accepted;
//! for QEMU also the firmware's counters and stack high-water mark) and fails unless every
//! intact scan arrived exactly once and no damaged one was accepted.

use anyhow::{bail, Context, Result};

use crate::util::{host_example, run as sh};

/// Entry point.
pub fn run(args: &[String]) -> Result<()> {
    let mut scans = "100000".to_string();
    let mut pty_scans = "300".to_string();
    let mut qemu_scans = "2000".to_string();
    let mut extra: Vec<String> = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || {
            it.next()
                .cloned()
                .with_context(|| format!("{a} needs a value"))
        };
        match a.as_str() {
            "--scans" => scans = val()?,
            "--pty-scans" => pty_scans = val()?,
            "--qemu-scans" => qemu_scans = val()?,
            "--seed" | "--damage" => {
                let v = val()?;
                extra.extend([a.clone(), v]);
            }
            other => bail!("unknown argument {other:?} (usage: cargo xtask soak [--scans N] [--pty-scans M] [--qemu-scans Q] [--seed S] [--damage P])"),
        }
    }
    let example = |transport: &str, n: &str| {
        let mut c = host_example("soak");
        c.arg("--")
            .args(["--transport", transport, "--scans", n])
            .args(&extra);
        c
    };
    if scans != "0" {
        sh(&mut example("inproc", &scans))?;
    }
    if pty_scans != "0" {
        // More damage on the short real-time run, unless --damage says otherwise.
        let mut c = example("pty", &pty_scans);
        if !extra.iter().any(|a| a == "--damage") {
            c.args(["--damage", "0.05"]);
        }
        sh(&mut c)?;
    }
    if qemu_scans != "0" {
        sh(&mut example("qemu", &qemu_scans))?;
    }
    Ok(())
}
