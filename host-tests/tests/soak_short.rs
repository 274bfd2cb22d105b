//! A short soak (the example `soak` with 5 % damage and a device reset every 100 scans) in
//! every `cargo test`: the account must balance in-process and over a pseudo-terminal.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

use host_tests::soak;

#[test]
fn short_soak_in_process_balances() {
    let args = soak::Args {
        scans: 400,
        seed: 7,
        damage: 0.05,
        pty: false,
        qemu: false,
    };
    assert!(soak::inproc(&args).unwrap(), "account does not balance");
}

#[test]
fn short_soak_over_a_pty_balances() {
    let args = soak::Args {
        scans: 60,
        seed: 8,
        damage: 0.05,
        pty: true,
        qemu: false,
    };
    assert!(soak::pty(&args).unwrap(), "account does not balance");
}
