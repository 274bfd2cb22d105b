//! End to end: the pfe-qemu firmware under QEMU (mps2-an386) initialises the emulated LMS200
//! over UART0, extracts features from simulated scans and sends them on UART1; the features
//! must be bit-identical to what `pfe extract --format lms200` gives on the host on the same
//! B0 telegrams (`host_features`), everything on: the checks for real scans and the 0.5°
//! scans' two sweeps.
//!
//! Skipped (with a message) when `qemu-system-arm` or the `thumbv7em-none-eabihf` target is
//! missing; `cargo xtask test` installs both, so CI runs it.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: a panic fails the test

use host_tests::qemu;

use std::path::PathBuf;
use std::time::Duration;

use firmware::app::ConfigChoice;
use pfe_frame::{Header, Report, ScanStatus};

fn firmware_elf() -> Option<PathBuf> {
    qemu::test_firmware("e2e_qemu", "pfe-qemu", "e2e-firmware")
}

fn check(elf: &std::path::Path, scans: u32, config: &str, choice: ConfigChoice, seed: u64) {
    let s = qemu::session(elf, scans, config, seed, Duration::from_secs(240)).unwrap();
    assert_eq!(
        s.run.code,
        Some(0),
        "firmware exit code; stderr:\n{}",
        s.run.stderr
    );
    assert!(s.bad_frames.is_empty(), "{:?}", s.bad_frames);
    let scan_frames: Vec<_> = s.frames.iter().filter(|f| f.scan().is_some()).collect();
    assert_eq!(scan_frames.len(), scans as usize);
    let mut features = 0;
    for (k, f) in scan_frames.iter().enumerate() {
        let h = f.scan().unwrap();
        assert_eq!(h.seq, k as u32);
        assert_eq!(h.status, ScanStatus::Ok);
        assert_eq!(h.counters.crc_dropped, 0);
        assert_eq!(h.counters.reinits, 0);
        let sent = &s.emulator.scans[k];
        assert!(!sent.damaged);
        let host = qemu::host_features(&sent.words, choice).unwrap();
        assert_eq!(host.len(), f.features.len(), "scan {k}: feature count");
        for (i, (a, b)) in host.iter().zip(f.features.iter()).enumerate() {
            assert_eq!(
                qemu::ulps_apart(a, b),
                None,
                "scan {k} feature {i}: host {a:?} vs firmware {b:?}"
            );
        }
        features += f.features.len();
    }
    assert!(
        features >= scans as usize * 3,
        "simulated rooms have walls: {features}"
    );
    let stack = s.frames.iter().find_map(|f| match f.header {
        Header::Report(Report::Stack { used, size }) => Some((used, size)),
        _ => None,
    });
    let (used, size) = stack.expect("a stack report");
    assert!(used > 512 && used < size, "stack {used} of {size}");
    assert!(s
        .frames
        .iter()
        .any(|f| f.header == Header::Report(Report::Done { scans })));
}

#[test]
fn firmware_features_equal_host_pfe_core() {
    let Some(elf) = firmware_elf() else { return };
    check(&elf, 8, "default", ConfigChoice::Default, 100);
    check(&elf, 4, "paper", ConfigChoice::Paper, 200);
}
