//! `cargo xtask size`: flash and RAM of both firmware binaries (release, opt-level s, pfe-core 3) and the
//! stack high-water mark measured under QEMU (cortex-m-rt `paint-stack`, reported by the
//! firmware in its output frames after 20 scans from the emulated LMS200).
//!
//! Budgets (exit non-zero when broken), for the firmware with everything on (pfe-core's
//! `scrutiny`: the host's extraction): flash (vector table + text + rodata + data) ≤ 96 KiB;
//! static RAM (data + bss + uninit) + stack high-water mark ≤ 48 KiB, with room for every
//! LMS200 variant (401 values). Refreshes the `size` section of docs/PERFORMANCE.md.
//!
//! Also runs `cargo xtask stack` (its own `-Z emit-stack-sizes` build of pfe-qemu, about a
//! minute) and prints the static worst-case stack bound beside the painted mark; a bound below
//! the mark, or a `.text` that differs from the measured binary's, breaks the budgets.

use std::path::Path;
use std::process::Command;

use anyhow::{bail, Context, Result};

use crate::fw::{build_fw, demo_host, target_dir, write_section, FIRMWARE_OPT_LEVEL};
use crate::util;

const FLASH_BUDGET: u64 = 96 * 1024;
const RAM_BUDGET: u64 = 48 * 1024;
/// Initialised statics, bytes: the extractor and the application start as all zeros (.bss),
/// so only small driver and HAL statics belong here.
const DATA_LIMIT: u64 = 1024;

/// Section sizes of an ELF: (flash, static RAM, .data, a description).
pub(crate) fn sizes(tool: &Path, elf: &Path) -> Result<(u64, u64, u64, String)> {
    let out = Command::new(tool)
        .arg("-A")
        .arg(elf)
        .output()
        .with_context(|| format!("running {}", tool.display()))?;
    if !out.status.success() {
        bail!("llvm-size failed on {}", elf.display());
    }
    let text = String::from_utf8_lossy(&out.stdout);
    let (mut flash, mut ram, mut data) = (0u64, 0u64, 0u64);
    let mut detail = Vec::new();
    for line in text.lines() {
        let mut it = line.split_whitespace();
        let (Some(name), Some(size)) = (it.next(), it.next()) else {
            continue;
        };
        let Ok(size) = size.parse::<u64>() else {
            continue;
        };
        match name {
            ".vector_table" | ".text" | ".rodata" => flash += size,
            ".data" => {
                flash += size;
                ram += size;
                data += size;
            }
            ".bss" | ".uninit" => ram += size,
            _ => continue,
        }
        detail.push(format!("{name} {size}"));
    }
    Ok((flash, ram, data, detail.join(", ")))
}

/// The sizes of the functions of `elf`, sorted (`llvm-nm`): equal for two builds of the same
/// code whatever the order the linker put them in.
fn function_sizes(elf: &Path) -> Result<Vec<u64>> {
    let nm = util::llvm_tool("llvm-nm")?;
    let out = Command::new(&nm)
        .args(["-S", "--defined-only"])
        .arg(elf)
        .output()
        .with_context(|| format!("running {}", nm.display()))?;
    if !out.status.success() {
        bail!("llvm-nm failed on {}", elf.display());
    }
    let mut sizes: Vec<u64> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| {
            let mut it = l.split_whitespace();
            let (_, size, kind) = (it.next()?, it.next()?, it.next()?);
            matches!(kind, "t" | "T").then(|| u64::from_str_radix(size, 16).ok())?
        })
        .collect();
    sizes.sort_unstable();
    Ok(sizes)
}

/// Size of the section `name` of `elf` (0 when absent).
fn section_size(tool: &Path, elf: &Path, name: &str) -> Result<u64> {
    let out = Command::new(tool)
        .arg("-A")
        .arg(elf)
        .output()
        .with_context(|| format!("running {}", tool.display()))?;
    Ok(String::from_utf8_lossy(&out.stdout)
        .lines()
        .find_map(|l| {
            let mut it = l.split_whitespace();
            (it.next() == Some(name)).then(|| it.next()?.parse().ok())?
        })
        .unwrap_or(0))
}

/// Runs the command.
pub fn run(args: &[String]) -> Result<()> {
    if !args.is_empty() {
        bail!("usage: cargo xtask size");
    }
    util::ensure_target()?;
    util::ensure_flip_link()?;
    util::ensure_apt("qemu-system-arm", "qemu-system-arm")?;
    let tool = util::llvm_tool("llvm-size")?;
    let base = target_dir().join("size");
    // Separate builds: the board's PAC turns on cortex-m-rt's `device` feature, which the
    // QEMU binary must not get.
    let qemu = build_fw("pfe-qemu", &[], &[], &base.join("qemu"))?;
    let mut c = util::cargo();
    c.args([
        "build",
        "--release",
        "-p",
        "firmware-board",
        "--bin",
        "pfe-board",
    ])
    .args(["--target", "thumbv7em-none-eabihf"])
    .env("CARGO_TARGET_DIR", base.join("board"))
    .env("CARGO_PROFILE_RELEASE_OPT_LEVEL", FIRMWARE_OPT_LEVEL)
    .env("DEFMT_LOG", "info")
    .env_remove("RUSTFLAGS");
    util::run(&mut c)?;
    let board = base
        .join("board")
        .join("thumbv7em-none-eabihf")
        .join("release")
        .join("pfe-board");
    // Stack high-water marks from 20-scan runs against the emulator: with the pose step (what
    // pfe-qemu runs) and without it (what the board runs: its binary has no pose step).
    let painted = |config: &str, file: &str| -> Result<(u64, String)> {
        let summary = base.join(file);
        demo_host(&[
            "demo".as_ref(),
            "--elf".as_ref(),
            qemu.as_os_str(),
            "--scans".as_ref(),
            "20".as_ref(),
            "--config".as_ref(),
            config.as_ref(),
            "--summary".as_ref(),
            summary.as_os_str(),
        ])?;
        let text = std::fs::read_to_string(&summary).context("reading the run summary")?;
        let stack = text
            .lines()
            .find_map(|l| l.strip_prefix("stack_used="))
            .and_then(|v| v.trim().parse::<u64>().ok())
            .filter(|v| *v > 0)
            .context("no stack high-water mark in the run summary")?;
        Ok((stack, text))
    };
    let (stack, text) = painted("default", "stack.txt")?;
    let (board_stack, _) = painted("default-nopose", "stack-nopose.txt")?;

    let field = |k: &str| {
        text.lines()
            .find_map(|l| l.strip_prefix(k))
            .map(|v| v.trim().to_string())
            .unwrap_or_default()
    };
    let (equal, compared) = (field("equal="), field("compared="));
    let mut broken = Vec::new();
    // The static bound of the same firmware (its own -Z emit-stack-sizes build, about a
    // minute), beside the painted mark: a bound below the mark would be a bug in the walk.
    let (bound_elf, bound) = crate::stack::refresh()?;
    let (text_measured, text_bound) = (
        section_size(&tool, &qemu, ".text")?,
        section_size(&tool, &bound_elf, ".text")?,
    );
    // The two builds may lay the same functions out in another order (their symbols are
    // mangled differently), which moves alignment padding: the same binary when every
    // function has the same size.
    let same_code =
        text_measured == text_bound || function_sizes(&qemu)? == function_sizes(&bound_elf)?;
    let mut md = format!(
        "Release profile with `opt-level = \"{FIRMWARE_OPT_LEVEL}\"` (pfe-core at 3; LTO, 1 codegen unit), \
         `App<401, 48>` (extractor for every LMS200 variant) in a static, all zeros at start (.bss). Flash = vector table + text + rodata + data; \
         static RAM = data + bss + uninit. Stack: painted-stack high-water mark after 20 scans \
         under QEMU against the emulated LMS200 (same driver, app and extractor code on the \
         board; the board's HAL glue differs): pfe-qemu's with the pose step, the board's \
         without it (`default-nopose`: the board binary has no pose step).\n\n\
         | binary | flash (bytes) | static RAM (bytes) | stack high-water (bytes) | RAM + stack | sections |\n\
         |---|---:|---:|---:|---:|---|\n"
    );
    for (name, elf, stack) in [
        ("pfe-qemu (mps2-an386)", &qemu, stack),
        ("pfe-board (STM32F411)", &board, board_stack),
    ] {
        let (flash, ram, data, detail) = sizes(&tool, elf)?;
        md.push_str(&format!(
            "| {name} | {flash} | {ram} | {stack} | {} | {detail} |\n",
            ram + stack
        ));
        println!(
            "{name}: flash {flash} B ({:.1} KiB of {}), static RAM {ram} B + stack {stack} B = {:.1} KiB of {}",
            flash as f64 / 1024.0,
            FLASH_BUDGET / 1024,
            (ram + stack) as f64 / 1024.0,
            RAM_BUDGET / 1024
        );
        // The flash budget is the board binary's (issue 42); pfe-qemu also carries the pose
        // step, which the board does not run (docs/POSE.md), and QEMU's flash is 4 MiB.
        if flash > FLASH_BUDGET && name.starts_with("pfe-board") {
            broken.push(format!("{name}: flash {flash} > {FLASH_BUDGET}"));
        }
        if data > DATA_LIMIT {
            broken.push(format!(
                "{name}: .data {data} > {DATA_LIMIT} (a static App / Extractor that is not all \
                 zeros is copied from flash)"
            ));
        }
        if ram + stack > RAM_BUDGET {
            broken.push(format!(
                "{name}: RAM + stack {} > {RAM_BUDGET}",
                ram + stack
            ));
        }
    }
    println!(
        "pfe-qemu stack: painted high-water mark {stack} B, static worst-case bound {} B \
         ({} B main path, {} B with an interrupt, then a HardFault)",
        bound.total(),
        bound.main.total,
        bound.with_interrupt()
    );
    md.push_str(&format!(
        "\nStatic worst-case stack bound of pfe-qemu (`cargo xtask stack`, section below): {} B \
         ({} B on `main`'s path, {} B with an interrupt, then a HardFault on top), against the \
         painted high-water mark of {stack} B.\n",
        bound.total(),
        bound.main.total,
        bound.with_interrupt()
    ));
    if stack > bound.total() {
        broken.push(format!(
            "pfe-qemu: painted stack {stack} B above the static bound {} B (the walk missed a path)",
            bound.total()
        ));
    }
    if !same_code {
        broken.push(format!(
            "pfe-qemu: .text of the -Z emit-stack-sizes build ({text_bound} B) differs from the \
             measured binary's ({text_measured} B), and so do its functions' sizes: the static \
             bound is not of this binary"
        ));
    }
    md.push_str(&format!(
        "\nThe same run compares the features the firmware sent (Cortex-M4F, QEMU) with what \
         `pfe extract --format lms200` gives on the host (x86-64) on a capture of the same B0 \
         telegrams (pfe-formats' reader, the CLI's configuration, sweeps and grid): \
         {equal}/{compared} scans bit-identical (libm is pure software on both targets and \
         rustc does not contract f32 mul/add into FMA, so no ulp differences are expected).\n"
    ));
    md.push_str(&format!(
        "\nBudgets: flash of the board binary ≤ {FLASH_BUDGET} B (pfe-qemu also carries the pose \
         step, which the board does not run), static RAM + stack ≤ {RAM_BUDGET} B, and .data ≤ \
         {DATA_LIMIT} B (the extractor starts as zeros in .bss, not copied from flash): **{}**.\n",
        if broken.is_empty() { "met" } else { "BROKEN" }
    ));
    write_section(
        &util::root().join("docs").join("PERFORMANCE.md"),
        "size",
        &md,
    )?;
    if !broken.is_empty() {
        bail!("size budgets broken: {}", broken.join("; "));
    }
    Ok(())
}
