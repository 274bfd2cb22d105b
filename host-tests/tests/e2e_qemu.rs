//! End to end: the pfe-qemu firmware under QEMU (mps2-an386) initialises the emulated LMS200
//! over UART0, extracts features from simulated scans and sends them on UART1 with each scan's
//! pose; the features must be bit-identical to what `pfe extract --format lms200` gives on the
//! host on the same B0 telegrams (`host_features`), everything on: the checks for real scans
//! and the 0.5° scans' two sweeps; and the poses to pfe-pose's odometry on the host (on a
//! simulated drive around a room, where they also follow the true motion).
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
        assert_eq!(f.pose, None, "scan {k}: the pose step is off");
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

/// The bits of every number of a pose block.
fn pose_bits(b: &pfe_frame::PoseBlock) -> Vec<u32> {
    let mut v = Vec::new();
    for c in [b.rel, b.pose] {
        v.extend([c.x, c.y, c.theta].map(f32::to_bits));
        v.extend(c.cov.iter().flatten().map(|x| x.to_bits()));
    }
    if let pfe_frame::PoseStatus::Degenerate { direction } = b.status {
        v.extend(direction.map(f32::to_bits));
    }
    v
}

/// The board computes the pose of every scan it receives; with the pose step it takes longer
/// than a scan period (docs/PERFORMANCE.md, `bench-mcu-pose`), so it misses telegrams: each
/// scan frame is matched to the telegram whose features it carries, and the host runs the same
/// odometry over the telegrams the board processed, in order.
#[test]
fn firmware_pose_equals_host_odometry_on_a_drive() {
    use pfe_pose::{FeatureOdometry, Pose};
    let Some(elf) = firmware_elf() else { return };
    let scans = 32u32;
    let s = qemu::session_drive(&elf, scans, "default", 5, Duration::from_secs(400)).unwrap();
    assert_eq!(
        s.run.code,
        Some(0),
        "firmware exit code; stderr:\n{}",
        s.run.stderr
    );
    assert!(s.bad_frames.is_empty(), "{:?}", s.bad_frames);
    let board: Vec<_> = s.frames.iter().filter(|f| f.scan().is_some()).collect();
    assert_eq!(board.len(), scans as usize);
    // The telegram each scan frame came from (the drive's scans are all distinct).
    let mut used: Vec<usize> = Vec::new();
    let mut next = 0usize;
    assert!(
        s.emulator.scans.len() <= 4 * scans as usize,
        "the drive started over: {} telegrams",
        s.emulator.scans.len()
    );
    for (k, b) in board.iter().enumerate() {
        let j = (next..s.emulator.scans.len())
            .find(|&j| {
                let sent = &s.emulator.scans[j];
                !sent.damaged && {
                    let h = qemu::host_features(&sent.words, ConfigChoice::Default).unwrap();
                    h.len() == b.features.len()
                        && h.iter()
                            .zip(b.features.iter())
                            .all(|(x, y)| qemu::ulps_apart(x, y).is_none())
                }
            })
            .unwrap_or_else(|| panic!("scan {k}: its features match no telegram from {next} on"));
        used.push(j);
        next = j + 1;
    }
    let words: Vec<&[u16]> = used
        .iter()
        .map(|&j| &s.emulator.scans[j].words[..])
        .collect();
    let host = qemu::host_frames(&words, ConfigChoice::Default).unwrap();
    // pfe odometry's call on the host's features, independently of the App.
    let mut odo = Box::new(FeatureOdometry::new_default());
    let t0 = pfe_eval::scene::drive::pose(used[0]);
    let truth0 = Pose::new(t0[0] as f32, t0[1] as f32, t0[2] as f32);
    let mut ok = 0;
    for (k, (b, h)) in board.iter().zip(&host).enumerate() {
        assert_eq!(b.scan().unwrap().seq, k as u32);
        let (bp, hp) = (b.pose.expect("a pose block"), h.pose.expect("a pose block"));
        assert_eq!(
            pose_bits(&bp),
            pose_bits(&hp),
            "scan {k}: board {bp:?} host {hp:?}"
        );
        assert_eq!(bp.status, hp.status, "scan {k}");
        let step = firmware::app::pose_block(&odo.update_features(&h.features, None));
        assert_eq!(
            pose_bits(&bp),
            pose_bits(&step),
            "scan {k}: odometry {step:?}"
        );
        ok += usize::from(bp.status == pfe_frame::PoseStatus::Ok);
        let t = pfe_eval::scene::drive::pose(used[k]);
        let t = truth0
            .inverse()
            .compose(&Pose::new(t[0] as f32, t[1] as f32, t[2] as f32));
        let err = (bp.pose.x - t.x).hypot(bp.pose.y - t.y);
        assert!(err < 100.0, "scan {k}: {err} mm from the true pose");
    }
    assert!(ok >= scans as usize * 9 / 10, "{ok} of {scans} ok");
    eprintln!(
        "drive: {ok}/{scans} ok; the board processed telegrams {used:?} of {}",
        s.emulator.scans.len()
    );
}

#[test]
fn firmware_features_equal_host_pfe_core() {
    let Some(elf) = firmware_elf() else { return };
    // The extraction alone (pose step off): the board keeps up with every telegram, and no
    // telegram may be lost. With the pose step on it cannot (docs/POSE.md, "On the board"):
    // `firmware_pose_equals_host_odometry_on_a_drive` matches frames to telegrams instead.
    check(&elf, 8, "default-nopose", ConfigChoice::Default, 100);
    check(&elf, 4, "paper-nopose", ConfigChoice::Paper, 200);
}
