//! cargo-fuzz target: see `pfe_fuzz_harness::lms_driver` for the input layout and the checks.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    pfe_fuzz_harness::lms_driver(data);
});
