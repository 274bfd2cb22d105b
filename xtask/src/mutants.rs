//! `cargo xtask mutants [--shard K/N] [--firmware] [--timeout S] [--min-score PCT]`: mutation
//! testing with cargo-mutants (installed with `cargo install cargo-mutants --locked` when
//! missing).
//!
//! Without `--firmware` it mutates pfe-core and runs pfe-core's own tests (the crate users
//! depend on carries its own proof); with it, the firmware's codec and output
//! (`firmware/lms2xx/src/**` and `firmware/frame/src/**`) against the firmware's tests. `--shard
//! K/N` takes every N-th mutant from the K-th (round-robin), a sample of the whole set. Tests
//! are built at opt-level 3 (the Monte Carlo and property tests take minutes unoptimised per
//! mutant); the unit and integration tests run, not the doctests (examples, each compiled on
//! its own: 20 s a mutant more, and they can only catch more). Mutants judged equivalent are
//! excluded in `.cargo/mutants.toml`, each with its reason. Prints the caught / missed /
//! timeout / unviable counts and the score caught / (caught + missed + timeout), and lists the
//! missed mutants; with `--min-score`, fails when the score is below `PCT` %.

use anyhow::{bail, Context, Result};
use std::path::Path;
use std::process::Command;

use crate::util::{cargo, have, root};

/// Counts of one run, from cargo-mutants' `mutants.out/*.txt`.
#[derive(Debug, Default, PartialEq, Eq)]
struct Counts {
    caught: usize,
    missed: usize,
    timeout: usize,
    unviable: usize,
}

impl Counts {
    /// Caught over the mutants that built (unviable ones do not count).
    fn score(&self) -> f64 {
        let viable = self.caught + self.missed + self.timeout;
        if viable == 0 {
            0.0
        } else {
            self.caught as f64 / viable as f64
        }
    }
}

fn lines(dir: &Path, name: &str) -> Vec<String> {
    std::fs::read_to_string(dir.join(name))
        .unwrap_or_default()
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(str::to_string)
        .collect()
}

fn counts(out: &Path) -> Counts {
    Counts {
        caught: lines(out, "caught.txt").len(),
        missed: lines(out, "missed.txt").len(),
        timeout: lines(out, "timeout.txt").len(),
        unviable: lines(out, "unviable.txt").len(),
    }
}

/// The cargo-mutants arguments of one run.
fn mutants_args(firmware: bool, shard: Option<&str>, timeout: u64, out: &Path) -> Vec<String> {
    let mut a: Vec<String> = vec!["mutants".into(), "--no-shuffle".into()];
    if firmware {
        a.extend(
            [
                "-p",
                "lms2xx",
                "-p",
                "pfe-frame",
                "--file",
                "firmware/lms2xx/src/**",
                "--file",
                "firmware/frame/src/**",
            ]
            .map(String::from),
        );
    } else {
        a.extend(["-p", "pfe-core"].map(String::from));
    }
    if let Some(s) = shard {
        a.extend([
            "--shard".into(),
            s.into(),
            "--sharding".into(),
            "round-robin".into(),
        ]);
    }
    a.extend([
        "-C=--config=profile.test.opt-level=3".into(),
        "--cargo-test-arg=--lib".into(),
        "--cargo-test-arg=--tests".into(),
        "--timeout".into(),
        timeout.to_string(),
        "--output".into(),
        out.display().to_string(),
    ]);
    a
}

fn ensure_tool() -> Result<()> {
    if !have("cargo-mutants") {
        crate::util::run(Command::new("cargo").args(["install", "cargo-mutants", "--locked"]))?;
    }
    Ok(())
}

/// Entry point.
pub fn run(args: &[String]) -> Result<()> {
    let (mut shard, mut firmware, mut timeout) = (None, false, 120u64);
    let mut min_score: Option<f64> = None;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--shard" => {
                let s = it.next().context("--shard needs K/N")?;
                let ok = s
                    .split_once('/')
                    .and_then(|(k, n)| Some((k.parse::<u32>().ok()?, n.parse::<u32>().ok()?)))
                    .is_some_and(|(k, n)| k < n || (k == 0 && n == 0));
                if !ok {
                    bail!("--shard takes K/N with 0 ≤ K < N (cargo-mutants counts shards from 0), got {s:?}");
                }
                shard = Some(s.clone());
            }
            "--firmware" => firmware = true,
            "--timeout" => {
                timeout = it
                    .next()
                    .context("--timeout needs seconds")?
                    .parse()
                    .context("--timeout needs a whole number of seconds")?;
            }
            "--min-score" => {
                let v: f64 = it
                    .next()
                    .context("--min-score needs a percentage")?
                    .parse()
                    .context("--min-score needs a number (per cent)")?;
                if !(0.0..=100.0).contains(&v) {
                    bail!("--min-score takes a percentage in 0..=100, got {v}");
                }
                min_score = Some(v);
            }
            other => bail!("unknown argument {other:?} (usage: cargo xtask mutants [--shard K/N] [--firmware] [--timeout S] [--min-score PCT])"),
        }
    }
    ensure_tool()?;
    let out = root()
        .join("target/mutants")
        .join(if firmware { "firmware" } else { "pfe-core" });
    std::fs::create_dir_all(&out)?;
    let mut c = cargo();
    c.args(mutants_args(firmware, shard.as_deref(), timeout, &out));
    eprintln!("$ {c:?}");
    // cargo-mutants exits 2 when mutants are missed, 3 on timeouts: the counts decide here.
    let status = c.status().with_context(|| format!("cannot start {c:?}"))?;
    let dir = out.join("mutants.out");
    let n = counts(&dir);
    if n == Counts::default() {
        bail!("cargo mutants produced no outcomes ({status}); see its output above");
    }
    println!(
        "\nmutants of {} (command: cargo xtask mutants{}{}): {} caught, {} missed, {} timeout, {} unviable; score {:.1} %",
        if firmware { "lms2xx + pfe_frame" } else { "pfe-core" },
        if firmware { " --firmware" } else { "" },
        shard.as_deref().map(|s| format!(" --shard {s}")).unwrap_or_default(),
        n.caught,
        n.missed,
        n.timeout,
        n.unviable,
        100.0 * n.score()
    );
    for m in lines(&dir, "missed.txt") {
        println!("  missed: {m}");
    }
    for m in lines(&dir, "timeout.txt") {
        println!("  timeout: {m}");
    }
    match min_score {
        Some(min) if 100.0 * n.score() < min => bail!(
            "mutation score {:.1} % is below {min} %: add tests for the missed mutants above, or \
             exclude an equivalent one in .cargo/mutants.toml with the reason",
            100.0 * n.score()
        ),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::{counts, mutants_args, Counts};
    use std::path::Path;

    #[test]
    fn counts_come_from_the_outcome_lists_and_score_ignores_unviable() {
        let dir = std::env::temp_dir().join(format!("xtask-mutants-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("caught.txt"), "a\nb\nc\n").unwrap();
        std::fs::write(dir.join("missed.txt"), "d\n").unwrap();
        std::fs::write(dir.join("unviable.txt"), "e\nf\n").unwrap();
        let n = counts(&dir);
        std::fs::remove_dir_all(&dir).ok();
        assert_eq!(
            n,
            Counts {
                caught: 3,
                missed: 1,
                timeout: 0,
                unviable: 2
            }
        );
        assert!((n.score() - 0.75).abs() < 1e-12);
    }

    #[test]
    fn the_firmware_run_is_limited_to_the_codec_and_output() {
        let a = mutants_args(true, Some("1/25"), 60, Path::new("/o")).join(" ");
        assert!(
            a.contains(
                "-p lms2xx -p pfe-frame --file firmware/lms2xx/src/** --file firmware/frame/src/**"
            ),
            "{a}"
        );
        assert!(a.contains("--shard 1/25 --sharding round-robin"), "{a}");
        assert!(
            a.contains("--cargo-test-arg=--lib --cargo-test-arg=--tests"),
            "{a}"
        );
        let a = mutants_args(false, None, 60, Path::new("/o")).join(" ");
        assert!(
            a.contains("-p pfe-core") && !a.contains("--shard") && !a.contains("--file"),
            "{a}"
        );
    }
}
