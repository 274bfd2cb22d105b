//! `cargo xtask run-qemu --scanner PATH --output PATH [--config paper|default] [--scans N]`:
//! the firmware under QEMU (mps2-an386) with its LMS200 UART on the tty or pty `--scanner`
//! (e.g. the link `pfe emulate --pty` made, or a USB–RS422 adapter) and its feature UART on
//! `--output` (an existing tty, or a new pty linked there): read it with
//! `pfe listen --input PATH`. Runs until the firmware exits or Ctrl-C.

use std::path::PathBuf;
use std::time::Duration;

use anyhow::{bail, Result};
use pfe_testkit::run_qemu::RunQemu;

use crate::fw::{build_fw, target_dir};
use crate::util;

const USAGE: &str =
    "usage: cargo xtask run-qemu --scanner PATH --output PATH [--config paper|default] [--scans N]";

/// Runs the command.
pub fn run(args: &[String]) -> Result<()> {
    let (mut scanner, mut output) = (None, None);
    let mut config = "default".to_string();
    let mut scans = 0u32;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let v = it.next().cloned();
        match (a.as_str(), v) {
            ("--scanner", Some(v)) => scanner = Some(PathBuf::from(v)),
            ("--output", Some(v)) => output = Some(PathBuf::from(v)),
            ("--config", Some(v)) if v == "paper" || v == "default" => config = v,
            ("--scans", Some(v)) => scans = v.parse()?,
            _ => bail!(USAGE),
        }
    }
    let (Some(scanner), Some(output)) = (scanner, output) else {
        bail!(USAGE)
    };
    util::ensure_target()?;
    util::ensure_apt("qemu-system-arm", "qemu-system-arm")?;
    let elf = build_fw("pfe-qemu", &[], &[], &target_dir().join("run-qemu"))?;
    let mut q = RunQemu::start(&elf, &scanner, &output, &config, scans)?;
    eprintln!(
        "run-qemu: firmware ({config}) reads the LMS200 on {}, sends features on {} ({}); \
         pfe listen --input {}",
        scanner.display(),
        output.display(),
        q.output_device.display(),
        output.display()
    );
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let _ = signal_hook::flag::register(signal_hook::consts::SIGINT, stop.clone());
    loop {
        if let Some(code) = q.wait(Duration::from_millis(200))? {
            eprintln!("run-qemu: firmware exited with {code}");
            if code != 0 {
                bail!("firmware exit code {code} (3: scanner link failed, 4: output failed)");
            }
            return Ok(());
        }
        if stop.load(std::sync::atomic::Ordering::SeqCst) {
            eprintln!("run-qemu: interrupted");
            return Ok(());
        }
    }
}
