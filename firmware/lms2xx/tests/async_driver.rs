//! The AsyncDriver against the scripted LMS200 (common/lms.rs), beside the blocking Driver on
//! the same device and the same faults: both run the one protocol state machine, so they must
//! deliver the same scans (values, sequence numbers, times), the same errors and counters, and
//! send the same commands. The executor is a ten-line `block_on` (a no-op waker polled in a
//! loop): the simulated UART and delay never leave a future pending for long.
#![cfg(feature = "async")]
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

mod common;

use core::future::{poll_fn, Future};
use core::pin::pin;
use core::task::{Context, Poll, Waker};

use common::lms::{device_telegram, Lms, E};
use common::Time;
use lms2xx::codec::types::{Baud, Unit};
use lms2xx::driver::{AsyncDriver, AsyncSetBaud, Config, Counters, Driver, Error, SetBaud};

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

// The async traits are embedded-io 0.7's (embassy's), whose errors are `core::error::Error`s.
impl core::fmt::Display for E {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("mock UART error")
    }
}
impl std::error::Error for E {}
impl embedded_io_async::Error for E {
    fn kind(&self) -> embedded_io_async::ErrorKind {
        embedded_io_async::ErrorKind::Other
    }
}

/// A blocking UART seen through the async traits: a read with nothing available is pending
/// (as on a real async UART) until bytes arrive, which in simulated time happens only when a
/// delay advances it.
struct Async<T>(T);

impl<T: embedded_io::ErrorType<Error = E>> embedded_io_async::ErrorType for Async<T> {
    type Error = E;
}
impl<T: embedded_io::Read + embedded_io::ReadReady + embedded_io::ErrorType<Error = E>>
    embedded_io_async::Read for Async<T>
{
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, E> {
        poll_fn(|_| match self.0.read_ready() {
            Ok(true) => Poll::Ready(self.0.read(buf)),
            Ok(false) => Poll::Pending,
            Err(e) => Poll::Ready(Err(e)),
        })
        .await
    }
}
impl<T: embedded_io::Write + embedded_io::ErrorType<Error = E>> embedded_io_async::Write
    for Async<T>
{
    async fn write(&mut self, buf: &[u8]) -> Result<usize, E> {
        self.0.write(buf)
    }
    async fn flush(&mut self) -> Result<(), E> {
        self.0.flush()
    }
}
impl<T: SetBaud + embedded_io::ErrorType<Error = E>> AsyncSetBaud for Async<T> {
    async fn set_baud(&mut self, baud: u32) -> Result<(), E> {
        self.0.set_baud(baud)
    }
}
impl embedded_hal_async::delay::DelayNs for Async<Time> {
    async fn delay_ns(&mut self, ns: u32) {
        embedded_hal::delay::DelayNs::delay_ns(&mut self.0, ns);
    }
}

/// Byte faults on the receive side: the received bytes with these indices (0 = first byte
/// ever read) are inverted (CRC errors, resynchronisation) or lost.
struct Faulty {
    lms: Lms,
    at: usize,
    flip: Vec<usize>,
    lose: Vec<usize>,
}

impl embedded_io::ErrorType for Faulty {
    type Error = E;
}
impl embedded_io::Read for Faulty {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, E> {
        let n = self.lms.read(buf)?;
        let mut kept = 0;
        for i in 0..n {
            let k = self.at;
            self.at += 1;
            if self.lose.contains(&k) {
                continue;
            }
            buf[kept] = if self.flip.contains(&k) {
                !buf[i]
            } else {
                buf[i]
            };
            kept += 1;
        }
        // Every byte lost: the spurious Ok(0) some HALs give, which the drivers must take.
        Ok(kept)
    }
}
impl embedded_io::ReadReady for Faulty {
    fn read_ready(&mut self) -> Result<bool, E> {
        self.lms.read_ready()
    }
}
impl embedded_io::Write for Faulty {
    fn write(&mut self, b: &[u8]) -> Result<usize, E> {
        self.lms.write(b)
    }
    fn flush(&mut self) -> Result<(), E> {
        self.lms.flush()
    }
}
impl SetBaud for Faulty {
    fn set_baud(&mut self, bps: u32) -> Result<(), E> {
        self.lms.set_baud(bps)
    }
}

/// What a scan is, for comparison: sequence number, driver time, status, value count, first
/// value and an FNV-1a hash of all values (short, so a mismatch prints readably).
type Seen = Result<(u32, u32, u8, usize, u16, u64), Error<E>>;

/// Everything a run shows: per call its result, the counters, the commands the device
/// received, the host's baud changes, the simulated time at the end (µs).
#[derive(Debug, PartialEq)]
struct Run {
    results: Vec<Seen>,
    counters: Counters,
    commands: Vec<Vec<u8>>,
    host_bauds: Vec<u32>,
    end_us: u64,
}

struct Scenario {
    name: &'static str,
    dev_bps: u32,
    config: Config,
    calls: usize,
    setup: fn(&mut Lms),
    flip: Vec<usize>,
    lose: Vec<usize>,
}

fn faulty(s: &Scenario, t: &Time) -> Faulty {
    let mut lms = Lms::new(t.clone(), s.dev_bps);
    (s.setup)(&mut lms);
    Faulty {
        lms,
        at: 0,
        flip: s.flip.clone(),
        lose: s.lose.clone(),
    }
}

fn seen(r: Result<&lms2xx::driver::ScanData, Error<E>>) -> Seen {
    r.map(|s| {
        let hash = s.codes().iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &c| {
            (h ^ u64::from(c)).wrapping_mul(0x0100_0000_01b3)
        });
        let first = s.codes().first().copied().unwrap_or(0);
        (s.seq, s.time_ms, s.status.0, s.len(), first, hash)
    })
}

fn run_blocking(s: &Scenario) -> Run {
    let t = Time::default();
    let mut d = Driver::new(faulty(s, &t), t.clone(), t.clone(), s.config);
    let results = (0..s.calls).map(|_| seen(d.next_scan())).collect();
    let counters = d.counters();
    let (u, _, _) = d.release();
    Run {
        results,
        counters,
        commands: u.lms.commands,
        host_bauds: u.lms.host_bauds,
        end_us: t.0.get(),
    }
}

fn run_async(s: &Scenario) -> Run {
    let t = Time::default();
    let mut d = AsyncDriver::new(Async(faulty(s, &t)), Async(t.clone()), t.clone(), s.config);
    let results = (0..s.calls)
        .map(|_| seen(block_on(d.next_scan())))
        .collect();
    let counters = d.counters();
    let (u, _, _) = d.release();
    Run {
        results,
        counters,
        commands: u.0.lms.commands,
        host_bauds: u.0.lms.host_bauds,
        end_us: t.0.get(),
    }
}

fn scenarios() -> Vec<Scenario> {
    let base = |name, setup: fn(&mut Lms)| Scenario {
        name,
        dev_bps: 38400,
        config: Config::default(),
        calls: 12,
        setup,
        flip: Vec::new(),
        lose: Vec::new(),
    };
    vec![
        base("clean", |_| {}),
        // Init answers take well under 1000 bytes; scans are 732 bytes each at 38 400 Bd.
        Scenario {
            flip: vec![2000, 2500, 2501, 4000],
            lose: vec![3000, 5200, 5201, 5202],
            ..base("corrupted and lost bytes", |_| {})
        },
        Scenario {
            dev_bps: 9600,
            calls: 5,
            ..base("baud switch from 9600", |_| {})
        },
        base("power-on in place of scans 3 and 4", |l| {
            l.power_on_scans = vec![3, 4]
        }),
        base("restart bit on scan 2", |l| l.restart_scans = vec![2]),
        base("scans in cm", |l| l.scan_unit_bits = Some(0)),
        base("stray A0 after scan 5", |l| {
            l.stray_after_scan = vec![(5, vec![0xA0, 0x00, 0x10])]
        }),
        base("type refused, status not answered", |l| {
            l.answer_status = false;
            l.replace_reply = Some((1, [&[0x06][..], &device_telegram(&[0x92, 0x10])].concat()));
        }),
        Scenario {
            calls: 3,
            ..base("power-on for ever", |l| {
                l.power_on_scans = (1..=60).collect()
            })
        },
        Scenario {
            config: Config::default()
                .with_unit(Unit::Cm)
                .with_baud(Baud::B19200),
            calls: 6,
            ..base("unit and baud to change", |_| {})
        },
    ]
}

/// Blocking and async deliver the same scans, errors and counters and send the same commands,
/// scenario by scenario; each scenario shows the behaviour it is about (so agreeing on doing
/// nothing would fail).
#[test]
fn async_and_blocking_agree_under_faults() {
    for s in scenarios() {
        let b = run_blocking(&s);
        let a = run_async(&s);
        let name = s.name;
        assert_eq!(a.results, b.results, "{name}: results");
        assert_eq!(a.counters, b.counters, "{name}: counters");
        assert_eq!(a.commands, b.commands, "{name}: commands");
        assert_eq!(a.host_bauds, b.host_bauds, "{name}: bauds");
        assert_eq!(a.end_us, b.end_us, "{name}: simulated time");
        let c = a.counters;
        let oks = a.results.iter().filter(|r| r.is_ok()).count();
        match name {
            "clean" => {
                assert_eq!(oks, 12);
                assert_eq!((c.crc_errors, c.reinits, c.timeouts), (0, 0, 0));
                let seqs: Vec<u32> = a.results.iter().map(|r| r.as_ref().unwrap().0).collect();
                assert_eq!(seqs, (1..=12).collect::<Vec<_>>());
                let first = a.results[0].as_ref().unwrap();
                assert_eq!((first.3, first.4), (361, 1000));
            }
            "corrupted and lost bytes" => {
                assert_eq!(oks, 12);
                assert!(c.crc_errors + c.bad_length >= 2, "{c:?}");
                assert!(c.bytes_skipped > 0, "{c:?}");
            }
            "baud switch from 9600" => {
                assert_eq!(oks, 5);
                assert_eq!(a.host_bauds.last(), Some(&38400));
                assert!(a.commands.contains(&vec![0x20, 0x40]));
            }
            "power-on in place of scans 3 and 4" => {
                assert_eq!(oks, 12);
                assert!(c.reinits >= 1 && c.device_resets >= 1, "{c:?}");
            }
            "restart bit on scan 2" => {
                assert_eq!((c.reinits, c.device_resets), (1, 1), "{c:?}");
            }
            "scans in cm" => {
                assert_eq!(oks, 12);
                assert_eq!((c.reinits, c.device_resets), (1, 1), "{c:?}");
            }
            "stray A0 after scan 5" => {
                // Scan 5 ends about a second after `20 24`: a late answer, no reset.
                assert_eq!(c.device_resets, 0, "{c:?}");
            }
            "type refused, status not answered" => {
                assert_eq!(oks, 12);
                assert_eq!(c.variant_refused, 0);
                assert!(a.commands.iter().any(|p| p[0] == 0x3B), "variant set");
            }
            "power-on for ever" => {
                assert!(a.results.iter().all(|r| *r == Err(Error::Silence)));
                assert_eq!(c.reinits, 3 * 2 + 2, "{c:?}");
            }
            "unit and baud to change" => {
                assert_eq!(oks, 6);
                assert!(a.commands.iter().any(|p| p[0] == 0x77), "config written");
                assert_eq!(a.host_bauds.last(), Some(&19200));
            }
            _ => unreachable!(),
        }
    }
}

/// A UART that takes writes and never receives: no device at any rate, in bounded (simulated)
/// time, with the blocking driver's counts (lms_driver.rs: 3 rounds over 4 rates, 1 s each).
struct Dead(u32);
impl embedded_io_async::ErrorType for Dead {
    type Error = E;
}
impl embedded_io_async::Read for Dead {
    async fn read(&mut self, _: &mut [u8]) -> Result<usize, E> {
        poll_fn(|_| Poll::Pending).await
    }
}
impl embedded_io_async::Write for Dead {
    async fn write(&mut self, b: &[u8]) -> Result<usize, E> {
        Ok(if self.0 == 0 { 0 } else { b.len() })
    }
    async fn flush(&mut self) -> Result<(), E> {
        Ok(())
    }
}
impl AsyncSetBaud for Dead {
    async fn set_baud(&mut self, _: u32) -> Result<(), E> {
        Ok(())
    }
}

#[test]
fn silent_device_gives_no_device_in_bounded_time() {
    let t = Time::default();
    let mut d = AsyncDriver::new(Dead(1), Async(t.clone()), t.clone(), Config::default());
    assert_eq!(block_on(d.init()), Err(Error::NoDevice));
    assert_eq!(d.counters().timeouts, 12);
    let secs = t.0.get() as f64 / 1e6;
    assert!((12.0..12.5).contains(&secs), "took {secs} s");
    assert_eq!(block_on(d.next_scan()).err(), Some(Error::NoDevice));
}

#[test]
fn write_returning_zero_is_an_error() {
    let t = Time::default();
    let mut d = AsyncDriver::new(Dead(0), Async(t.clone()), t, Config::default());
    assert_eq!(block_on(d.init()), Err(Error::WriteZero));
}

/// stop and reset_device: `20 25`, then `10` answered `91`, after which the device is at 9600.
#[test]
fn stop_and_reset() {
    let t = Time::default();
    let lms = Async(Lms::new(t.clone(), 38400));
    let mut d = AsyncDriver::new(lms, Async(t.clone()), t, Config::default());
    block_on(d.next_scan()).unwrap();
    assert!(d.is_streaming());
    block_on(d.stop()).unwrap();
    assert!(!d.is_streaming());
    block_on(d.reset_device()).unwrap();
    assert_eq!(d.device().baud, Some(Baud::B9600));
    let (u, _, _) = d.release();
    let n = u.0.commands.len();
    assert_eq!(u.0.commands[n - 2], vec![0x20, 0x25]);
    assert_eq!(u.0.commands[n - 1], vec![0x10]);
}
