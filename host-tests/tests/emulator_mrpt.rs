//! Conformance: MRPT's `CSickLaserSerial` (Debian libmrpt-hwdrivers-dev), an independent LMS200
//! client, initialises against the emulator on a pseudo-terminal and reads scans equal to what
//! the emulator sent. Skips with a message when g++ or the MRPT headers are missing, unless
//! `PFE_CONFORMANCE_REQUIRED` is set (as `cargo xtask conformance` does).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: a panic fails the test

use std::path::{Path, PathBuf};
use std::process::Command;

use lms200_emulator::serve::Pty;
use lms200_emulator::{Emulator, EmulatorConfig, RangeSource, TaggedSource};
use lms2xx::codec::types::{Baud, MeasuringMode, Unit};

mod common;

use common::PtyServer;

const SCANS: usize = 12;

/// Every 9th beam from beam 5 on returns nothing (NaN: the emulator sends the no-return code).
fn no_return(i: usize) -> bool {
    i >= 5 && i % 9 == 5
}

/// [`TaggedSource`] with the beams of [`no_return`] dropped.
#[derive(Default)]
struct TaggedWithGaps(TaggedSource);

impl RangeSource for TaggedWithGaps {
    fn next_scan(&mut self, n: usize, start_deg: f32, step_deg: f32) -> Vec<f32> {
        let mut r = self.0.next_scan(n, start_deg, step_deg);
        for (i, v) in r.iter_mut().enumerate() {
            if no_return(i) {
                *v = f32::NAN;
            }
        }
        r
    }
}

fn missing(what: &str) {
    if std::env::var_os("PFE_CONFORMANCE_REQUIRED").is_some() {
        panic!("MRPT conformance needs {what}");
    }
    pfe_testkit::skip::skip(
        "emulator_mrpt",
        &format!("MRPT conformance needs {what} (apt-get install g++ libmrpt-hwdrivers-dev)"),
        pfe_testkit::skip::Need::InCi,
    );
}

fn compile(dir: &Path) -> Option<PathBuf> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../xtask/conformance/mrpt_client.cpp");
    let inc = Path::new("/usr/include/mrpt");
    if !inc.join("hwdrivers").exists() {
        missing("the MRPT headers under /usr/include/mrpt");
        return None;
    }
    let mut cmd = Command::new("g++");
    cmd.args(["-std=c++17", "-O1", "-w"]);
    for e in std::fs::read_dir(inc).ok()?.flatten() {
        let p = e.path().join("include");
        if p.exists() {
            cmd.arg(format!("-I{}", p.display()));
        }
    }
    let bin = dir.join("mrpt_client");
    cmd.arg(&src).arg("-o").arg(&bin);
    for l in [
        "hwdrivers",
        "obs",
        "comms",
        "core",
        "system",
        "io",
        "serialization",
        "config",
        "poses",
        "math",
        "containers",
        "rtti",
    ] {
        cmd.arg(format!("-lmrpt-{l}"));
    }
    match cmd.output() {
        Ok(o) if o.status.success() => Some(bin),
        Ok(o) => {
            missing(&format!(
                "a working MRPT build: {}",
                String::from_utf8_lossy(&o.stderr)
            ));
            None
        }
        Err(_) => {
            missing("g++");
            None
        }
    }
}

#[test]
fn mrpt_reads_exactly_the_emulated_scans() {
    let dir = std::env::temp_dir().join(format!("pfe-mrpt-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let Some(bin) = compile(&dir) else { return };
    let link = dir.join("lms");
    let pty = Pty::open(&link).unwrap();
    let cfg = EmulatorConfig::default();
    let emu = PtyServer::start(pty, Emulator::new(cfg, Box::new(TaggedWithGaps::default())));
    let out = Command::new(&bin)
        .arg(&link)
        .arg(SCANS.to_string())
        .output()
        .unwrap();
    let (report, _pty) = emu.stop();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "mrpt_client failed: {}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    // MRPT set mm and the 32 m measuring mode through installation mode + 77, at 38400.
    assert!(report.commands.contains(&0x77), "{:02X?}", report.commands);
    let last = report.scans.last().unwrap();
    assert_eq!((last.unit, last.mode), (Unit::Mm, MeasuringMode(6)));
    // At 38400: MRPT left its port at 38400 (the client reads the pty's termios), and the
    // emulator garbles every byte sent while host and device speeds differ, so undamaged
    // scans (checked below) mean the device was at 38400 too.
    let baud = stdout
        .lines()
        .find_map(|l| l.strip_prefix("BAUD "))
        .expect("the client prints the port's speed");
    assert_eq!(
        baud.trim(),
        Baud::B38400.bps().to_string(),
        "MRPT's line speed"
    );

    let mut matched = 0;
    for line in stdout.lines().filter(|l| l.starts_with("SCAN ")) {
        let mut it = line.split_whitespace().skip(1);
        let n: usize = it.next().unwrap().parse().unwrap();
        let vals: Vec<(f32, bool)> = it
            .map(|t| {
                let (r, v) = t.split_once(':').unwrap();
                (r.parse().unwrap(), v == "1")
            })
            .collect();
        assert_eq!(vals.len(), n);
        assert_eq!(n, 361);
        let mm: Vec<u16> = vals
            .iter()
            .map(|(r, _)| (r * 1000.0).round() as u16)
            .collect();
        let tag = TaggedSource::tag_of(&mm).expect("tag in the first two ranges");
        let sent = report
            .scans
            .iter()
            .find(|s| s.seq == tag)
            .expect("MRPT scan was sent");
        assert!(!sent.damaged);
        let mut gaps = 0;
        for (i, ((r, valid), &w)) in vals.iter().zip(&sent.words).enumerate() {
            let code = w & 0x7FFF;
            if no_return(i) {
                // The no-return code must come out invalid, whatever range MRPT puts there.
                assert!(
                    code > MeasuringMode(6).max_valid(),
                    "beam {i}: sent {code:#x}"
                );
                assert!(
                    !*valid,
                    "scan {tag} beam {i}: no return ({code:#x}) read as valid {r} m"
                );
                gaps += 1;
            } else {
                assert!(
                    code <= MeasuringMode(6).max_valid() && code > 0,
                    "beam {i}: {code}"
                );
                assert!(
                    *valid,
                    "scan {tag} beam {i}: {code} mm sent, MRPT says invalid"
                );
                // Unit quantum: 1 mm.
                assert!(
                    (r * 1000.0 - f32::from(code)).abs() <= 1.0,
                    "scan {tag} beam {i}: {r} m vs {code} mm"
                );
            }
        }
        assert_eq!(gaps, (0..361).filter(|&i| no_return(i)).count());
        matched += 1;
    }
    eprintln!(
        "MRPT conformance: {matched} scans matched; emulator sent {}, commands {:02X?}",
        report.scans.len(),
        report.commands
    );
    assert_eq!(matched, SCANS);
    let _ = std::fs::remove_dir_all(&dir);
}
