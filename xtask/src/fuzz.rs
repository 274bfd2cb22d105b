//! `cargo xtask fuzz`.

use anyhow::{bail, Result};

/// Runs the command.
pub fn run(_args: &[String]) -> Result<()> {
    bail!("`cargo xtask fuzz` is not implemented yet")
}
