//! Linker setup for the STM32F411: this package's `memory.x`, `link.x`, `defmt.x`.

use std::path::PathBuf;

fn main() {
    println!("cargo:rerun-if-changed=memory.x");
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=../../memory.x");
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return;
    }
    let out = PathBuf::from(std::env::var_os("OUT_DIR").unwrap_or_default());
    // `pfe-memory.x` for the workspace root's memory.x (read when the linker runs there),
    // `memory.x` for a link from anywhere else.
    for name in ["pfe-memory.x", "memory.x"] {
        if let Err(e) = std::fs::write(out.join(name), include_str!("memory.x")) {
            println!("cargo:warning=cannot write {name}: {e}");
        }
    }
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rustc-link-arg=-Tlink.x");
    println!("cargo:rustc-link-arg=-Tdefmt.x");
}
