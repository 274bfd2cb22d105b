//! `cargo xtask soak`.

use anyhow::{bail, Result};

/// Runs the command.
pub fn run(_args: &[String]) -> Result<()> {
    bail!("`cargo xtask soak` is not implemented yet")
}
