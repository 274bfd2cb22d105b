//! Helpers shared by the `pfe` CLI tests.
#![allow(dead_code)]

use std::path::PathBuf;
use std::process::{Command, Output};

/// A file of `tests/fixtures`.
pub fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

/// Runs `pfe ARGS` and returns what it did.
pub fn pfe(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pfe"))
        .args(args)
        .output()
        .unwrap()
}
