//! Memory map (QEMU mps2-an386, generous RAM: this build is about panics, not budgets) and
//! cortex-m-rt's `link.x`, whatever directory cargo runs from.
use std::path::PathBuf;

fn main() {
    let out = PathBuf::from(std::env::var_os("OUT_DIR").unwrap_or_default());
    println!("cargo:rerun-if-changed=build.rs");
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("none") {
        let mem = "MEMORY\n{\n  FLASH : ORIGIN = 0x00000000, LENGTH = 4M\n  RAM : ORIGIN = 0x20000000, LENGTH = 256K\n}\n";
        if let Err(e) = std::fs::write(out.join("memory.x"), mem) {
            println!("cargo:warning=cannot write memory.x: {e}");
        }
        println!("cargo:rustc-link-search={}", out.display());
        println!("cargo:rustc-link-arg=-Tlink.x");
    }
}
