//! pfe's host-side end-to-end and integration tests, benches and examples (in `tests/`,
//! `benches/`, `examples/`), and what they share:
//!
//! | module | what |
//! | --- | --- |
//! | [`qemu`] | the firmware under QEMU against the emulated LMS200 serving simulated scenes |
//! | [`soak`] | long runs with damage through emulator, driver, pfe-core and frames (in-process, pty, QEMU) |
//!
//! The host side's crates, by role: `pfe-cli` (the `pfe` command line), `pfe-formats`
//! (recordings in, JSON out), `pfe-eval` (simulator, baselines, evaluation), `lms200-emulator`
//! (the device emulator) and `pfe-testkit` (helpers for xtask and the tests).

#![forbid(unsafe_code)]

pub mod qemu;
pub mod soak;
