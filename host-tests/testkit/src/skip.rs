//! Skipped tests are reported, never silent passes.
//!
//! A test that cannot run (no `../shared/data`, no `qemu-system-arm`, no g++/MRPT) calls
//! [`skip`]: it prints `SKIPPED: <test>: <reason>` and appends the same line to
//! [`skips_file`], which `cargo xtask test` clears before its test step and lists at the end.
//! Under `CI=true` a skip of something CI installs is a failure (a panic), so CI never passes
//! by skipping.

use std::io::Write;
use std::path::PathBuf;

/// Whether CI provides what is missing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Need {
    /// CI installs it (QEMU, MRPT and g++, the thumbv7em target) or has it (`../shared/data`):
    /// skipping under `CI=true` fails.
    InCi,
    /// A local choice (e.g. `PFE_SKIP_QEMU` from `cargo xtask test --quick`): never a failure.
    Optional,
}

/// The file skips are listed in: `$PFE_SKIPS_FILE`, else `pfe-skips.txt` in
/// `$CARGO_TARGET_DIR` or the workspace's `target/`.
pub fn skips_file() -> PathBuf {
    if let Some(f) = std::env::var_os("PFE_SKIPS_FILE") {
        return PathBuf::from(f);
    }
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target"))
        .join("pfe-skips.txt")
}

/// True when running under CI (`CI=true`, as GitHub Actions sets it).
pub fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v == "true" || v == "1")
}

/// Reports that `test` is skipped because of `reason`; panics under `CI=true` when CI
/// provides what is missing (`need` is [`Need::InCi`]).
#[allow(
    clippy::panic,
    reason = "a test helper: its panic is the calling test's failure"
)]
pub fn skip(test: &str, reason: &str, need: Need) {
    let line = format!("SKIPPED: {test}: {reason}");
    eprintln!("{line}");
    let path = skips_file();
    if let Some(dir) = path.parent() {
        let _ = std::fs::create_dir_all(dir);
    }
    let written = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&path)
        .and_then(|mut f| writeln!(f, "{test}: {reason}"));
    if let Err(e) = written {
        eprintln!("warning: cannot list the skip in {}: {e}", path.display());
    }
    if need == Need::InCi && in_ci() {
        panic!("{test}: {reason}; CI provides this, so skipping it is a failure");
    }
}

/// The skips listed in [`skips_file`], one `test: reason` per line.
pub fn listed() -> Vec<String> {
    std::fs::read_to_string(skips_file())
        .map(|s| s.lines().map(str::to_string).collect())
        .unwrap_or_default()
}

/// The shared real recordings, `shared/data` beside the repository, when it holds every folder
/// of `needs` (`"carmen"`, `"hokuyo-cylinders"`); else `None` after skipping `test` loudly (a
/// failure under `CI=true`, [`Need::InCi`]).
pub fn shared_data(test: &str, needs: &[&str]) -> Option<std::path::PathBuf> {
    let d = crate::qemu::root().join("../shared/data");
    if needs.iter().all(|n| d.join(n).is_dir()) {
        Some(d)
    } else {
        skip(
            test,
            &format!(
                "real data folder {} (with {}) is absent (it sits beside the repository as shared/data)",
                d.display(),
                needs.join(", ")
            ),
            Need::InCi,
        );
        None
    }
}
