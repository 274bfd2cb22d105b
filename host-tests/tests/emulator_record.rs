//! `pfe record` (firmware driver over a real tty) against the emulator on a pseudo-terminal:
//! the capture holds exactly the scans the emulator sent: each one once, in the order sent.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: a panic fails the test

mod common;

use common::{arg, PtyServer};
use lms200_emulator::serve::Pty;
use lms200_emulator::{Emulator, EmulatorConfig, SourceKind};
use lms2xx::codec::frame::{Decoder, Event, MAX_TELEGRAM};
use lms2xx::codec::reply::{parse_reply, Reply, ReplyOptions};

#[test]
fn record_over_pty_captures_sent_scans() {
    let dir = std::env::temp_dir().join(format!("pfe-record-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let link = dir.join("lms");
    let out = dir.join("capture.lms");
    let pty = Pty::open(&link).unwrap();
    let cfg = EmulatorConfig {
        source: SourceKind::Tagged,
        ..Default::default()
    };
    let emu = PtyServer::start(pty, Emulator::from_config(cfg));
    let args: Vec<String> = [
        "--port",
        arg(&link),
        "--baud",
        "38400",
        "--scans",
        "4",
        "-o",
        arg(&out),
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let res = pfe_cli::record::cli(&args);
    let (report, _pty) = emu.stop();
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
    assert_sent_in_order(&scans, &sent);
    assert_eq!(
        report.scans.last().map(|s| s.unit),
        Some(lms2xx::codec::types::Unit::Mm)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every captured scan was sent, each at a later position than the one before: copies of one
/// scan or reordered scans fail (the tagged source makes every sent scan distinct).
fn assert_sent_in_order(captured: &[Vec<u16>], sent: &[Vec<u16>]) {
    let mut next = 0;
    for (i, c) in captured.iter().enumerate() {
        let Some(at) = sent.iter().skip(next).position(|s| s == c) else {
            let anywhere = sent.contains(c);
            panic!(
                "captured scan {i} {}",
                if anywhere {
                    "repeats or precedes an earlier capture"
                } else {
                    "was not sent by the emulator"
                }
            );
        };
        next += at + 1;
    }
}

#[test]
fn copies_and_reordered_scans_are_not_a_capture() {
    let sent: Vec<Vec<u16>> = (0..6u16).map(|k| vec![k, 100 + k, 200 + k]).collect();
    assert_sent_in_order(&sent[1..5], &sent);
    assert_sent_in_order(&[sent[0].clone(), sent[3].clone()], &sent);
    for bad in [
        vec![sent[2].clone(); 4],
        vec![sent[3].clone(), sent[2].clone()],
        vec![vec![9, 9, 9]],
    ] {
        let r = std::panic::catch_unwind(|| assert_sent_in_order(&bad, &sent));
        assert!(r.is_err(), "{bad:?} accepted");
    }
}
