//! `pfe_extractor_init` sets an extractor up by zeroing the caller's memory in place (no
//! 31 KiB temporary on the stack). That is `Extractor::new()` only while every byte
//! `Extractor::new()` defines is zero, which is also what puts a `static` extractor in .bss.
//! This checks it the way the compiler sees it: a static of `Extractor::new()` lands in .bss.

// Test helpers: a failure to run a tool or read a file fails the test.
#![allow(clippy::expect_used, clippy::panic, clippy::indexing_slicing)]
#![allow(unsafe_code)] // `#[no_mangle]`: a symbol name to look for

use std::process::Command;

use pfe_core::Extractor;
use pfe_testkit::skip::{skip, Need};

/// The extractor of the C API's capacities, as `pfe_extractor_init` leaves it (`mut`: an
/// immutable static goes to .rodata whatever its bytes; never accessed).
#[used]
#[no_mangle]
static mut PFE_CAPI_FRESH_EXTRACTOR: Extractor<
    { pfe_capi::PFE_MAX_READINGS },
    { pfe_capi::PFE_MAX_FEATURES },
> = Extractor::new();

#[test]
fn a_new_extractor_is_all_zero_bytes() {
    let exe = std::env::current_exe().expect("test binary");
    let Ok(out) = Command::new("nm").arg(&exe).output() else {
        skip(
            "pfe-capi in_place a_new_extractor_is_all_zero_bytes",
            "no nm (binutils)",
            Need::InCi,
        );
        return;
    };
    let symbols = String::from_utf8_lossy(&out.stdout);
    let line = symbols
        .lines()
        .find(|l| l.ends_with(" PFE_CAPI_FRESH_EXTRACTOR"))
        .expect("the static is in the test binary");
    // nm's type letter: B/b for .bss; D/d (.data) or R/r (.rodata) when a byte is not zero.
    let kind = line.split_whitespace().nth(1).unwrap_or("?");
    assert!(
        kind.eq_ignore_ascii_case("b"),
        "Extractor::new() is no longer all zero bytes (nm: {line}): pfe_extractor_init must \
         write it rather than zero the memory"
    );
}
