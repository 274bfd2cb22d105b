//! `cargo xtask conformance`.

use anyhow::{bail, Result};

/// Runs the command.
pub fn run(_args: &[String]) -> Result<()> {
    bail!("`cargo xtask conformance` is not implemented yet")
}
