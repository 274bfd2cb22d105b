//! cargo-fuzz target: see `pfe_fuzz_harness::frame_decoder` for the input layout and the invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    pfe_fuzz_harness::frame_decoder(data);
});
