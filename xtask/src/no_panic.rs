//! `cargo xtask no-panic`.

use anyhow::{bail, Result};

/// Runs the command.
pub fn run(_args: &[String]) -> Result<()> {
    bail!("`cargo xtask no-panic` is not implemented yet")
}
