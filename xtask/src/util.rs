//! Helpers shared by the xtask commands: running programs, installing what they need.

use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The workspace root (parent of `xtask/`).
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."))
}

/// `cargo` as invoked by the user.
pub fn cargo() -> Command {
    let mut c = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    c.current_dir(root());
    c
}

/// `cargo run --release -q -p {package} {target} {name}`, `target` `--bin` or `--example`.
fn cargo_run(package: &str, target: &str, name: &str) -> Command {
    let mut c = cargo();
    c.args(["run", "--release", "-q", "-p", package, target, name]);
    c
}

/// `cargo run --release -q -p host-tests --example {name}` (append `--` and its arguments).
pub fn host_example(name: &str) -> Command {
    cargo_run("host-tests", "--example", name)
}

/// `cargo run --release -q -p pfe-cli --bin pfe --` (append the `pfe` arguments).
pub fn pfe() -> Command {
    let mut c = cargo_run("pfe-cli", "--bin", "pfe");
    c.arg("--");
    c
}

/// Runs `cmd`, echoing it, and fails with its exit status.
pub fn run(cmd: &mut Command) -> Result<()> {
    eprintln!("$ {cmd:?}");
    let status = cmd
        .status()
        .with_context(|| format!("cannot start {cmd:?}"))?;
    if !status.success() {
        bail!("{cmd:?} failed: {status}");
    }
    Ok(())
}

/// True when `program` is on PATH.
pub fn have(program: &str) -> bool {
    Command::new("sh")
        .args(["-c", &format!("command -v {program} >/dev/null 2>&1")])
        .status()
        .map(|s| s.success())
        .unwrap_or(false)
}

/// Makes sure the Cortex-M target and llvm-tools are installed (rustup).
pub fn ensure_target() -> Result<()> {
    let out = Command::new("rustup")
        .args(["target", "list", "--installed"])
        .output()
        .context("rustup is needed to install the thumbv7em-none-eabihf target")?;
    if !String::from_utf8_lossy(&out.stdout).contains("thumbv7em-none-eabihf") {
        run(Command::new("rustup").args(["target", "add", "thumbv7em-none-eabihf"]))?;
    }
    Ok(())
}

/// Makes sure flip-link, the firmware's linker (`.cargo/config.toml`), is on PATH
/// (`cargo install flip-link --locked`, about 10 s).
pub fn ensure_flip_link() -> Result<()> {
    if !have("flip-link") {
        run(Command::new("cargo").args(["install", "flip-link", "--locked"]))?;
    }
    if !have("flip-link") {
        bail!("flip-link is still missing after `cargo install flip-link --locked`");
    }
    Ok(())
}

/// Makes sure `program` exists, installing Debian `package` when running as root; otherwise
/// says precisely what is missing.
pub fn ensure_apt(program: &str, package: &str) -> Result<()> {
    if have(program) {
        return Ok(());
    }
    let root = Command::new("id")
        .arg("-u")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
        .unwrap_or(false);
    if !root || !have("apt-get") {
        bail!("`{program}` is missing: install the Debian package `{package}` (apt-get install {package})");
    }
    static UPDATED: std::sync::Once = std::sync::Once::new();
    UPDATED.call_once(|| {
        let _ = run(Command::new("apt-get").arg("update"));
    });
    run(Command::new("apt-get")
        .args(["install", "-y", "--no-install-recommends", package])
        .env("DEBIAN_FRONTEND", "noninteractive"))?;
    if !have(program) {
        bail!("installed {package} but `{program}` is still missing");
    }
    Ok(())
}

/// An LLVM tool of the rustup `llvm-tools` component (installed on demand).
pub fn llvm_tool(name: &str) -> Result<PathBuf> {
    let find = || -> Option<PathBuf> {
        let out = Command::new("rustc")
            .args(["--print", "sysroot"])
            .output()
            .ok()?;
        let sysroot = PathBuf::from(String::from_utf8_lossy(&out.stdout).trim());
        std::fs::read_dir(sysroot.join("lib/rustlib"))
            .ok()?
            .flatten()
            .map(|e| e.path().join("bin").join(name))
            .find(|p| p.is_file())
    };
    if let Some(p) = find() {
        return Ok(p);
    }
    run(Command::new("rustup").args(["component", "add", "llvm-tools"]))?;
    find().with_context(|| format!("{name} not found after `rustup component add llvm-tools`"))
}

/// The shared CARMEN logs, relative to the repository root.
const SHARED_LOGS: &str = "../shared/data/carmen";

/// Every CARMEN log in `../shared/data/carmen` (relative paths, sorted), or `None` after a loud
/// skip named `job` when the shared data is absent (under CI, which has it, a failure).
pub fn shared_carmen_logs(job: &str) -> Result<Option<Vec<String>>> {
    let dir = root().join(SHARED_LOGS);
    if !dir.is_dir() {
        pfe_testkit::skip::skip(
            job,
            "../shared/data not found",
            pfe_testkit::skip::Need::InCi,
        );
        return Ok(None);
    }
    let mut logs: Vec<String> = std::fs::read_dir(&dir)
        .with_context(|| format!("reading {}", dir.display()))?
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().to_string())
        .filter(|n| pfe_formats::carmen::is_log_name(n))
        .map(|n| format!("{SHARED_LOGS}/{n}"))
        .collect();
    logs.sort();
    Ok(Some(logs))
}

/// `cargo xtask JOB ARGS…`, as a generated document names the command that wrote it.
pub fn xtask_command(job: &str, args: &[String]) -> String {
    let mut named = format!("cargo xtask {job}");
    for a in args {
        named.push(' ');
        named.push_str(a);
    }
    named
}
