//! `cargo xtask fuzz [--seconds S] [--runs N] [--target NAME]…`: builds and runs every cargo-fuzz target
//! (`fuzz/`, libFuzzer, nightly) for S seconds each (default 60), or until N executions if sooner, and prints a table of
//! executions, exec/s, coverage (`cov`) and features (`ft`) from libFuzzer's final lines.
//!
//! Installs cargo-fuzz (`cargo install cargo-fuzz --locked`) and the nightly toolchain when
//! missing. Seed corpora are generated first into `fuzz/corpus/<target>/` (not committed) by
//! `fuzz/harness`'s `seeds` binary from the protocol test vectors and the real logs in
//! `../shared/data`. A crash fails the command and names the reproducer in
//! `fuzz/artifacts/<target>/`; copy it to `fuzz/regressions/<target>/` once fixed so that
//! `cargo test --manifest-path fuzz/Cargo.toml` (a step of `cargo xtask test`) replays it
//! forever. Each target is given three directories: its corpus (where libFuzzer adds what it
//! finds), then, read only, its committed minimised campaign corpus (`fuzz/corpus-min/<target>/`)
//! and its committed regressions, so every run starts from the campaign's coverage and from the
//! inputs that once crashed.

use anyhow::{bail, Context, Result};
use std::path::Path;
use std::process::{Command, Stdio};

use crate::util::{have, root};

/// The fuzz targets, in the order they run.
pub const TARGETS: [&str; 6] = [
    "lms_decoder",
    "extractor",
    "readers",
    "frame_decoder",
    "lms_driver",
    "lms_driver_async",
];

/// The target whose committed inputs `target` reads: the async driver's target takes the
/// blocking driver's input layout, so it starts from that target's corpus and regressions.
fn inputs_of(target: &str) -> &str {
    match target {
        "lms_driver_async" => "lms_driver",
        t => t,
    }
}

/// libFuzzer's summary of one run.
#[derive(Debug, Default)]
struct Outcome {
    execs: u64,
    exec_per_s: u64,
    cov: u64,
    ft: u64,
    corpus: u64,
    crashed: bool,
    artifact: Option<String>,
}

fn field(line: &str, key: &str) -> Option<u64> {
    let mut words = line.split_whitespace();
    while let Some(w) = words.next() {
        if w == key {
            let v = words.next()?;
            return v.trim_end_matches(['b', 'k', 'M', '/']).parse().ok();
        }
    }
    None
}

/// Parses libFuzzer's stderr: the last status line (`#N DONE cov: C ft: F corp: K/… exec/s: E`)
/// and `stat::number_of_executed_units`.
fn parse(stderr: &str) -> Outcome {
    let mut o = Outcome::default();
    for line in stderr.lines() {
        if let Some(n) = line
            .strip_prefix('#')
            .and_then(|r| r.split_whitespace().next())
            .and_then(|n| n.parse::<u64>().ok())
        {
            o.execs = o.execs.max(n);
            o.cov = field(line, "cov:").unwrap_or(o.cov);
            o.ft = field(line, "ft:").unwrap_or(o.ft);
            o.exec_per_s = field(line, "exec/s:").unwrap_or(o.exec_per_s);
            if let Some(c) = line
                .split("corp: ")
                .nth(1)
                .and_then(|r| r.split('/').next())
                .and_then(|c| c.parse().ok())
            {
                o.corpus = c;
            }
        }
        if let Some(n) = line
            .strip_prefix("stat::number_of_executed_units: ")
            .and_then(|n| n.trim().parse().ok())
        {
            o.execs = n;
        }
        if let Some(n) = line
            .strip_prefix("stat::average_exec_per_sec: ")
            .and_then(|n| n.trim().parse().ok())
        {
            o.exec_per_s = n;
        }
        if line.contains("ERROR: libFuzzer")
            || line.contains("panicked at")
            || line.contains("deadly signal")
        {
            o.crashed = true;
        }
        if let Some(a) = line.split("Test unit written to ").nth(1) {
            o.artifact = Some(a.trim().to_string());
        }
    }
    o
}

fn ensure_tools() -> Result<()> {
    let nightly = Command::new("rustup")
        .args(["run", "nightly", "rustc", "--version"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .map(|s| s.success())
        .unwrap_or(false);
    if !nightly {
        crate::util::run(Command::new("rustup").args([
            "toolchain",
            "install",
            "nightly",
            "--profile",
            "minimal",
        ]))?;
    }
    let fuzz = Command::new("cargo")
        .args(["fuzz", "--version"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .map(|s| s.success())
        .unwrap_or(false);
    if !fuzz {
        crate::util::run(Command::new("cargo").args(["install", "cargo-fuzz", "--locked"]))?;
    }
    if !have("cargo-fuzz") {
        bail!("cargo-fuzz is still missing after `cargo install cargo-fuzz --locked`");
    }
    Ok(())
}

fn fuzz_cmd(args: &[&str]) -> Command {
    let mut c = Command::new("cargo");
    c.arg("+nightly")
        .arg("fuzz")
        .args(args)
        .current_dir(root())
        // cargo-fuzz keeps its own target dir under fuzz/; a CARGO_TARGET_DIR from the caller
        // would mix sanitizer builds with ordinary ones.
        .env_remove("CARGO_TARGET_DIR")
        .env_remove("RUSTFLAGS");
    c
}

/// Generates the seed corpora into `fuzz/corpus/`.
fn seeds(fuzz: &Path) -> Result<()> {
    let shared = root().join("../shared");
    let mut c = Command::new("cargo");
    c.args(["run", "--release", "-q", "--manifest-path"])
        .arg(fuzz.join("Cargo.toml"))
        .args(["-p", "pfe-fuzz-harness", "--bin", "seeds", "--"])
        .arg(fuzz.join("corpus"))
        .arg(&shared)
        .env_remove("RUSTFLAGS");
    crate::util::run(&mut c)
}

/// The corpus directories libFuzzer is given for `target`: the corpus it writes to first,
/// then the committed minimised campaign corpus and regression inputs (libFuzzer only reads
/// those: it adds new inputs to the first directory).
fn corpus_dirs(fuzz: &Path, target: &str) -> [std::path::PathBuf; 3] {
    [
        fuzz.join("corpus").join(target),
        fuzz.join("corpus-min").join(inputs_of(target)),
        fuzz.join("regressions").join(inputs_of(target)),
    ]
}

/// `cargo test` of the fuzz workspace: the harness replays `fuzz/regressions/<target>/` (and
/// fails when a target has none) and generated seeds, without nightly or libFuzzer.
pub fn replay_regressions(skips: &Path) -> Result<()> {
    let mut c = Command::new("cargo");
    c.args(["test", "--manifest-path"])
        .arg(root().join("fuzz/Cargo.toml"))
        .args(["-p", "pfe-fuzz-harness"])
        .env("PFE_SKIPS_FILE", skips)
        .env_remove("RUSTFLAGS");
    crate::util::run(&mut c)
}

/// Entry point.
pub fn run_cmd(args: &[String]) -> Result<()> {
    let mut seconds = 60u64;
    let mut runs: Option<u64> = None;
    let mut only: Vec<String> = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--seconds" => {
                seconds = it
                    .next()
                    .context("--seconds needs a value")?
                    .parse()
                    .context("--seconds needs a whole number")?;
            }
            "--runs" => {
                runs = Some(
                    it.next()
                        .context("--runs needs a value")?
                        .parse()
                        .context("--runs needs a whole number")?,
                );
            }
            "--target" => only.push(it.next().context("--target needs a name")?.clone()),
            other => bail!("unknown argument {other:?} (usage: cargo xtask fuzz [--seconds S] [--runs N] [--target NAME]…)"),
        }
    }
    let targets: Vec<&str> = TARGETS
        .iter()
        .copied()
        .filter(|t| only.is_empty() || only.iter().any(|o| o == t))
        .collect();
    if targets.is_empty() {
        bail!("no such target: {only:?} (targets: {TARGETS:?})");
    }
    ensure_tools()?;
    let fuzz = root().join("fuzz");
    seeds(&fuzz)?;
    crate::util::run(&mut fuzz_cmd(&["build", "--fuzz-dir", "fuzz"]))?;
    let mut rows = Vec::new();
    for t in &targets {
        let corpus = fuzz.join("corpus").join(t);
        std::fs::create_dir_all(&corpus)?;
        let artifacts = fuzz.join("artifacts").join(t);
        std::fs::create_dir_all(&artifacts)?;
        let mut c = fuzz_cmd(&["run", "--fuzz-dir", "fuzz", t]);
        c.args(corpus_dirs(&fuzz, t))
            .arg("--")
            .arg(format!("-max_total_time={seconds}"))
            .arg("-print_final_stats=1")
            .arg(format!("-artifact_prefix={}/", artifacts.display()))
            .arg("-max_len=8192")
            .arg("-timeout=10")
            .arg("-rss_limit_mb=2048");
        if let Some(n) = runs {
            // The campaign's stop: N executions (or the time limit, whichever comes first).
            c.arg(format!("-runs={n}"));
        }
        eprintln!("$ {c:?}");
        let out = c.output().with_context(|| format!("cannot run {c:?}"))?;
        let stderr = String::from_utf8_lossy(&out.stderr);
        let mut o = parse(&stderr);
        if !out.status.success() {
            o.crashed = true;
            // The crash report, for the log.
            let tail: Vec<&str> = stderr.lines().rev().take(60).collect();
            for l in tail.iter().rev() {
                eprintln!("  | {l}");
            }
        }
        rows.push((t.to_string(), o));
    }
    println!("\nfuzzing, {seconds} s per target (command: cargo xtask fuzz --seconds {seconds})");
    println!(
        "{:<14} {:>12} {:>9} {:>7} {:>7} {:>7}  result",
        "target", "executions", "exec/s", "cov", "ft", "corpus"
    );
    let mut failed = Vec::new();
    for (t, o) in &rows {
        println!(
            "{:<14} {:>12} {:>9} {:>7} {:>7} {:>7}  {}",
            t,
            o.execs,
            o.exec_per_s,
            o.cov,
            o.ft,
            o.corpus,
            if o.crashed {
                format!("CRASH {}", o.artifact.as_deref().unwrap_or("(see log)"))
            } else {
                "ok".into()
            }
        );
        if o.crashed {
            failed.push(t.clone());
        }
    }
    if !failed.is_empty() {
        bail!("fuzz targets crashed: {failed:?} (reproduce: cargo +nightly fuzz run --fuzz-dir fuzz <target> <artifact>)");
    }
    Ok(())
}

/// `cargo xtask fuzz` entry point (see the module docs).
pub fn run(args: &[String]) -> Result<()> {
    run_cmd(args)
}

#[cfg(test)]
mod tests {
    use super::{corpus_dirs, inputs_of, TARGETS};
    use std::path::Path;

    #[test]
    fn every_target_gets_its_corpus_its_minimised_corpus_and_its_regressions() {
        let fuzz = Path::new("/f");
        for t in TARGETS {
            assert_eq!(
                corpus_dirs(fuzz, t),
                [
                    fuzz.join("corpus").join(t),
                    fuzz.join("corpus-min").join(inputs_of(t)),
                    fuzz.join("regressions").join(inputs_of(t))
                ]
            );
        }
        // The committed directories exist for every target (the fuzz harness's test checks
        // that each holds at least one input).
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz");
        for t in TARGETS {
            for d in &corpus_dirs(&root, t)[1..] {
                assert!(d.is_dir(), "{} is missing", d.display());
            }
        }
    }
}
