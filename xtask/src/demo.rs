//! `cargo xtask demo`.

use anyhow::{bail, Result};

/// Runs the command.
pub fn run(_args: &[String]) -> Result<()> {
    bail!("`cargo xtask demo` is not implemented yet")
}
