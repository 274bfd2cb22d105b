//! cargo-fuzz target: see `pfe_fuzz_harness::lms_driver_async` for the checks (the input
//! layout is `lms_driver`'s).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    pfe_fuzz_harness::lms_driver_async(data);
});
