//! End to end through the user's tools: the emulated LMS200 on a pty → the QEMU firmware
//! between two serial lines (`cargo xtask run-qemu`'s `RunQemu`) → `pfe listen` on its output
//! pty gives, scan for scan, exactly the features `pfe extract --format lms200` (no option:
//! its defaults) gives on a capture of the telegrams the emulator sent, and exactly the pose
//! `pfe odometry` gives on the capture of the telegrams the firmware received. The board runs the
//! host's extraction: the checks for real scans, small objects, and the interleaved sweeps of
//! 0.5° (2) and 0.25° (4) scans aligned. Scenes: the emulator's room, real 0.5° scans of the
//! shared CARMEN logs (skipped loudly without `../shared/data`), the synthetic scan of ranges
//! 1000 + i mm (two circles on the host), and simulated scenes at 0.25° with the sweeps out of
//! place.
//!
//! Without qemu-system-arm or the thumbv7em target it prints `SKIPPED: …` and passes, except
//! under `CI=true`, where it fails.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)] // test code: a panic fails the test

use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use lms200_emulator::serve::{serve_on, Pty};
use lms200_emulator::{Emulator, EmulatorConfig, RangeSource, RunLimits};
use lms2xx::codec::types::Unit;
use pfe_testkit::qemu;
use pfe_testkit::run_qemu::RunQemu;
use serde_json::Value;

const SCANS: u32 = 12;

/// Held by each run of the firmware: one QEMU at a time. The emulator sends in real time; run
/// side by side on a small machine (CI's two cores), the firmwares fell behind it, their
/// receive rings filled and telegrams were dropped (csail's scans with the pose step).
static ONE_QEMU: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn skip(why: &str) -> Option<PathBuf> {
    let msg = format!("SKIPPED: e2e_listen: {why}");
    assert!(
        std::env::var("CI").as_deref() != Ok("true"),
        "{msg} (CI=true)"
    );
    eprintln!("{msg}");
    None
}

/// The pfe-qemu firmware under test: `PFE_E2E_FIRMWARE` (a pfe-qemu ELF built elsewhere, to
/// check these tests against another build, such as the one-sweep firmware before the board
/// ran the host's extraction), else this tree's, built here.
fn firmware_elf() -> Option<PathBuf> {
    if let Some(elf) = std::env::var_os("PFE_E2E_FIRMWARE") {
        return Some(PathBuf::from(elf));
    }
    if !qemu::have("qemu-system-arm") {
        return skip("qemu-system-arm not found");
    }
    if !qemu::have_target() {
        return skip("thumbv7em-none-eabihf target not installed");
    }
    let dir = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| qemu::root().join("target"))
        .join("e2e-firmware");
    Some(
        qemu::build_firmware(
            "pfe-qemu",
            &[],
            &[("CARGO_PROFILE_RELEASE_OPT_LEVEL", qemu::FIRMWARE_OPT_LEVEL)],
            &dir,
        )
        .unwrap(),
    )
}

fn json_lines(out: &[u8]) -> Vec<Value> {
    String::from_utf8_lossy(out)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// Serves `scans` in order, cycling (NaN where a scan's length is not the variant's).
struct Given {
    scans: Vec<Vec<f32>>,
    next: usize,
}

impl RangeSource for Given {
    fn next_scan(&mut self, n: usize, _start_deg: f32, _step_deg: f32) -> Vec<f32> {
        let r = match self.scans.get(self.next % self.scans.len().max(1)) {
            Some(r) if r.len() == n => r.clone(),
            _ => vec![f32::NAN; n],
        };
        self.next += 1;
        r
    }
}

/// What one run compared: the scans `pfe listen` received, as `pfe extract` gave them.
struct Compared {
    /// `pfe extract`'s lines for the received scans, in order.
    extracted: Vec<Value>,
}

/// Runs the firmware (`args` after the scan count: config, baud, slow, slow_every, field,
/// resolution) against an emulator serving `source` (its room when `None`), listens to
/// `SCANS` scans and asserts each equals `pfe extract --format lms200` on the capture of the
/// telegrams sent; `None` when skipped.
fn listen_vs_extract(
    tag: &str,
    source: Option<Box<dyn RangeSource>>,
    args: &[&str],
) -> Option<Compared> {
    let elf = firmware_elf()?;
    // A test that failed while holding it poisons it; the others still run one at a time.
    let _one = ONE_QEMU.lock().unwrap_or_else(|e| e.into_inner());
    let tmp = std::env::temp_dir().join(format!("pfe-e2e-listen-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    let (lms, out) = (tmp.join("lms200"), tmp.join("features"));

    let mut pty = Pty::open(&lms).unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let limits = RunLimits {
        stop: Some(stop.clone()),
        max_time: Some(Duration::from_secs(300)),
        ..RunLimits::default()
    };
    let emu = match source {
        Some(s) => Emulator::new(EmulatorConfig::default(), s),
        None => Emulator::from_config(EmulatorConfig::default()),
    };
    let server = std::thread::spawn(move || serve_on(&mut pty, emu, limits));

    let mut fw = RunQemu::start_with(&elf, &lms, &out, SCANS, args).unwrap();
    let listen = Command::new(env!("CARGO_BIN_EXE_pfe"))
        .args([
            "listen",
            "--scans",
            &SCANS.to_string(),
            "--seconds",
            "240",
            "--input",
        ])
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let listened = listen.wait_with_output().unwrap();
    let code = fw.wait(Duration::from_secs(60)).unwrap();
    stop.store(true, Ordering::Relaxed);
    let report = server.join().unwrap().unwrap();
    drop(fw);
    assert_eq!(code, Some(0), "firmware exit code");
    assert!(
        listened.status.success(),
        "pfe listen: {}",
        String::from_utf8_lossy(&listened.stderr)
    );
    let got = json_lines(&listened.stdout);
    assert_eq!(got.len(), SCANS as usize, "scans received");

    // The capture: every B0 telegram the emulator sent, as bytes.
    let mut capture = Vec::new();
    for s in &report.scans {
        capture.extend(qemu::b0_telegram(&s.words, s.unit == Unit::Mm).unwrap());
    }
    let cap = tmp.join("capture.lms");
    std::fs::write(&cap, &capture).unwrap();
    // The host's extraction as a user runs it: the format's defaults, nothing told.
    let extracted = Command::new(env!("CARGO_BIN_EXE_pfe"))
        .args(["extract", "--format", "lms200"])
        .args(args.first().map(|c| ["--config", c]).unwrap_or_default())
        .arg(&cap)
        .output()
        .unwrap();
    assert!(
        extracted.status.success(),
        "pfe extract: {}",
        String::from_utf8_lossy(&extracted.stderr)
    );
    let want = json_lines(&extracted.stdout);

    // Each scan received is one of the telegrams sent, in order: the first telegram after the
    // previous scan's whose `pfe extract` features are the scan's (the scenes served differ,
    // so no other telegram has them). Telegrams sent before the driver streamed, or cut by
    // a re-initialisation, are no scans to the firmware.
    let mut compared = Vec::new();
    let mut used = Vec::new();
    let mut next = 0;
    for g in &got {
        let k = (next..want.len())
            .find(|&k| want[k]["features"] == g["features"])
            .unwrap_or_else(|| {
                let near =
                    (g["counters"]["telegrams"].as_u64().unwrap() as usize).min(want.len() - 1);
                panic!(
                    "scan {} (telegrams {}): no telegram from {next} on gives its features\n\
                     firmware: {}\nhost, telegram {near}: {}",
                    g["seq"], g["counters"]["telegrams"], g["features"], want[near]["features"]
                )
            });
        next = k + 1;
        assert_eq!(g["status"], want[k]["status"]);
        compared.push(want[k].clone());
        used.push(k);
    }
    assert!(
        got.len() >= SCANS as usize && compared.len() == got.len(),
        "every scan received compared"
    );
    same_pose_as_odometry(tag, &tmp, &report, &got, &used, args);
    let _ = std::fs::remove_dir_all(&tmp);
    Some(Compared {
        extracted: compared,
    })
}

/// The pose each received scan's frame carries equals `pfe odometry`'s (the same
/// configuration as the firmware's, `args[0]`) on the telegrams the firmware processed
/// (`used`: indices into the emulator's `report`), from the firmware's first scan (seq 0,
/// where its odometry starts).
fn same_pose_as_odometry(
    tag: &str,
    tmp: &std::path::Path,
    report: &lms200_emulator::EmulatorReport,
    got: &[Value],
    used: &[usize],
    args: &[&str],
) {
    let seq0 = got[0]["seq"].as_u64().unwrap();
    let consecutive = got
        .iter()
        .enumerate()
        .all(|(k, g)| g["seq"].as_u64() == Some(seq0 + k as u64));
    assert!(consecutive, "{tag}: pfe listen missed a frame");
    if seq0 != 0 {
        eprintln!(
            "SKIPPED (pose part): e2e_listen {tag}: pfe listen joined at seq {seq0}; the odometry before it is unknown"
        );
        return;
    }
    let mut received = Vec::new();
    for &j in used {
        let s = &report.scans[j];
        received.extend(qemu::b0_telegram(&s.words, s.unit == Unit::Mm).unwrap());
    }
    let cap = tmp.join("received.lms");
    std::fs::write(&cap, &received).unwrap();
    let odometry = Command::new(env!("CARGO_BIN_EXE_pfe"))
        .args(["odometry", "--format", "lms200"])
        .args(args.first().map(|c| ["--config", c]).unwrap_or_default())
        .arg(&cap)
        .output()
        .unwrap();
    assert!(
        odometry.status.success(),
        "pfe odometry: {}",
        String::from_utf8_lossy(&odometry.stderr)
    );
    let poses = json_lines(&odometry.stdout);
    assert_eq!(poses.len(), got.len());
    for (g, host) in got.iter().zip(&poses) {
        let board = &g["odometry"];
        assert!(
            board.is_object(),
            "{tag} scan {}: no pose from pfe listen",
            g["seq"]
        );
        for key in ["rel", "pose", "status", "direction", "reason"] {
            // Equal JSON numbers: f32 values printed in their shortest form, so equal bits.
            assert_eq!(
                board.get(key),
                host.get(key),
                "{tag} scan {}: {key}",
                g["seq"]
            );
        }
    }
}

/// The features of kind `kind` in one `pfe extract` line.
fn count(line: &Value, kind: &str) -> usize {
    line["features"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|f| f["kind"] == kind)
        .count()
}

#[test]
fn listen_gives_what_extract_gives_on_the_same_telegrams() {
    let Some(c) = listen_vs_extract("room", None, &["default"]) else {
        return;
    };
    assert!(
        c.extracted.iter().all(|l| count(l, "line") >= 3),
        "a room has walls"
    );
}

#[test]
fn the_paper_configuration_too() {
    listen_vs_extract("paper", None, &["paper"]);
}

/// The first scans of a CARMEN log of 0.5° scans (361 beams; a 360-beam log's last beam as no
/// return), as mm.
fn carmen_half_degree(log: &str, wanted: usize) -> Option<Vec<Vec<f32>>> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/carmen")
        .join(log);
    if !path.is_file() {
        pfe_testkit::skip::skip(
            "e2e_listen::real_half_degree_scans",
            &format!(
                "the shared CARMEN log {} is absent (../shared/data beside the repository)",
                path.display()
            ),
            pfe_testkit::skip::Need::InCi,
        );
        return None;
    }
    let input = pfe_formats::open_for(&path, pfe_formats::Format::Carmen, |r| r).unwrap();
    let scans: Vec<Vec<f32>> = pfe_formats::scans(pfe_formats::Format::Carmen, input)
        // Every 7th: scans that differ, from the start of the log.
        .step_by(7)
        .take(wanted)
        .map(|r| {
            let mut ranges = r.unwrap().ranges_mm;
            ranges.resize(361, f32::NAN);
            ranges
        })
        .collect();
    assert_eq!(scans.len(), wanted, "{log}: too few scans");
    Some(scans)
}

#[test]
fn real_half_degree_scans() {
    for log in ["csail-corrected.log.gz", "freiburg-079-corrected.log.gz"] {
        let Some(scans) = carmen_half_degree(log, SCANS as usize + 4) else {
            return;
        };
        let source = Given { scans, next: 0 };
        let Some(c) = listen_vs_extract(&log[..4], Some(Box::new(source)), &["default"]) else {
            return;
        };
        let features: usize = c
            .extracted
            .iter()
            .map(|l| l["features"].as_array().unwrap().len())
            .sum();
        assert!(features >= SCANS as usize * 3, "{log}: {features} features");
    }
}

#[test]
fn ranges_1000_plus_i_mm_are_two_circles_on_both() {
    // The synthetic scan of issue 39: 361 ranges of 1000 + i mm.
    let scan: Vec<f32> = (0..361).map(|i| 1000.0 + i as f32).collect();
    let source = Given {
        scans: vec![scan],
        next: 0,
    };
    let Some(c) = listen_vs_extract("ramp", Some(Box::new(source)), &["default"]) else {
        return;
    };
    for l in &c.extracted {
        assert_eq!(count(l, "circle"), 2, "{l}");
        assert_eq!(count(l, "line"), 0, "{l}");
    }
}

#[test]
fn quarter_degree_scans_with_their_sweeps_out_of_place() {
    use pfe_eval::scene::{Resolution, Scenario, SceneKind};
    // Mixed scenes at 0.25°, the scanner moving (each sweep 8 mm and 6 mrad after the one
    // before): the 100° the LMS200 scans at 0.25°, beams 160..=560 of the simulator's 180°
    // (160 a multiple of 4: every beam keeps its sweep).
    let scans: Vec<Vec<f32>> = (0..SCANS as u64 + 4)
        .map(|seed| {
            let mut sc = Scenario::new(SceneKind::Mixed, 40 + seed).with_motion(600.0, 0.45);
            sc.resolution = Resolution::Quarter;
            sc.simulate().ranges_mm[160..561].to_vec()
        })
        .collect();
    let source = Given { scans, next: 0 };
    let Some(c) = listen_vs_extract(
        "quarter",
        Some(Box::new(source)),
        &["default", "38400", "0", "1", "100", "25"],
    ) else {
        return;
    };
    // 401 beams: features reach past beam 360.
    let last = c
        .extracted
        .iter()
        .flat_map(|l| l["features"].as_array().unwrap().clone())
        .filter_map(|f| f["last"].as_u64())
        .max();
    assert!(
        last.is_some_and(|b| b > 360 && b <= 400),
        "last beam {last:?}"
    );
}
