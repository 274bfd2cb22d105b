//! Driver behaviour that needs no device: every wait ends, odd UART answers are errors, not
//! panics or hangs. (Behaviour against a device: host-tests/tests/emulator_*.rs, faults_*.rs.)
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

mod common;

use common::Time;
use lms2xx::driver::Error;
use lms2xx::driver::{Config, Driver, SetBaud};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct E;
impl embedded_io::Error for E {
    fn kind(&self) -> embedded_io::ErrorKind {
        embedded_io::ErrorKind::Other
    }
}

/// A UART that accepts writes (or not) and never receives anything, or only `Ok(0)` reads.
struct Dead {
    write_zero: bool,
    spurious_ready: bool,
    written: usize,
    bauds: Vec<u32>,
}
impl embedded_io::ErrorType for Dead {
    type Error = E;
}
impl embedded_io::Read for Dead {
    fn read(&mut self, _: &mut [u8]) -> Result<usize, E> {
        Ok(0)
    }
}
impl embedded_io::ReadReady for Dead {
    fn read_ready(&mut self) -> Result<bool, E> {
        Ok(self.spurious_ready)
    }
}
impl embedded_io::Write for Dead {
    fn write(&mut self, b: &[u8]) -> Result<usize, E> {
        if self.write_zero {
            return Ok(0);
        }
        self.written += b.len();
        Ok(b.len())
    }
    fn flush(&mut self) -> Result<(), E> {
        Ok(())
    }
}
impl SetBaud for Dead {
    fn set_baud(&mut self, b: u32) -> Result<(), E> {
        self.bauds.push(b);
        Ok(())
    }
}

fn dead(write_zero: bool, spurious_ready: bool) -> Dead {
    Dead {
        write_zero,
        spurious_ready,
        written: 0,
        bauds: Vec::new(),
    }
}

#[test]
fn silent_device_gives_no_device_in_bounded_time() {
    for spurious in [false, true] {
        let t = Time::default();
        let mut d = Driver::new(
            dead(false, spurious),
            t.clone(),
            t.clone(),
            Config::default(),
        );
        assert_eq!(d.init(), Err(Error::NoDevice));
        let c = d.counters();
        // 3 rounds over 4 rates, one 1 s try each.
        assert_eq!(c.timeouts, 12);
        let secs = t.0.get() as f64 / 1e6;
        assert!((12.0..12.5).contains(&secs), "took {secs} s");
        // next_scan reports the same error instead of hanging.
        assert_eq!(d.next_scan().err(), Some(Error::NoDevice));
        let (uart, _, _) = d.release();
        // Every rate was tried, the configured one (38400) first.
        assert_eq!(&uart.bauds[..4], &[38400, 9600, 19200, 500_000]);
        assert_eq!(uart.written, 2 * 12 * 8);
    }
}

#[test]
fn write_returning_zero_is_an_error() {
    let t = Time::default();
    let mut d = Driver::new(dead(true, false), t.clone(), t, Config::default());
    assert_eq!(d.init(), Err(Error::WriteZero));
}

#[test]
fn invalid_variant_refused_before_any_byte() {
    let t = Time::default();
    let cfg = Config::default().with_variant(lms2xx::codec::types::Variant::new(180, 25));
    let mut d = Driver::new(dead(false, false), t.clone(), t, cfg);
    assert_eq!(d.init(), Err(Error::InvalidConfig));
    assert_eq!(d.release().0.written, 0);
}

#[test]
fn errors_display() {
    let e: Error<E> = Error::Timeout { command: 0x31 };
    assert_eq!(e.to_string(), "no reply to command 0x31");
    let e: Error<E> = Error::Rejected {
        command: 0x3B,
        code: 0,
    };
    assert!(e.to_string().contains("0x3b"));
}

/// A device that streams scans without end and answers no command: every byte read takes its
/// line time at 38 400 Bd (260 µs) on the shared clock. Reading more than `limit` bytes means
/// the driver never gave up.
struct Chatty {
    time: Time,
    telegram: Vec<u8>,
    at: usize,
    read: usize,
    limit: usize,
}
impl embedded_io::ErrorType for Chatty {
    type Error = E;
}
impl embedded_io::Read for Chatty {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, E> {
        assert!(
            self.read < self.limit,
            "the driver kept reading: a wait never ended"
        );
        let n = buf.len().min(16);
        for b in &mut buf[..n] {
            *b = self.telegram[self.at];
            self.at = (self.at + 1) % self.telegram.len();
        }
        self.read += n;
        self.time.0.set(self.time.0.get() + 260 * n as u64);
        Ok(n)
    }
}
impl embedded_io::ReadReady for Chatty {
    fn read_ready(&mut self) -> Result<bool, E> {
        Ok(true)
    }
}
impl embedded_io::Write for Chatty {
    fn write(&mut self, b: &[u8]) -> Result<usize, E> {
        Ok(b.len())
    }
    fn flush(&mut self) -> Result<(), E> {
        Ok(())
    }
}
impl SetBaud for Chatty {
    fn set_baud(&mut self, _: u32) -> Result<(), E> {
        Ok(())
    }
}

/// A line that never falls quiet (a scanner left streaming, whose scans answer no command)
/// does not keep a command's wait going: init gives up after its tries, in bounded time.
#[test]
fn a_line_that_never_falls_quiet_does_not_hold_a_wait() {
    let telegram = common::b0_telegram(361, 1000);
    assert_eq!(telegram.len(), 732);
    let t = Time::default();
    let uart = Chatty {
        time: t.clone(),
        telegram,
        at: 0,
        read: 0,
        limit: 2_000_000,
    };
    let mut d = Driver::new(uart, t.clone(), t.clone(), Config::default());
    assert!(d.init().is_err());
    assert!(d.counters().timeouts > 0);
    let secs = t.0.get() as f64 / 1e6;
    assert!(secs < 120.0, "init took {secs} s of line time");
}
