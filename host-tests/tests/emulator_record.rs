//! `pfe record` (firmware driver over a real tty) against the emulator on a pseudo-terminal:
//! the capture holds exactly the scans the emulator sent.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use firmware::lms::frame::{Decoder, Event, MAX_TELEGRAM};
use firmware::lms::reply::{parse_reply, Reply, ReplyOptions};
use host_tests::device::emulator::serve::{serve_on, Pty};
use host_tests::device::emulator::{Emulator, EmulatorConfig, RunLimits, SourceKind};

#[test]
fn record_over_pty_captures_sent_scans() {
    let dir = std::env::temp_dir().join(format!("pfe-record-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let link = dir.join("lms");
    let out = dir.join("capture.lms");
    let mut pty = Pty::open(&link).unwrap();
    let cfg = EmulatorConfig {
        source: SourceKind::Tagged,
        ..Default::default()
    };
    let stop = Arc::new(AtomicBool::new(false));
    let limits = RunLimits {
        max_time: Some(Duration::from_secs(60)),
        stop: Some(stop.clone()),
        ..Default::default()
    };
    let emu = std::thread::spawn(move || {
        serve_on(&mut pty, Emulator::from_config(cfg), limits).map(|r| (r, pty))
    });
    let args: Vec<String> = [
        "--port",
        link.to_str().unwrap(),
        "--baud",
        "38400",
        "--scans",
        "4",
        "-o",
        out.to_str().unwrap(),
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let res = host_tests::cli::record::cli(&args);
    stop.store(true, Ordering::Relaxed);
    let (report, _pty) = emu.join().unwrap().unwrap();
    res.unwrap();

    let bytes = std::fs::read(&out).unwrap();
    let mut dec = Decoder::<MAX_TELEGRAM>::new();
    let mut rest = &bytes[..];
    let mut scans = Vec::new();
    loop {
        let (u, ev) = dec.feed(rest);
        rest = &rest[u..];
        match ev {
            Some(Event::Telegram(t)) => {
                if let Ok(p) = parse_reply(t.payload(), ReplyOptions::default()) {
                    if let Reply::Values(v) = p.reply {
                        scans.push(v.words().collect::<Vec<_>>());
                    }
                }
            }
            Some(_) => {}
            None => break,
        }
    }
    assert!(scans.len() >= 4, "{} scans in the capture", scans.len());
    let sent: Vec<_> = report.scans.iter().map(|s| s.words.clone()).collect();
    for s in &scans {
        assert!(sent.contains(s), "captured scan not sent by the emulator");
    }
    assert_eq!(
        report.scans.last().map(|s| s.unit),
        Some(firmware::lms::Unit::Mm)
    );
    let _ = std::fs::remove_dir_all(&dir);
}
