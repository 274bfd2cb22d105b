//! `cargo xtask demo [--scans N] [--config default|paper] [--seed S]`: the firmware under QEMU
//! (mps2-an386) against the emulated LMS200 serving simulated scenes. Prints one line per scan
//! (features, lines, circles, link counters), checks the features against pfe-core on the host
//! and against the simulator's ground truth, and writes `target/demo/scan0.svg`.
//!
//! Installs what it needs: the thumbv7em target (rustup) and qemu-system-arm (apt, as root).

use anyhow::{bail, Result};

use crate::fw::{build_fw, demo_host, target_dir};
use crate::util;

/// Runs the command.
pub fn run(args: &[String]) -> Result<()> {
    let mut scans = "10".to_string();
    let mut config = "default".to_string();
    let mut seed = "1".to_string();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let v = it.next().cloned();
        match (a.as_str(), v) {
            ("--scans", Some(v)) => scans = v,
            ("--config", Some(v)) => config = v,
            ("--seed", Some(v)) => seed = v,
            _ => bail!("usage: cargo xtask demo [--scans N] [--config default|paper] [--seed S]"),
        }
    }
    util::ensure_target()?;
    util::ensure_apt("qemu-system-arm", "qemu-system-arm")?;
    let dir = target_dir().join("demo");
    let elf = build_fw("pfe-qemu", &[], &[], &dir.join("firmware"))?;
    let svg = dir.join("scan0.svg");
    let log = dir.join("defmt.bin");
    eprintln!(
        "the firmware's defmt log (semihosting) goes to {}; decode it with `defmt-print -e {} < {}`",
        log.display(),
        elf.display(),
        log.display()
    );
    demo_host(&[
        "demo".as_ref(),
        "--elf".as_ref(),
        elf.as_os_str(),
        "--scans".as_ref(),
        scans.as_ref(),
        "--config".as_ref(),
        config.as_ref(),
        "--seed".as_ref(),
        seed.as_ref(),
        "--svg".as_ref(),
        svg.as_os_str(),
        "--defmt-log".as_ref(),
        log.as_os_str(),
    ])?;
    Ok(())
}
