//! End to end, the async path: `pfe-qemu-async` (lms2xx's `AsyncDriver` on the UART0 receive
//! interrupt, a timer-0 delay and a `WFI` executor) and the blocking `pfe-qemu` run under QEMU
//! (mps2-an386) against the same emulated LMS200 scan sequence; their frames must agree scan by
//! scan (features bit for bit, and the extraction's header fields) and both must equal
//! pfe-core run on the host on the values the emulator sent.
//!
//! Skipped (with a message) when `qemu-system-arm` or the `thumbv7em-none-eabihf` target is
//! missing; `cargo xtask test` installs both, so CI runs it.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: a panic fails the test

use host_tests::qemu;

use std::path::{Path, PathBuf};
use std::time::Duration;

use firmware::app::ConfigChoice;
use pfe_frame::{Frame, Header, Report, ScanHeader, ScanStatus};

const TEST: &str = "e2e_qemu_async";

/// Both firmwares, built as shipped (the blocking one where `e2e_qemu` builds it).
fn firmwares() -> Option<(PathBuf, PathBuf)> {
    let blocking = qemu::test_firmware(TEST, "pfe-qemu", "e2e-firmware")?;
    let asynch = qemu::test_firmware_with(TEST, "pfe-qemu-async", &["async"], "e2e-firmware")?;
    Some((blocking, asynch))
}

/// Runs `elf` for `scans` scans from `seed`; checks the run ended well and returns the
/// session with its scan frames (in order).
fn run(elf: &Path, scans: u32, config: &str, seed: u64) -> (qemu::Session, Vec<Frame>) {
    let s = qemu::session(elf, scans, config, seed, Duration::from_secs(240)).unwrap();
    let name = elf.file_name().unwrap().to_string_lossy().into_owned();
    assert_eq!(
        s.run.code,
        Some(0),
        "{name} exit code; stderr:\n{}",
        s.run.stderr
    );
    assert!(s.bad_frames.is_empty(), "{name}: {:?}", s.bad_frames);
    assert!(
        s.frames
            .iter()
            .any(|f| f.header == Header::Report(Report::Done { scans })),
        "{name}: no Done report"
    );
    let frames: Vec<Frame> = s
        .frames
        .iter()
        .filter(|f| f.scan().is_some())
        .cloned()
        .collect();
    assert_eq!(frames.len(), scans as usize, "{name}: scan frames");
    let stack = s.frames.iter().find_map(|f| match f.header {
        Header::Report(Report::Stack { used, size }) => Some((used, size)),
        _ => None,
    });
    let (used, size) = stack.expect("a stack report");
    assert!(used > 512 && used < size, "{name}: stack {used} of {size}");
    // For the log: the time stamps are the one thing the two may differ in.
    let times: Vec<u32> = frames
        .iter()
        .filter_map(|f| f.scan())
        .map(|h| h.time_ms)
        .collect();
    eprintln!("{name} ({config}): stack {used} of {size} B, scan times {times:?} ms");
    (s, frames)
}

/// What the extraction put in a scan header: its sequence number, counts and status (not the
/// time stamp, nor the link counters, which count the init's exchanges and so depend on the
/// race between the firmware's baud switch and the emulator sampling the pty's speed).
fn extraction(h: &ScanHeader) -> (u32, u16, u16, u16, u16, ScanStatus) {
    (
        h.seq,
        h.valid,
        h.segments,
        h.dropped,
        h.n_features,
        h.status,
    )
}

fn check(
    blocking: &Path,
    asynch: &Path,
    scans: u32,
    config: &str,
    choice: ConfigChoice,
    seed: u64,
) {
    let (bs, bf) = run(blocking, scans, config, seed);
    let (as_, af) = run(asynch, scans, config, seed);
    let mut features = 0;
    for (k, (b, a)) in bf.iter().zip(&af).enumerate() {
        // The same scan was served to both: the same simulated room, undamaged.
        let (sent_b, sent_a) = (&bs.emulator.scans[k], &as_.emulator.scans[k]);
        assert!(!sent_b.damaged && !sent_a.damaged, "scan {k}: damaged");
        assert_eq!(
            sent_b.words, sent_a.words,
            "scan {k}: the emulator served different scans"
        );

        let (hb, ha) = (b.scan().unwrap(), a.scan().unwrap());
        assert_eq!(ha.seq, k as u32);
        assert_eq!(ha.status, ScanStatus::Ok);
        assert_eq!(extraction(hb), extraction(ha), "scan {k}: headers");
        for h in [hb, ha] {
            assert_eq!(h.counters.crc_dropped, 0, "scan {k}");
            assert_eq!(h.counters.reinits, 0, "scan {k}");
        }

        // Bit for bit, against each other and against pfe-core on the host.
        let host = qemu::host_features(&sent_a.words, choice).unwrap();
        assert_eq!(
            b.features.len(),
            a.features.len(),
            "scan {k}: feature count"
        );
        assert_eq!(
            host.len(),
            a.features.len(),
            "scan {k}: feature count vs host"
        );
        for (i, ((fb, fa), fh)) in b
            .features
            .iter()
            .zip(a.features.iter())
            .zip(&host)
            .enumerate()
        {
            assert_eq!(
                qemu::ulps_apart(fb, fa),
                None,
                "scan {k} feature {i}: blocking {fb:?} vs async {fa:?}"
            );
            // Debug prints each f32 so that it reads back to the same bits (and tells -0 from 0,
            // which ulps_apart counts as equal).
            assert_eq!(format!("{fb:?}"), format!("{fa:?}"), "scan {k} feature {i}");
            assert_eq!(
                qemu::ulps_apart(fh, fa),
                None,
                "scan {k} feature {i}: host {fh:?} vs async {fa:?}"
            );
        }
        features += a.features.len();
    }
    assert!(
        features >= scans as usize * 3,
        "simulated rooms have walls: {features}"
    );
}

#[test]
fn async_firmware_frames_equal_blocking_firmware() {
    let Some((blocking, asynch)) = firmwares() else {
        return;
    };
    // Without the pose step, as the embassy firmware runs: with it, the async firmware's
    // executor on top of the pose step's stack outgrows the 48 KiB RAM budget (QEMU exits 1
    // at the overflow; the blocking firmware's high-water mark is 25.3 of 25.7 KB with it,
    // 7.6 KB without). The pose step on the blocking path is checked by e2e_qemu.
    check(
        &blocking,
        &asynch,
        8,
        "default-nopose",
        ConfigChoice::Default,
        300,
    );
    check(
        &blocking,
        &asynch,
        4,
        "paper-nopose",
        ConfigChoice::Paper,
        400,
    );
}
