//! `cargo xtask no-panic [--overflow-checks]`: proves at link time that the firmware's scan
//! path and LMS driver have no panic path.
//!
//! Builds `firmware/no-panic` (UART bytes → LMS decoder → reply → pfe-core with both
//! configurations → output frames; and the LMS driver's init sequence, baud probe, re-init,
//! `poll`, `stop` and `reset_device` over a register-backed UART, delay, clock and
//! configuration, so nothing about replies, timing or settings is known) in release for thumbv7em-none-eabihf. Its panic handler
//! calls a symbol defined nowhere, so the link fails while any panic (bounds check, unwrap,
//! division by zero, …) is still reachable after optimisation. On failure it rebuilds with
//! `--features probe` (a panic handler that links), disassembles, and lists every surviving
//! call into the panic machinery with its inlining chain (llvm-addr2line), so the report says
//! which function and line to fix. `--overflow-checks` also turns arithmetic overflow checks on
//! (stricter than the shipped release profile).

use anyhow::{bail, Context, Result};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::util::{cargo, ensure_flip_link, ensure_target, root};

const TARGET: &str = "thumbv7em-none-eabihf";
const SYMBOL: &str = "__pfe_panic_path_survived";

fn target_dir(overflow: bool) -> PathBuf {
    let base = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join("target"));
    base.join(if overflow {
        "no-panic-overflow"
    } else {
        "no-panic"
    })
}

fn build(probe: bool, overflow: bool) -> Result<(bool, String)> {
    let mut c = cargo();
    c.args(["build", "--release", "--target", TARGET, "--manifest-path"])
        .arg(root().join("firmware/no-panic/Cargo.toml"))
        .env("CARGO_TARGET_DIR", target_dir(overflow))
        .env_remove("RUSTFLAGS");
    if probe {
        c.args(["--features", "probe"]);
    }
    if overflow {
        c.env("CARGO_PROFILE_RELEASE_OVERFLOW_CHECKS", "true");
    }
    eprintln!("$ {c:?}");
    let out = c.output().context("cannot run cargo")?;
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    Ok((out.status.success(), stderr))
}

fn elf(overflow: bool) -> PathBuf {
    target_dir(overflow).join(format!("{TARGET}/release/pfe-no-panic"))
}

/// An LLVM tool: rustup's llvm-tools component first, then PATH.
fn llvm_tool(name: &str) -> Option<PathBuf> {
    let sysroot = Command::new("rustc")
        .args(["--print", "sysroot"])
        .output()
        .ok()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())?;
    let host = Command::new("rustc")
        .arg("-vV")
        .output()
        .ok()
        .and_then(|o| {
            String::from_utf8_lossy(&o.stdout)
                .lines()
                .find_map(|l| l.strip_prefix("host: ").map(str::to_string))
        })?;
    let p = Path::new(&sysroot).join(format!("lib/rustlib/{host}/bin/{name}"));
    if p.exists() {
        return Some(p);
    }
    crate::util::have(name).then(|| PathBuf::from(name))
}

/// A surviving call into the panic machinery.
struct Site {
    addr: u64,
    function: String,
    callee: String,
    chain: Vec<String>,
}

/// Disassembles `elf` and finds the calls and branches from outside `core` into functions
/// that (transitively, within `core`) end in `panic_fmt`.
fn panic_sites(elf: &Path) -> Result<Vec<Site>> {
    let objdump = llvm_tool("llvm-objdump")
        .context("llvm-objdump is missing: `rustup component add llvm-tools`")?;
    let out = Command::new(&objdump)
        .args(["-d", "-C", "--no-show-raw-insn"])
        .arg(elf)
        .output()
        .context("cannot run llvm-objdump")?;
    let text = String::from_utf8_lossy(&out.stdout);
    // function -> [(address, callee)]
    let mut calls: BTreeMap<String, Vec<(u64, String)>> = BTreeMap::new();
    let mut current = String::new();
    for line in text.lines() {
        if let Some(name) = line
            .split_once(" <")
            .filter(|(a, _)| u64::from_str_radix(a, 16).is_ok() && !a.starts_with(' '))
            .and_then(|(_, r)| r.strip_suffix(">:"))
        {
            current = name.to_string();
            calls.entry(current.clone()).or_default();
            continue;
        }
        let Some((addr, rest)) = line.trim_start().split_once(':') else {
            continue;
        };
        let Ok(addr) = u64::from_str_radix(addr.trim(), 16) else {
            continue;
        };
        let mut words = rest.split_whitespace();
        let Some(op) = words.next() else { continue };
        if !op.starts_with('b') || op.starts_with("bic") || op.starts_with("bfi") {
            continue;
        }
        if let Some((_, callee)) = rest.split_once(" <") {
            let callee = callee.split('>').next().unwrap_or("");
            let callee = callee.split('+').next().unwrap_or(callee).to_string();
            if callee != current {
                calls
                    .entry(current.clone())
                    .or_default()
                    .push((addr, callee));
            }
        }
    }
    let mut panicky: BTreeSet<String> = calls
        .keys()
        .filter(|f| f.contains("panic_fmt") || f.contains("rust_begin_unwind"))
        .cloned()
        .collect();
    loop {
        let more: Vec<String> = calls
            .iter()
            .filter(|(f, cs)| {
                f.starts_with("core::")
                    && !panicky.contains(*f)
                    && cs.iter().any(|(_, c)| panicky.contains(c))
            })
            .map(|(f, _)| f.clone())
            .collect();
        if more.is_empty() {
            break;
        }
        panicky.extend(more);
    }
    let addr2line = ["llvm-addr2line", "llvm-addr2line-14"]
        .into_iter()
        .find_map(llvm_tool);
    let mut sites = Vec::new();
    for (f, cs) in &calls {
        if panicky.contains(f) || f.starts_with("core::") {
            continue;
        }
        for (addr, callee) in cs.iter().filter(|(_, c)| panicky.contains(c)) {
            let chain = match &addr2line {
                Some(tool) => Command::new(tool)
                    .args(["-f", "-i", "-C", "-e"])
                    .arg(elf)
                    .arg(format!("{addr:#x}"))
                    .output()
                    .map(|o| {
                        let s = String::from_utf8_lossy(&o.stdout).into_owned();
                        let lines: Vec<&str> = s.lines().collect();
                        lines
                            .chunks(2)
                            .filter(|p| p.get(1).is_some_and(|l| !l.starts_with("/rustc/")))
                            .map(|p| {
                                let loc = p.get(1).copied().unwrap_or("");
                                let loc = loc
                                    .strip_prefix(&format!("{}/", root().display()))
                                    .unwrap_or(loc);
                                format!("{} ({loc})", tidy(p.first().copied().unwrap_or("")))
                            })
                            .collect()
                    })
                    .unwrap_or_default(),
                None => Vec::new(),
            };
            sites.push(Site {
                addr: *addr,
                function: f.clone(),
                callee: callee.clone(),
                chain,
            });
        }
    }
    Ok(sites)
}

/// Rust legacy-mangling escapes and hashes out of a symbol, for reading.
fn tidy(name: &str) -> String {
    let s = name
        .replace("$LT$", "<")
        .replace("$GT$", ">")
        .replace("$C$", ",")
        .replace("$u20$", " ")
        .replace("$RF$", "&")
        .replace("..", "::");
    match s.rfind("::h") {
        Some(i) if s.len() - i == 19 => s[..i].to_string(),
        _ => s,
    }
}

fn size(elf: &Path) -> String {
    llvm_tool("llvm-size")
        .and_then(|t| Command::new(t).arg(elf).output().ok())
        .map(|o| String::from_utf8_lossy(&o.stdout).into_owned())
        .unwrap_or_default()
}

/// Entry point.
pub fn run(args: &[String]) -> Result<()> {
    let overflow = args.iter().any(|a| a == "--overflow-checks");
    if let Some(other) = args.iter().find(|a| *a != "--overflow-checks") {
        bail!("unknown argument {other:?} (usage: cargo xtask no-panic [--overflow-checks])");
    }
    ensure_target()?;
    ensure_flip_link()?;
    let (ok, stderr) = build(false, overflow)?;
    if ok {
        let elf = elf(overflow);
        let sz = size(&elf);
        // The proof is only worth something if the scan path is really in the binary.
        let text: u64 = sz
            .lines()
            .nth(1)
            .and_then(|l| l.split_whitespace().next())
            .and_then(|t| t.parse().ok())
            .unwrap_or(0);
        println!("{sz}");
        if text != 0 && text < 16 * 1024 {
            bail!("the no-panic firmware is only {text} bytes of code: the scan path was optimised away");
        }
        println!(
            "no-panic: PASS — {} links with a panic handler that references the undefined `{SYMBOL}`: \
             no panic path survives on the scan path (decoder → reply → pfe-core paper+default → output frames) \
             nor in the LMS driver (init, baud probe, re-init, poll, stop, reset){}",
            elf.display(),
            if overflow { ", overflow checks on" } else { "" }
        );
        return Ok(());
    }
    if !stderr.contains(SYMBOL) {
        eprintln!("{stderr}");
        bail!("the no-panic firmware failed to build (not because of a panic path)");
    }
    eprintln!("no-panic: the link failed on `{SYMBOL}`: locating the surviving panic paths…");
    let (ok, stderr) = build(true, overflow)?;
    if !ok {
        eprintln!("{stderr}");
        bail!("the probe build failed");
    }
    let sites = panic_sites(&elf(overflow))?;
    println!("surviving panic call sites ({}):", sites.len());
    for s in &sites {
        println!(
            "  {:#08x} in {} → {}",
            s.addr,
            tidy(&s.function),
            tidy(&s.callee)
        );
        for c in &s.chain {
            println!("      {c}");
        }
    }
    bail!(
        "no-panic: FAIL — {} panic call site(s) survive optimisation (see above)",
        sites.len()
    )
}
