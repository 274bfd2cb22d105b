//! `cargo xtask <command>`: the project's commands (see README.md).
//!
//! Each command lives in its own module; `util` holds what they share; generated document
//! sections are written by `pfe_formats::docs`, as `pfe bench` writes them.

mod bench_mcu;
mod conformance;
mod demo;
mod eval;
mod fuzz;
mod fw;
mod mutants;
mod no_panic;
mod pose;
mod realdata;
mod run_qemu;
mod size;
mod soak;
mod stack;
mod test;
#[allow(dead_code)]
mod util;

use anyhow::{bail, Result};

const HELP: &str = "cargo xtask <command> [args]

  demo          firmware in QEMU against the emulated LMS200, prints features (main job)
  test          everything CI runs: fmt, clippy, unit/integration tests, thumbv7em builds,
                end-to-end QEMU test, MRPT conformance, no-panic build, budgets
  msrv          the published crates built with the declared rust-version (rustup installs it)
  eval          PFE paper/default vs ACF and split-and-merge on simulated scans -> docs/EVALUATION.md
  conformance   MRPT's CSickLaserSerial against the emulator on a pseudo-terminal
  bench-mcu     instruction counts on mps2-an386 under QEMU (budgets enforced)
  size          flash/RAM of both firmware binaries and the stack high-water mark (budgets enforced),
                beside the static stack bound
  stack         static worst-case stack bound of pfe-qemu (call graph of -Z emit-stack-sizes build)
  fuzz          every cargo-fuzz target for --seconds S
  mutants       cargo-mutants on pfe-core (--firmware: lms and output) [--shard K/N] [--min-score PCT]
  no-panic      firmware build whose link fails if a panic path survives
  run-qemu      firmware in QEMU between a scanner tty/pty and a feature pty (--scanner, --output)
  soak          long runs with 1% damage: in-process, on a pty, and the firmware under QEMU
  realdata      features re-found in the next scan on the shared CARMEN logs -> docs/REALDATA.md
  pose          pose benchmark (pfe posebench) on the shared CARMEN logs -> docs/POSE.md (--quick)
";

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(cmd) = args.first() else {
        eprint!("{HELP}");
        return Ok(());
    };
    let rest = args.get(1..).unwrap_or(&[]);
    match cmd.as_str() {
        "help" | "--help" | "-h" => {
            eprint!("{HELP}");
            Ok(())
        }
        "demo" => demo::run(rest),
        "test" => test::run(rest),
        "msrv" => test::msrv(),
        "eval" => eval::run(rest),
        "conformance" => conformance::run(rest),
        "bench-mcu" => bench_mcu::run(rest),
        "size" => size::run(rest),
        "stack" => stack::run(rest),
        "fuzz" => fuzz::run(rest),
        "mutants" => mutants::run(rest),
        "no-panic" => no_panic::run(rest),
        "soak" => soak::run(rest),
        "realdata" => realdata::run(rest),
        "pose" => pose::run(rest),
        "run-qemu" => run_qemu::run(rest),
        other => bail!("unknown command `{other}` (rest: {rest:?})\n\n{HELP}"),
    }
}
