//! Soak test (see [`host_tests::soak`]):
//!
//! ```text
//! cargo run --release -p host-tests --example soak -- [--scans N] [--seed S] [--damage P]
//!     [--transport inproc|pty|qemu]
//! ```

use anyhow::{bail, Result};
use host_tests::soak::{args, inproc, pty, qemu};

fn main() -> Result<()> {
    let a = args()?;
    let ok = if a.qemu {
        qemu::run(&a)?
    } else if a.pty {
        pty(&a)?
    } else {
        inproc(&a)?
    };
    if !ok {
        bail!("soak: the account does not balance");
    }
    Ok(())
}
