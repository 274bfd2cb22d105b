//! Helpers shared by the integration tests of host-tests and of pfe-cli (which includes this
//! file by path: only its own tests have the `pfe` binary, as `CARGO_BIN_EXE_pfe`).
#![allow(dead_code, clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use lms200_emulator::serve::{serve_on, Pty};
use lms200_emulator::{Emulator, EmulatorReport, RunLimits};

/// A file of `host-tests/tests/fixtures` (from host-tests or from pfe-cli in `host-tests/cli`).
pub fn fixture(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let fixtures = dir.join("tests/fixtures");
    let fixtures = if fixtures.is_dir() {
        fixtures
    } else {
        dir.join("../tests/fixtures")
    };
    fixtures.join(name)
}

/// The `pfe` binary (pfe-cli's tests only).
#[allow(clippy::option_env_unwrap, reason = "host-tests' tests never run pfe")]
pub fn pfe_bin() -> &'static str {
    option_env!("CARGO_BIN_EXE_pfe").expect("only pfe-cli's tests run the pfe binary")
}

/// A fresh, empty directory `pfe-TAG-PID` under the system's temporary directory.
pub fn scratch(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pfe-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A [`scratch`] directory, removed when dropped.
pub struct TempDir(pub PathBuf);

impl TempDir {
    /// A fresh `pfe-TAG-PID` directory.
    pub fn new(tag: &str) -> Self {
        TempDir(scratch(tag))
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// `path` as a command-line argument (test paths are UTF-8).
pub fn arg(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// Runs `pfe ARGS` and returns what it did.
pub fn pfe(args: &[&str]) -> Output {
    Command::new(pfe_bin()).args(args).output().unwrap()
}

/// A run's stdout read as JSON lines.
pub fn json_lines(out: &Output) -> Vec<serde_json::Value> {
    String::from_utf8(out.stdout.clone())
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// Starts `pfe ARGS` with stdin, stdout and stderr piped.
pub fn spawn_pfe(args: &[&str]) -> Child {
    Command::new(pfe_bin())
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// An MCAP writer into `out`, uncompressed, with chunks of `chunk_size` bytes.
pub fn mcap_writer(
    out: &mut std::io::Cursor<Vec<u8>>,
    chunk_size: u64,
) -> mcap::Writer<&mut std::io::Cursor<Vec<u8>>> {
    mcap::WriteOptions::new()
        .compression(None)
        .chunk_size(Some(chunk_size))
        .create(out)
        .unwrap()
}

/// What a run wrote to stderr.
pub fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// The JSON array `v` of whole numbers.
pub fn u64s(v: &serde_json::Value) -> Vec<u64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap())
        .collect()
}

/// The value of `key` in a Foxglove entity's `metadata` list.
pub fn metadata(entity: &serde_json::Value, key: &str) -> String {
    entity["metadata"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["key"] == key)
        .map(|m| m["value"].as_str().unwrap().to_string())
        .unwrap_or_else(|| panic!("no metadata {key}"))
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
    use pfe_testkit::skip::{skip, Need};
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
    python(test, "foxglove/read_foxglove.py", &[arg(path)], "mcap")
}

/// An emulator served on a pseudo-terminal in its own thread for at most 60 s.
pub struct PtyServer {
    stop: Arc<AtomicBool>,
    thread: JoinHandle<anyhow::Result<(EmulatorReport, Pty)>>,
}

impl PtyServer {
    /// Serves `emu` on `pty` until [`PtyServer::stop`].
    pub fn start(mut pty: Pty, emu: Emulator) -> Self {
        let stop = Arc::new(AtomicBool::new(false));
        let limits = RunLimits {
            max_time: Some(Duration::from_secs(60)),
            stop: Some(stop.clone()),
            ..Default::default()
        };
        let thread = std::thread::spawn(move || serve_on(&mut pty, emu, limits).map(|r| (r, pty)));
        PtyServer { stop, thread }
    }

    /// Stops serving; the emulator's report and the pseudo-terminal (kept open until here).
    pub fn stop(self) -> (EmulatorReport, Pty) {
        self.stop.store(true, Ordering::Relaxed);
        self.thread.join().unwrap().unwrap()
    }
}
