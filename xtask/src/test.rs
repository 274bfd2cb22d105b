//! `cargo xtask test`.

use anyhow::{bail, Result};

/// Runs the command.
pub fn run(_args: &[String]) -> Result<()> {
    bail!("`cargo xtask test` is not implemented yet")
}
