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

/// Runs the fixture script `script` (a path under `tests/fixtures`) with `args` and parses its
/// JSON output; without python3 or its `packages`, reports `test` as skipped (a failure in CI)
/// and returns `None`.
pub fn python(
    test: &str,
    script: &str,
    args: &[&str],
    packages: &str,
) -> Option<serde_json::Value> {
    use host_tests::skip::{skip, Need};
    let out = match Command::new("python3")
        .arg(fixture(script))
        .args(args)
        .output()
    {
        Ok(out) => out,
        Err(e) => {
            let why =
                format!("python3 cannot be run ({e}); install it and `pip install {packages}`");
            skip(test, &why, Need::InCi);
            return None;
        }
    };
    let err = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        if err.contains("ModuleNotFoundError") {
            let why = format!(
                "the Python packages are missing ({}); `pip install {packages}`",
                err.lines().last().unwrap_or("")
            );
            skip(test, &why, Need::InCi);
            return None;
        }
        panic!("{script} failed: {err}");
    }
    Some(serde_json::from_slice(&out.stdout).unwrap())
}

/// `read_foxglove.py`'s summary of the Foxglove file `path` (read by Python's `mcap`), or `None`
/// after reporting `test` as skipped.
pub fn read_foxglove(test: &str, path: &std::path::Path) -> Option<serde_json::Value> {
    python(
        test,
        "foxglove/read_foxglove.py",
        &[path.to_str().unwrap()],
        "mcap",
    )
}
