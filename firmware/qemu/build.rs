//! Linker setup for the Cortex-M build (QEMU memory map, `link.x`, `defmt.x`) and the bench
//! scans (`PFE_BENCH_SCANS`: a file of back-to-back B0 telegrams, written by
//! `cargo xtask bench-mcu`; empty when unset).

use std::path::PathBuf;

fn main() {
    let out = PathBuf::from(std::env::var_os("OUT_DIR").unwrap_or_default());
    println!("cargo:rerun-if-changed=memory-qemu.x");
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=../../memory.x");
    println!("cargo:rerun-if-env-changed=PFE_BENCH_SCANS");
    println!("cargo:rerun-if-env-changed=PFE_BENCH_RESET_AT");
    let scans = match std::env::var_os("PFE_BENCH_SCANS") {
        Some(p) => {
            println!("cargo:rerun-if-changed={}", PathBuf::from(&p).display());
            std::fs::read(&p).unwrap_or_else(|e| {
                println!("cargo:warning=cannot read PFE_BENCH_SCANS {p:?}: {e}");
                Vec::new()
            })
        }
        None => Vec::new(),
    };
    if let Err(e) = std::fs::write(out.join("bench_scans.bin"), scans) {
        println!("cargo:warning=cannot write bench_scans.bin: {e}");
    }
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("none") {
        // A memory.x in OUT_DIR, first on the search path, whatever the current directory.
        let mem = include_str!("memory-qemu.x");
        // `pfe-memory.x` for the workspace root's memory.x (read when the linker runs
        // there), `memory.x` for a link from anywhere else.
        for name in ["pfe-memory.x", "memory.x"] {
            if let Err(e) = std::fs::write(out.join(name), mem) {
                println!("cargo:warning=cannot write {name}: {e}");
            }
        }
        println!("cargo:rustc-link-search={}", out.display());
        println!("cargo:rustc-link-arg=-Tlink.x");
        println!("cargo:rustc-link-arg=-Tdefmt.x");
    }
}
