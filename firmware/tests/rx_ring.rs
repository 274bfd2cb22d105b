//! The receive path the board and QEMU run: bytes arrive at wire speed into the interrupt's
//! ring while the application extracts (made artificially slow here); the driver polls the
//! ring. While the backlog fits the ring nothing is lost; beyond it the loss is counted and
//! reported once, the decoder resyncs on the next telegram, and the driver does not
//! re-initialise.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

/// The simulated clock of lms2xx's driver tests (one definition for both crates).
#[path = "../lms2xx/tests/common/mod.rs"]
mod common;

use common::Time;
use firmware::rx_ring::{RxConsumer, RxCounters, RxLoss, RxProducer, RxQueue, RING_SLOTS};
use lms2xx::codec::frame::encode_telegram;
use lms2xx::driver::Error;
use lms2xx::driver::{Config, Driver, SetBaud};

/// The driver's UART over the ring's consumer end (as `ScannerUart` on the board).
struct RingUart<'a> {
    rx: RxConsumer<'a>,
}
impl embedded_io::ErrorType for RingUart<'_> {
    type Error = RxLoss;
}
impl embedded_io::Read for RingUart<'_> {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, RxLoss> {
        self.rx.read(buf)
    }
}
impl embedded_io::ReadReady for RingUart<'_> {
    fn read_ready(&mut self) -> Result<bool, RxLoss> {
        Ok(self.rx.ready())
    }
}
impl embedded_io::Write for RingUart<'_> {
    fn write(&mut self, b: &[u8]) -> Result<usize, RxLoss> {
        Ok(b.len())
    }
    fn flush(&mut self) -> Result<(), RxLoss> {
        Ok(())
    }
}
impl SetBaud for RingUart<'_> {
    fn set_baud(&mut self, _: u32) -> Result<(), RxLoss> {
        Ok(())
    }
}

/// `n` B0 telegrams of 361 values in mm, value 0 of telegram `k` = `k + 1` (to name it).
fn stream(n: usize) -> Vec<u8> {
    let mut out = Vec::new();
    for k in 0..n {
        let mut payload = vec![0xB0];
        payload.extend_from_slice(&(361u16 | 1 << 14).to_le_bytes());
        for i in 0..361u16 {
            let v = if i == 0 { k as u16 + 1 } else { 2000 + i };
            payload.extend_from_slice(&v.to_le_bytes());
        }
        payload.push(0x10);
        let mut t = vec![0u8; payload.len() + 6];
        let len = encode_telegram(0x80, &payload, &mut t).unwrap();
        t.truncate(len);
        out.extend(t);
    }
    out
}

/// What one run saw.
#[derive(Debug)]
struct Run {
    /// Telegram numbers of the scans the driver delivered.
    scans: Vec<u16>,
    /// Losses the driver returned.
    losses: Vec<RxLoss>,
    ring_full: u32,
    reinits: u32,
    crc_errors: u32,
    max_backlog: usize,
}

/// Streams `telegrams` at wire speed; after delivering scan `slow_at` the application is busy
/// for `busy` bytes' time (the wire keeps filling the ring), after every other scan for
/// `fast` bytes' time; between scans the driver polls every 16 bytes.
fn run(telegrams: usize, slow_at: usize, busy: usize, fast: usize) -> Run {
    let bytes = stream(telegrams);
    let mut queue = RxQueue::new();
    let counters = RxCounters::new();
    let (p, c) = queue.split();
    let mut isr = RxProducer::new(p, &counters);
    let uart = RingUart {
        rx: RxConsumer::new(c, &counters),
    };
    let time = Time::default();
    let mut drv = Driver::new(uart, time.clone(), time.clone(), Config::default());
    let mut wire = bytes.iter().copied();
    let mut r = Run {
        scans: Vec::new(),
        losses: Vec::new(),
        ring_full: 0,
        reinits: 0,
        crc_errors: 0,
        max_backlog: 0,
    };
    let mut ended = false;
    while !ended {
        let mut busy_for = 16;
        match drv.poll() {
            Ok(Some(scan)) => {
                let k = scan.codes()[0];
                r.scans.push(k);
                busy_for = if r.scans.len() == slow_at { busy } else { fast };
            }
            Ok(None) => {}
            Err(Error::Io(loss)) => r.losses.push(loss),
            Err(e) => panic!("driver error {e:?}"),
        }
        // The interrupt meanwhile: the wire's bytes go into the ring.
        for _ in 0..busy_for {
            match wire.next() {
                Some(b) => {
                    isr.push(b);
                }
                None => ended = true,
            }
        }
        r.max_backlog = r.max_backlog.max(isr.len());
        time.0.set(time.0.get() + busy_for as u64 * 20);
    }
    // Drain what is left.
    for _ in 0..1000 {
        match drv.poll() {
            Ok(Some(scan)) => r.scans.push(scan.codes()[0]),
            Ok(None) => break,
            Err(Error::Io(loss)) => r.losses.push(loss),
            Err(e) => panic!("driver error {e:?}"),
        }
    }
    r.ring_full = counters.ring_full();
    r.reinits = drv.counters().reinits;
    r.crc_errors = drv.counters().crc_errors;
    r
}

#[test]
fn a_slow_scan_whose_backlog_fits_the_ring_loses_nothing() {
    // Busy for 2000 bytes' time (2.7 telegrams, 40 ms at 500 kBd): the ring holds 2047.
    let r = run(12, 3, 2000, 100);
    assert_eq!(r.ring_full, 0, "{r:?}");
    assert!(r.losses.is_empty(), "{r:?}");
    assert_eq!(r.scans, (1..=12).collect::<Vec<u16>>(), "{r:?}");
    assert!(r.max_backlog > 1500 && r.max_backlog < RING_SLOTS, "{r:?}");
    assert_eq!((r.reinits, r.crc_errors), (0, 0));
}

#[test]
fn beyond_the_ring_the_loss_is_counted_the_decoder_resyncs_and_nothing_reinitialises() {
    // Busy for 4000 bytes' time: 4000 − 2047 bytes are dropped.
    let r = run(14, 3, 4000, 100);
    assert!(r.ring_full >= 4000 - 2047 - 16, "{r:?}");
    assert_eq!(r.losses, vec![RxLoss::RingFull], "reported once: {r:?}");
    // Everything up to the overflow (scans 1..=5: the ring held 2.8 telegrams), then one
    // gap of the telegrams whose bytes were dropped, then every later telegram again: the
    // decoder resynced on the next header (the one cut telegram fails its CRC).
    let lost_telegrams = r.ring_full as usize / 732 + 2;
    let gap = r.scans.windows(2).position(|w| w[1] != w[0] + 1);
    let after = gap.map_or(r.scans.len(), |g| g + 1);
    assert_eq!(&r.scans[..after], &[1, 2, 3, 4, 5], "{r:?}");
    let first_again = usize::from(r.scans[after]);
    assert!(first_again - 6 <= lost_telegrams, "{r:?}");
    assert_eq!(
        &r.scans[after..],
        (first_again as u16..=14).collect::<Vec<u16>>(),
        "resynced: {r:?}"
    );
    assert!(r.crc_errors <= 1, "{r:?}");
    assert_eq!(r.reinits, 0, "no re-initialisation for a ring overrun");
}
