//! cargo-fuzz target: see `pfe_fuzz_harness::readers` for the input layout and the invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    pfe_fuzz_harness::readers(data);
});
