//! `cargo xtask bench-mcu`.

use anyhow::{bail, Result};

/// Runs the command.
pub fn run(_args: &[String]) -> Result<()> {
    bail!("`cargo xtask bench-mcu` is not implemented yet")
}
