//! The Arm build: the static library for a Cortex-M4F (`thumbv7em-none-eabihf`, release),
//! linked by Debian's `arm-none-eabi-gcc` into the smallest C program that uses it
//! (`tests/c/arm_main.c`) and into the C example; reports `arm-none-eabi-size`, with and
//! without the `scrutiny` feature. Checks that the extractor is a static in .bss, that no
//! panic code is linked (nothing in the library can panic, so the linker drops the handler),
//! and that no function's stack frame is anywhere near an extractor's size (it is set up in
//! place).
//! Skipped loudly without `arm-none-eabi-gcc` or the Rust target.

// Test helpers: a failure to run a tool or read a file fails the test.
#![allow(clippy::expect_used, clippy::panic, clippy::indexing_slicing)]

use std::path::{Path, PathBuf};
use std::process::Command;

use pfe_testkit::skip::{skip, Need};

const TEST: &str = "pfe-capi arm the_library_links_for_a_cortex_m4f";
const TARGET: &str = "thumbv7em-none-eabihf";
/// The Cortex-M4F with its single-precision FPU, hard-float calls: the Rust target's ABI.
const CPU: [&str; 4] = [
    "-mcpu=cortex-m4",
    "-mthumb",
    "-mfloat-abi=hard",
    "-mfpu=fpv4-sp-d16",
];

fn here() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// True when `cmd --version` runs.
fn runs(cmd: &str) -> bool {
    Command::new(cmd)
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success())
}

/// True when the Rust standard library for `TARGET` is installed.
fn rust_target_installed() -> bool {
    Command::new("rustc")
        .args(["--print", "sysroot"])
        .output()
        .ok()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .is_some_and(|root| Path::new(&root).join("lib/rustlib").join(TARGET).exists())
}

/// Builds the library for `TARGET` (release) into `dir`, with `features` flags; its path.
fn build_library(dir: &Path, features: &[&str]) -> PathBuf {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_string());
    let status = Command::new(cargo)
        .args(["build", "-p", "pfe-capi", "--release", "--target", TARGET])
        .args(features)
        .arg("--target-dir")
        .arg(dir)
        .status()
        .expect("run cargo");
    assert!(status.success(), "cargo build for {TARGET} failed");
    dir.join(TARGET).join("release/libpfe_capi.a")
}

/// Links `source` with `lib` for the Cortex-M4F into `elf`.
fn link(source: &Path, lib: &Path, elf: &Path) {
    let out = Command::new("arm-none-eabi-gcc")
        .args(CPU)
        .args([
            "--specs=nosys.specs",
            "-std=c11",
            "-Wall",
            "-Wextra",
            "-Werror",
            "-O2",
        ])
        .args([
            "-ffunction-sections",
            "-fdata-sections",
            "-Wl,--gc-sections",
        ])
        // newlib's crt objects carry no .note.GNU-stack: ld warns; nothing runs from the stack.
        .arg("-Wl,-z,noexecstack")
        .arg("-I")
        .arg(here().join("include"))
        .arg(source)
        .arg(lib)
        .arg("-lm")
        .arg("-o")
        .arg(elf)
        .output()
        .expect("run arm-none-eabi-gcc");
    assert!(
        out.status.success(),
        "arm-none-eabi-gcc {}: {}",
        source.display(),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// `arm-none-eabi-size`'s text, data and bss of `elf`.
fn size(elf: &Path) -> [u64; 3] {
    let out = Command::new("arm-none-eabi-size")
        .arg(elf)
        .output()
        .expect("run arm-none-eabi-size");
    let text = String::from_utf8_lossy(&out.stdout);
    let row: Vec<u64> = text
        .lines()
        .nth(1)
        .unwrap_or_default()
        .split_whitespace()
        .take(3)
        .filter_map(|v| v.parse().ok())
        .collect();
    [0, 1, 2].map(|i| row.get(i).copied().unwrap_or(0))
}

/// The output of `arm-none-eabi-<tool> args… elf`.
fn tool(name: &str, args: &[&str], elf: &Path) -> String {
    let out = Command::new(format!("arm-none-eabi-{name}"))
        .args(args)
        .arg(elf)
        .output()
        .expect("run binutils");
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The largest stack frame (`sub sp, #n`) in `elf`'s code, bytes.
fn largest_frame(elf: &Path) -> u64 {
    tool("objdump", &["-d", "--no-show-raw-insn"], elf)
        .lines()
        .filter(|l| l.contains("sub") && l.contains("sp, sp, #") || l.contains("sub\tsp, #"))
        .filter_map(|l| l.rsplit('#').next())
        .filter_map(|n| n.split_whitespace().next())
        .filter_map(|n| n.parse::<u64>().ok())
        .max()
        .unwrap_or(0)
}

#[test]
fn the_library_links_for_a_cortex_m4f() {
    if !runs("arm-none-eabi-gcc") {
        skip(
            TEST,
            "no arm-none-eabi-gcc (apt-get install gcc-arm-none-eabi)",
            Need::InCi,
        );
        return;
    }
    if !rust_target_installed() {
        skip(
            TEST,
            "no Rust target thumbv7em-none-eabihf (rustup target add thumbv7em-none-eabihf)",
            Need::InCi,
        );
        return;
    }
    let tmp = Path::new(env!("CARGO_TARGET_TMPDIR")).join("arm");
    let empty = tmp.join("empty.c");
    std::fs::create_dir_all(&tmp).expect("temporary directory");
    std::fs::write(&empty, "int main(void) { return 0; }\n").expect("write empty.c");
    // What newlib's start-up and an empty main cost, to tell the library's share.
    let lib = build_library(&tmp.join("target"), &[]);
    link(&empty, &lib, &tmp.join("empty.elf"));
    let base = size(&tmp.join("empty.elf"));

    let mut report = Vec::new();
    for (name, features) in [
        ("default (scrutiny)", &[][..]),
        ("--no-default-features", &["--no-default-features"][..]),
    ] {
        let lib = match features.is_empty() {
            true => lib.clone(),
            false => build_library(&tmp.join("target-lean"), features),
        };
        let elf = tmp.join(format!("arm_main{}.elf", features.len()));
        link(&here().join("tests/c/arm_main.c"), &lib, &elf);
        let [text, data, bss] = size(&elf);
        let symbols = tool("nm", &["-C", "-S"], &elf);
        let extractor = symbols
            .lines()
            .find(|l| l.ends_with(" extractor"))
            .expect("the static extractor");
        assert!(
            extractor.contains(" b ") || extractor.contains(" B "),
            "the extractor is not in .bss: {extractor}"
        );
        let panics: Vec<&str> = symbols
            .lines()
            .filter(|l| l.contains("panic") || l.contains("rust_begin_unwind"))
            .collect();
        assert!(panics.is_empty(), "panic code linked: {panics:?}");
        let frame = largest_frame(&elf);
        // pfe-core's own are about 1 KiB (a scratch array); an extractor built on the stack
        // would be 31 KiB.
        assert!(frame < 4096, "a stack frame of {frame} bytes");
        report.push(format!(
            "{name}: text {text} data {data} bss {bss} (library and extractor: text {} data {} \
             bss {}; largest stack frame {frame} B)",
            text - base[0],
            data - base[1],
            bss - base[2],
        ));
    }
    // The C example links as well (with newlib's printf and maths).
    link(
        &here().join("examples/static_extractor.c"),
        &lib,
        &tmp.join("example.elf"),
    );
    let [text, data, bss] = size(&tmp.join("example.elf"));
    report.push(format!(
        "examples/static_extractor.c: text {text} data {data} bss {bss}"
    ));
    report.push(format!(
        "empty main (newlib start-up): text {} data {} bss {}",
        base[0], base[1], base[2]
    ));
    for line in &report {
        eprintln!("arm-none-eabi-size, cortex-m4f: {line}");
    }
}
