//! Small helpers for xtask and the tests, with no heavy dependencies:
//!
//! | module | what |
//! | --- | --- |
//! | [`skip`] | reporting tests that cannot run (listed by `cargo xtask test`, failures in CI) |
//! | [`qemu`] | building the firmware and running it under QEMU, reading its frames |
//! | [`run_qemu`] | the QEMU firmware between two serial lines (`cargo xtask run-qemu`) |

#![forbid(unsafe_code)]

pub mod qemu;
pub mod run_qemu;
pub mod skip;
