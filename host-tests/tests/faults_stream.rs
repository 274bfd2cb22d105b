//! Fault injection between the emulated LMS200 and the firmware driver: every intact scan is
//! delivered exactly once, no damaged one is accepted, the driver recovers, counters tell.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: a panic fails the test

use std::collections::BTreeSet;
use std::future::{poll_fn, Future};
use std::pin::pin;
use std::task::{Context, Poll, Waker};

use lms200_emulator::{
    Emulator, EmulatorConfig, Faults, HostPort, Link, LinkDelay, LinkError, SentScan, SourceKind,
    TaggedSource,
};
use lms2xx::codec::types::Baud;
use lms2xx::driver::{AsyncDriver, AsyncSetBaud, Config, Counters, Driver, SetBaud};

struct Run {
    delivered: Vec<u32>,
    sent: Vec<SentScan>,
    counters: Counters,
}

fn run(faults: Faults, seed: u64, initial: Baud, n: usize, driver: Config) -> Run {
    let cfg = EmulatorConfig {
        source: SourceKind::Tagged,
        faults: faults.clone(),
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
    let run = Run {
        delivered,
        sent: link.with_emulator(|e| e.report().scans.clone()).unwrap(),
        counters: lms.counters(),
    };
    let a = run_async(faults, seed, initial, n, driver);
    assert_eq!(a.delivered, run.delivered, "async driver: other scans");
    assert_eq!(
        format!("{:?}", a.counters),
        format!("{:?}", run.counters),
        "async driver: other counters"
    );
    run
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

/// The async driver ([`AsyncDriver`]) on the same emulated device, faults and seed: it must
/// deliver the same scans with the same counters as the blocking one (one state machine).
fn run_async(faults: Faults, seed: u64, initial: Baud, n: usize, driver: Config) -> Run {
    let cfg = EmulatorConfig {
        source: SourceKind::Tagged,
        faults,
        seed,
        initial_baud: initial,
        ..Default::default()
    };
    let link = Link::new(Emulator::from_config(cfg), Some(9600));
    let mut lms = AsyncDriver::new(
        AsyncPort(link.host_port()),
        AsyncDelay(link.delay()),
        link.clock(),
        driver,
    );
    let mut delivered = Vec::new();
    while delivered.len() < n {
        let s = block_on(lms.next_scan()).expect("async driver recovers");
        let tag = TaggedSource::tag_of(s.codes()).expect("tagged scan");
        delivered.push(tag);
    }
    Run {
        delivered,
        sent: link.with_emulator(|e| e.report().scans.clone()).unwrap(),
        counters: lms.counters(),
    }
}

/// Runs `f` to completion; a future pending for a million polls is a hang.
fn block_on<F: Future>(f: F) -> F::Output {
    let mut f = pin!(f);
    let mut cx = Context::from_waker(Waker::noop());
    for _ in 0..1_000_000 {
        if let Poll::Ready(v) = f.as_mut().poll(&mut cx) {
            return v;
        }
    }
    panic!("future pending for a million polls");
}

/// The emulator's host port through the async traits: a read with nothing available is
/// pending until bytes arrive, which in virtual time happens only when a delay advances it.
struct AsyncPort(HostPort);
struct AsyncDelay(LinkDelay);

/// The link's error as an embedded-io-async error.
#[derive(Debug)]
struct PortError(#[allow(dead_code)] LinkError);
impl core::fmt::Display for PortError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{:?}", self.0)
    }
}
impl std::error::Error for PortError {}
impl embedded_io_async::Error for PortError {
    fn kind(&self) -> embedded_io_async::ErrorKind {
        embedded_io_async::ErrorKind::Other
    }
}
impl embedded_io_async::ErrorType for AsyncPort {
    type Error = PortError;
}
impl embedded_io_async::Read for AsyncPort {
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, PortError> {
        use embedded_io::{Read, ReadReady};
        poll_fn(|_| match self.0.read_ready() {
            Ok(true) => Poll::Ready(self.0.read(buf).map_err(PortError)),
            Ok(false) => Poll::Pending,
            Err(e) => Poll::Ready(Err(PortError(e))),
        })
        .await
    }
}
impl embedded_io_async::Write for AsyncPort {
    async fn write(&mut self, buf: &[u8]) -> Result<usize, PortError> {
        embedded_io::Write::write(&mut self.0, buf).map_err(PortError)
    }
    async fn flush(&mut self) -> Result<(), PortError> {
        embedded_io::Write::flush(&mut self.0).map_err(PortError)
    }
}
impl AsyncSetBaud for AsyncPort {
    async fn set_baud(&mut self, baud: u32) -> Result<(), PortError> {
        SetBaud::set_baud(&mut self.0, baud).map_err(PortError)
    }
}
impl embedded_hal_async::delay::DelayNs for AsyncDelay {
    async fn delay_ns(&mut self, ns: u32) {
        embedded_hal::delay::DelayNs::delay_ns(&mut self.0, ns);
    }
}
