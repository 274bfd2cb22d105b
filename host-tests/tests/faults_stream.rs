//! Fault injection between the emulated LMS200 and the firmware driver: every intact scan is
//! delivered exactly once, no damaged one is accepted, the driver recovers, counters tell.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: a panic fails the test

use std::collections::BTreeSet;

use lms200_emulator::{Emulator, EmulatorConfig, Faults, Link, SentScan, SourceKind, TaggedSource};
use lms2xx::codec::types::Baud;
use lms2xx::driver::{Config, Counters, Driver};

struct Run {
    delivered: Vec<u32>,
    sent: Vec<SentScan>,
    counters: Counters,
}

fn run(faults: Faults, seed: u64, initial: Baud, n: usize, driver: Config) -> Run {
    let cfg = EmulatorConfig {
        source: SourceKind::Tagged,
        faults,
        seed,
        initial_baud: initial,
        ..Default::default()
    };
    let link = Link::new(Emulator::from_config(cfg), Some(9600));
    let mut lms = Driver::new(link.host_port(), link.delay(), link.clock(), driver);
    let mut delivered = Vec::new();
    while delivered.len() < n {
        let s = lms.next_scan().expect("driver recovers");
        let tag = TaggedSource::tag_of(s.codes()).expect("tagged scan");
        let sent = link
            .with_emulator(|e| e.report().scans[tag as usize].clone())
            .unwrap();
        assert_eq!(
            s.codes(),
            &sent.words[..],
            "scan {tag} delivered with other values"
        );
        assert!(!sent.damaged, "damaged scan {tag} accepted");
        delivered.push(tag);
    }
    Run {
        delivered,
        sent: link.with_emulator(|e| e.report().scans.clone()).unwrap(),
        counters: lms.counters(),
    }
}

/// Delivered exactly once each, in order, and every intact scan up to the last delivered one.
fn check_exactly_once(r: &Run) {
    let set: BTreeSet<u32> = r.delivered.iter().copied().collect();
    assert_eq!(
        set.len(),
        r.delivered.len(),
        "duplicates: {:?}",
        r.delivered
    );
    assert!(r.delivered.windows(2).all(|w| w[0] < w[1]), "out of order");
    let last = *r.delivered.last().unwrap();
    let intact: BTreeSet<u32> = r
        .sent
        .iter()
        .filter(|s| !s.damaged && s.seq <= last)
        .map(|s| s.seq)
        .collect();
    let missing: Vec<_> = intact.difference(&set).collect();
    assert!(
        missing.is_empty(),
        "intact scans not delivered: {missing:?}"
    );
}

fn damaged_upto(r: &Run) -> usize {
    let last = *r.delivered.last().unwrap();
    r.sent.iter().filter(|s| s.damaged && s.seq <= last).count()
}

fn dflt() -> Config {
    Config::default()
}

#[test]
fn clean_stream_baseline() {
    let r = run(Faults::default(), 1, Baud::B9600, 30, dflt());
    check_exactly_once(&r);
    assert_eq!(r.delivered, (0..30).collect::<Vec<_>>());
    assert_eq!(r.counters.crc_errors, 0);
    assert_eq!(r.counters.reinits, 0);
}

#[test]
fn garbage_between_telegrams() {
    let f = Faults {
        garbage: 0.6,
        ..Default::default()
    };
    let r = run(f, 2, Baud::B9600, 60, dflt());
    check_exactly_once(&r);
    assert_eq!(damaged_upto(&r), 0);
    assert!(r.counters.bytes_skipped > 100, "{:?}", r.counters);
}

#[test]
fn bit_flips() {
    let f = Faults {
        bit_flip: 0.3,
        ..Default::default()
    };
    let r = run(f, 3, Baud::B9600, 60, dflt());
    check_exactly_once(&r);
    let d = damaged_upto(&r);
    assert!(d >= 10, "only {d} damaged");
    let dropped = r.counters.crc_errors + r.counters.bad_length;
    assert!(dropped as usize >= d, "{d} damaged but {:?}", r.counters);
}

#[test]
fn dropped_and_duplicated_bytes() {
    let f = Faults {
        drop_byte: 0.2,
        duplicate_byte: 0.2,
        ..Default::default()
    };
    let r = run(f, 4, Baud::B9600, 60, dflt());
    check_exactly_once(&r);
    let d = damaged_upto(&r);
    assert!(d >= 10, "only {d} damaged");
    assert!((r.counters.crc_errors + r.counters.bad_length) as usize >= d);
}

#[test]
fn truncated_telegrams() {
    let f = Faults {
        truncate: 0.3,
        ..Default::default()
    };
    let r = run(f, 5, Baud::B9600, 60, dflt());
    check_exactly_once(&r);
    assert!(damaged_upto(&r) >= 10);
}

#[test]
fn everything_at_once_over_many_seeds() {
    for seed in 10..16 {
        let f = Faults {
            bit_flip: 0.05,
            drop_byte: 0.05,
            duplicate_byte: 0.05,
            truncate: 0.05,
            garbage: 0.1,
            ..Default::default()
        };
        let r = run(f, seed, Baud::B9600, 40, dflt());
        check_exactly_once(&r);
    }
}

#[test]
fn nak_then_retry() {
    let f = Faults {
        nak_commands: 2,
        ..Default::default()
    };
    // Device already at 38400: the first command (the probe) is NAKed twice.
    let r = run(f, 6, Baud::B38400, 5, dflt());
    check_exactly_once(&r);
    assert_eq!(r.counters.naks, 2);
    assert_eq!(r.counters.reinits, 0);
}

#[test]
fn device_silent_then_back() {
    let f = Faults {
        silence_after_scans: Some(10),
        silence_ms: 2500,
        ..Default::default()
    };
    let r = run(f, 7, Baud::B9600, 25, dflt());
    let set: BTreeSet<u32> = r.delivered.iter().copied().collect();
    assert_eq!(set.len(), r.delivered.len(), "duplicates");
    assert!(r.counters.reinits >= 1, "{:?}", r.counters);
    assert_eq!(r.delivered[..10], (0..10).collect::<Vec<_>>()[..]);
    assert!(r.delivered.len() == 25);
}

#[test]
fn device_reset_mid_stream() {
    let f = Faults {
        reset_after_scans: Some(8),
        ..Default::default()
    };
    let r = run(f, 8, Baud::B9600, 20, dflt());
    let set: BTreeSet<u32> = r.delivered.iter().copied().collect();
    assert_eq!(set.len(), r.delivered.len(), "duplicates");
    assert_eq!(r.delivered[..8], (0..8).collect::<Vec<_>>()[..]);
    // The device came back at 9600: the driver found it again and switched to 38400.
    assert!(r.counters.reinits >= 1, "{:?}", r.counters);
    assert!(r.counters.timeouts >= 1);
}

#[test]
fn commanded_reset_then_reinit() {
    let cfg = EmulatorConfig {
        source: SourceKind::Tagged,
        ..Default::default()
    };
    let link = Link::new(Emulator::from_config(cfg), Some(9600));
    let mut lms = Driver::new(link.host_port(), link.delay(), link.clock(), dflt());
    lms.next_scan().unwrap();
    lms.reset_device().unwrap();
    // Next scan: re-initialises from 9600 after the power-on message.
    let s = lms.next_scan().unwrap();
    assert_eq!(s.len(), 361);
    assert_eq!(link.with_emulator(|e| e.report().resets).unwrap(), 1);
    assert_eq!(link.with_emulator(|e| e.baud()).unwrap(), Baud::B38400);
}

#[test]
fn wrong_initial_baud_is_probed() {
    for initial in [Baud::B19200, Baud::B38400, Baud::B500000] {
        let r = run(Faults::default(), 9, initial, 5, dflt());
        check_exactly_once(&r);
    }
    // And a target of 500 k from a device at 19200.
    let r = run(
        Faults::default(),
        9,
        Baud::B19200,
        5,
        dflt().with_baud(Baud::B500000),
    );
    check_exactly_once(&r);
}

#[test]
fn damaged_replies_during_init_are_retried() {
    let (mut damaged, mut retries) = (0, 0);
    for seed in 20..26 {
        let f = Faults {
            bit_flip: 0.15,
            truncate: 0.1,
            drop_byte: 0.05,
            damage_replies: true,
            ..Default::default()
        };
        let cfg = EmulatorConfig {
            source: SourceKind::Tagged,
            faults: f,
            seed,
            ..Default::default()
        };
        let link = Link::new(Emulator::from_config(cfg), Some(9600));
        let mut lms = Driver::new(link.host_port(), link.delay(), link.clock(), dflt());
        // A lost A0 to the baud switch makes one init fail; calling again recovers.
        let mut delivered = Vec::new();
        let mut errors = 0;
        while delivered.len() < 10 {
            match lms.next_scan() {
                Ok(s) => delivered.push(TaggedSource::tag_of(s.codes()).unwrap()),
                Err(_) => errors += 1,
            }
            assert!(errors < 5, "seed {seed}: driver does not recover");
        }
        let sent = link.with_emulator(|e| e.report().clone()).unwrap();
        for t in &delivered {
            assert!(!sent.scans[*t as usize].damaged);
        }
        let set: BTreeSet<u32> = delivered.iter().copied().collect();
        assert_eq!(set.len(), delivered.len());
        damaged += sent.damaged_replies;
        retries += lms.counters().retries;
    }
    eprintln!("damaged replies {damaged}, driver retries {retries}");
    assert!(damaged >= 5, "only {damaged} replies damaged");
    assert!(retries >= 3, "only {retries} retries");
}
