//! In-process link between the firmware driver and the [`Emulator`], in virtual time.
//!
//! [`HostPort`] implements `embedded_io::{Read, Write, ReadReady}` and the driver's `SetBaud`;
//! [`LinkDelay`] (`DelayNs`) advances virtual time; [`LinkClock`] reads it. Nothing sleeps, so
//! tests of seconds of device time run in milliseconds and are deterministic.
//!
//! ```
//! use lms2xx::driver::{Config, Driver};
//! use lms200_emulator::{Emulator, EmulatorConfig, Link};
//! // A device at power-on (9600 baud), host UART modelled starting at 9600.
//! let link = Link::new(Emulator::from_config(EmulatorConfig::default()), Some(9600));
//! let mut lms = Driver::new(link.host_port(), link.delay(), link.clock(), Config::default());
//! let scan = lms.next_scan().unwrap(); // probes, switches to 38400, streams
//! assert_eq!(scan.len(), 361);
//! let sent = link.with_emulator(|e| e.report().scans[0].words.clone()).unwrap();
//! assert_eq!(scan.codes(), &sent[..]);
//! ```

use std::sync::{Arc, Mutex, MutexGuard};

use lms2xx::driver::{Clock, SetBaud};

use super::Emulator;

/// Errors of the in-process link.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LinkError {
    /// The link's lock was poisoned (a test panicked while holding it).
    Poisoned,
}

impl std::fmt::Display for LinkError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("emulated link unusable (poisoned lock)")
    }
}

impl std::error::Error for LinkError {}

impl embedded_io::Error for LinkError {
    fn kind(&self) -> embedded_io::ErrorKind {
        embedded_io::ErrorKind::Other
    }
}

struct Inner {
    emu: Emulator,
    now_us: u64,
    /// Host UART speed; `None` models a link without baud (always the device's).
    host_baud: Option<u32>,
    rx: std::collections::VecDeque<u8>,
    /// Every byte the host received, in order (for captures).
    capture: Vec<u8>,
}

impl Inner {
    fn pump(&mut self) {
        let mut out = Vec::new();
        let now = self.now_us;
        let hb = self.host_baud;
        self.emu.take_ready(now, hb, &mut out);
        self.capture.extend(&out);
        self.rx.extend(out);
    }
}

/// Shared handle on an emulated device and the wire to it.
#[derive(Clone)]
pub struct Link {
    inner: Arc<Mutex<Inner>>,
}

impl Link {
    /// A link to `emu`, host UART at 9600 baud (`Some`) or without baud modelling (`None`).
    pub fn new(emu: Emulator, host_baud: Option<u32>) -> Self {
        Self {
            inner: Arc::new(Mutex::new(Inner {
                emu,
                now_us: 0,
                host_baud,
                rx: Default::default(),
                capture: Vec::new(),
            })),
        }
    }

    fn lock(&self) -> Result<MutexGuard<'_, Inner>, LinkError> {
        self.inner.lock().map_err(|_| LinkError::Poisoned)
    }

    /// The host side of the UART.
    pub fn host_port(&self) -> HostPort {
        HostPort { link: self.clone() }
    }
    /// A delay that advances virtual time.
    pub fn delay(&self) -> LinkDelay {
        LinkDelay { link: self.clone() }
    }
    /// A clock reading virtual time.
    pub fn clock(&self) -> LinkClock {
        LinkClock { link: self.clone() }
    }
    /// Runs `f` on the emulator (e.g. to read its report or change faults).
    pub fn with_emulator<R>(&self, f: impl FnOnce(&mut Emulator) -> R) -> Result<R, LinkError> {
        Ok(f(&mut self.lock()?.emu))
    }
    /// Virtual time, µs.
    pub fn now_us(&self) -> u64 {
        self.lock().map(|g| g.now_us).unwrap_or(0)
    }
    /// Advances virtual time by `us`.
    pub fn advance(&self, us: u64) -> Result<(), LinkError> {
        let mut g = self.lock()?;
        g.now_us += us;
        g.pump();
        Ok(())
    }
    /// Every byte the host side has received so far.
    pub fn capture(&self) -> Vec<u8> {
        self.lock().map(|g| g.capture.clone()).unwrap_or_default()
    }
    /// The host UART's current baud (`None`: not modelled).
    pub fn host_baud(&self) -> Option<u32> {
        self.lock().ok().and_then(|g| g.host_baud)
    }
}

/// Host side of the emulated UART.
#[derive(Clone)]
pub struct HostPort {
    link: Link,
}

impl embedded_io::ErrorType for HostPort {
    type Error = LinkError;
}

impl embedded_io::ReadReady for HostPort {
    fn read_ready(&mut self) -> Result<bool, LinkError> {
        let mut g = self.link.lock()?;
        g.pump();
        Ok(!g.rx.is_empty())
    }
}

impl embedded_io::Read for HostPort {
    /// Blocks (in virtual time) until a byte is there, for at most 100 ms; may return `Ok(0)`.
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, LinkError> {
        let mut g = self.link.lock()?;
        g.pump();
        if g.rx.is_empty() {
            let limit = g.now_us + 100_000;
            let next = g.emu.next_byte_at().unwrap_or(limit).min(limit);
            g.now_us = g.now_us.max(next);
            g.pump();
        }
        let n = buf.len().min(g.rx.len());
        for (d, s) in buf.iter_mut().zip(g.rx.drain(..n)) {
            *d = s;
        }
        Ok(n)
    }
}

impl embedded_io::Write for HostPort {
    /// Sends `buf`; virtual time advances by its transmission time at the host's baud.
    fn write(&mut self, buf: &[u8]) -> Result<usize, LinkError> {
        let mut g = self.link.lock()?;
        let bt = g
            .host_baud
            .map_or(0, |b| 10_000_000u64.div_ceil(u64::from(b.max(1))));
        g.now_us += bt * buf.len() as u64;
        let (now, hb) = (g.now_us, g.host_baud);
        g.emu.receive(now, hb, buf);
        g.pump();
        Ok(buf.len())
    }
    fn flush(&mut self) -> Result<(), LinkError> {
        Ok(())
    }
}

impl SetBaud for HostPort {
    fn set_baud(&mut self, baud: u32) -> Result<(), LinkError> {
        let mut g = self.link.lock()?;
        if g.host_baud.is_some() {
            g.host_baud = Some(baud);
        }
        Ok(())
    }
}

/// `DelayNs` advancing the link's virtual time.
#[derive(Clone)]
pub struct LinkDelay {
    link: Link,
}

impl embedded_hal::delay::DelayNs for LinkDelay {
    fn delay_ns(&mut self, ns: u32) {
        let _ = self.link.advance(u64::from(ns).div_ceil(1000));
    }
}

/// Millisecond clock of the link's virtual time.
#[derive(Clone)]
pub struct LinkClock {
    link: Link,
}

impl Clock for LinkClock {
    fn now_ms(&mut self) -> u32 {
        (self.link.now_us() / 1000) as u32
    }
}
