//! Fuzz target `lms_driver`: the LMS driver's state machine against arbitrary device bytes
//! and timing.
//!
//! Input layout: 9 setting bytes, then a script the mock UART consumes, one step per
//! `read_ready` that finds its queue empty:
//!
//! | byte | meaning |
//! |------|---------|
//! | 0 | driver baud (`& 3`), variant (`>> 2 & 7`, 5–7 invalid), unit (`>> 5 & 3`) |
//! | 1 | reply timeout, ms |
//! | 2 | configuration timeout, 4 ms units |
//! | 3 | tries (`& 3`), re-inits per call (`>> 2 & 3`), measuring mode `>> 5` if bit 4 |
//! | 4 | silence timeout, 8 ms units |
//! | 5 | poll interval, 16 µs units |
//! | 6 | baud-switch wait, ms |
//! | 7 | clock origin: `b × 4` ms before the `u32` wrap |
//! | 8 | emulator's baud (`& 3`); bit 2: it refuses 500 000 Bd; bit 3: it answers `3A`/`31` with `92` |
//!
//! Script steps (`c >> 6`): 0 nothing ready, time += `c & 63` ms; 1 the next `(c & 63) + 1`
//! script bytes arrive raw; 2 a device telegram with a good CRC whose payload is the next
//! `((c & 63) << 8 | next byte)` script bytes; 3 time += `c & 63` ms, then whatever the
//! [`Emulator`] (fed everything the driver wrote) sends by then arrives. When the script
//! ends the line goes quiet for good.
//!
//! Checks: no panic; every call returns, and waits on a quiet line (time in which no byte
//! arrived: script pauses, delays, transmission, and a millisecond per look once the script
//! is spent) no longer than its budget: the sum of the timeouts it may wait for (every
//! command, try and re-initialisation, see [`budget_ms`]) plus one script step of overshoot
//! per wait. A call that ignored its timeouts would run past the budget, or forever (a poll
//! cap turns that into a failed assertion). Time while bytes arrive is not counted: a wait
//! checks its timeout when the line is quiet, and the script's bytes are finite.

use std::cell::RefCell;
use std::collections::VecDeque;
use std::convert::Infallible;
use std::rc::Rc;

use lms2xx::codec::types::{Baud, MeasuringMode, Unit, Variant};

use lms200_emulator::telegram::device_telegram;
use lms200_emulator::{Emulator, EmulatorConfig};
use lms2xx::driver::{Clock, Config, Counters, Driver, Error, ScanData, SetBaud};

/// Setting bytes before the script.
pub const SETTINGS: usize = 9;
/// Polls of a quiet line after which a call counts as hung.
const POLL_CAP: u64 = 5_000_000;

pub(crate) struct Line {
    script: VecDeque<u8>,
    rx: VecDeque<u8>,
    now_ns: u64,
    /// Time during which nothing arrived (the time a wait's timeout must bound).
    quiet_ns: u64,
    origin_ms: u32,
    host_baud: u32,
    emu: Emulator,
    polls: u64,
}

impl Line {
    fn now_us(&self) -> u64 {
        self.now_ns / 1000
    }

    fn quiet(&mut self, ns: u64) {
        self.now_ns += ns;
        self.quiet_ns += ns;
    }

    fn step(&mut self) {
        let Some(c) = self.script.pop_front() else {
            // A quiet line for good: a millisecond per look, so a wait ends in few polls.
            self.quiet(1_000_000);
            return;
        };
        let arg = usize::from(c & 63);
        match c >> 6 {
            0 => self.quiet(arg as u64 * 1_000_000),
            1 => {
                let n = (arg + 1).min(self.script.len());
                self.rx.extend(self.script.drain(..n));
            }
            2 => {
                let lo = self.script.pop_front().unwrap_or(0);
                let len = (arg << 8 | usize::from(lo)).min(self.script.len());
                let payload: Vec<u8> = self.script.drain(..len).collect();
                if let Some(t) = device_telegram(&payload) {
                    self.rx.extend(t);
                }
            }
            _ => {
                let step = arg as u64 * 1_000_000;
                let mut out = Vec::new();
                let (now, baud) = (self.now_us() + step / 1000, self.host_baud);
                self.emu.take_ready(now, Some(baud), &mut out);
                if out.is_empty() {
                    self.quiet(step);
                } else {
                    self.now_ns += step;
                }
                self.rx.extend(out);
            }
        }
    }
}

/// The mock UART, delay and clock over one scripted line.
#[derive(Clone)]
pub struct Mock(Rc<RefCell<Line>>);

impl embedded_io::ErrorType for Mock {
    type Error = Infallible;
}

impl embedded_io::ReadReady for Mock {
    fn read_ready(&mut self) -> Result<bool, Infallible> {
        let mut l = self.0.borrow_mut();
        l.polls += 1;
        assert!(l.polls < POLL_CAP, "the driver polls a quiet line forever");
        if l.rx.is_empty() {
            l.step();
        }
        Ok(!l.rx.is_empty())
    }
}

impl embedded_io::Read for Mock {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Infallible> {
        let mut l = self.0.borrow_mut();
        let n = buf.len().min(l.rx.len());
        for (d, s) in buf.iter_mut().zip(l.rx.drain(..n)) {
            *d = s;
        }
        Ok(n)
    }
}

impl embedded_io::Write for Mock {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Infallible> {
        let mut l = self.0.borrow_mut();
        let ns = 10_000_000_000 / u64::from(l.host_baud.max(1)) * buf.len() as u64;
        l.quiet(ns);
        let (now, baud) = (l.now_us(), l.host_baud);
        l.emu.receive(now, Some(baud), buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
}

impl SetBaud for Mock {
    fn set_baud(&mut self, baud: u32) -> Result<(), Infallible> {
        self.0.borrow_mut().host_baud = baud;
        Ok(())
    }
}

impl embedded_hal::delay::DelayNs for Mock {
    fn delay_ns(&mut self, ns: u32) {
        self.0.borrow_mut().quiet(u64::from(ns));
    }
}

impl Clock for Mock {
    fn now_ms(&mut self) -> u32 {
        let mut l = self.0.borrow_mut();
        l.polls += 1;
        assert!(l.polls < POLL_CAP, "the driver reads the clock forever");
        l.origin_ms.wrapping_add((l.now_ns / 1_000_000) as u32)
    }
}

/// The driver settings of the setting bytes `s`.
pub fn config(s: &[u8; SETTINGS]) -> Config {
    let baud = Baud::ALL[usize::from(s[0] & 3)];
    let variant = Variant::VALID
        .get(usize::from(s[0] >> 2 & 7))
        .copied()
        .unwrap_or(Variant::new(90, 33));
    let unit = match s[0] >> 5 & 3 {
        0 => Unit::Cm,
        1 => Unit::Mm,
        _ => Unit::Dm,
    };
    let mut c = Config::default()
        .with_baud(baud)
        .with_variant(variant)
        .with_unit(unit)
        .with_silence_timeout_ms(u32::from(s[4]) * 8);
    if s[3] & 0x10 != 0 {
        c = c.with_measuring_mode(MeasuringMode(s[3] >> 5));
    }
    c.reply_timeout_ms = u32::from(s[1]);
    c.config_timeout_ms = u32::from(s[2]) * 4;
    c.tries = s[3] & 3;
    c.max_reinits_per_call = s[3] >> 2 & 3;
    c.poll_interval_us = u32::from(s[5]) * 16;
    c.baud_switch_wait_ms = u32::from(s[6]);
    c
}

/// Most script-step overshoot past one wait's timeout, ms (one step of up to 63 ms, one
/// idle, one telegram's transmission).
const OVERSHOOT_MS: u64 = 64 + 2;

/// Line time of the longest command the driver sends (48 bytes with its framing, 10 bits a
/// byte) at the slowest rate, 9600 Bd, ms: the mock UART's writes take their line time on the
/// script's clock, before the wait for the reply starts.
const SEND_MS: u64 = 48 * 10 * 1000 / 9600;

/// Time budget of the driver calls under `c`, ms: `(init, next_scan, one command)`.
pub fn budget_ms(c: &Config) -> (u64, u64, u64) {
    let tries = u64::from(c.tries.max(1));
    let wait = u64::from(c.reply_timeout_ms.max(c.config_timeout_ms)) + SEND_MS + OVERSHOOT_MS;
    let command = tries * wait;
    // Probe: every rate (≤ 4 distinct) `tries` times with one try each; then at most 12
    // commands (baud switch and its check, type, status, configuration, variant, installation
    // mode, 77, request mode twice, continuous) and the wait after a baud switch.
    let init = 4 * command + 12 * command + u64::from(c.baud_switch_wait_ms) + OVERSHOOT_MS;
    // Silence before each re-initialisation: the timeout or two 401-value telegrams at 9600 Bd.
    let silence = u64::from(c.silence_timeout_ms).max(1_700) + OVERSHOOT_MS;
    let reinits = u64::from(c.max_reinits_per_call) + 1;
    let next_scan = init + reinits * (silence + init);
    (init, next_scan, command)
}

/// One driver call's outcome, as compared between the blocking and the async driver.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// The call failed.
    Failed(Error<Infallible>),
    /// The call ended without a scan (`init`, `stop`, `reset_device`, an empty `poll`).
    Done,
    /// A scan: its sequence number, driver time, value count and first value.
    Scan(u32, u32, usize, u16),
}

/// A driver call the script chooses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Call {
    /// `init`.
    Init,
    /// `stop`.
    Stop,
    /// `reset_device`.
    ResetDevice,
    /// `poll` (the blocking driver only).
    Poll,
    /// `next_scan`.
    NextScan,
}

/// A driver under test: makes `call` and reports its counters.
pub trait Calls {
    /// Makes the call.
    fn call(&mut self, c: Call) -> Outcome;
    /// The driver's counters.
    fn counters(&self) -> Counters;
}

/// The outcome of a scan, after the checks every delivered scan must pass.
pub fn scan_outcome(s: &ScanData) -> Outcome {
    assert!(s.len() <= lms2xx::driver::MAX_VALUES);
    assert_eq!(s.codes().len(), s.len());
    Outcome::Scan(
        s.seq,
        s.time_ms,
        s.len(),
        s.codes().first().copied().unwrap_or(0),
    )
}

fn done(r: Result<(), Error<Infallible>>) -> Outcome {
    match r {
        Ok(()) => Outcome::Done,
        Err(e) => Outcome::Failed(e),
    }
}

struct Blocking(Driver<Mock, Mock, Mock>);

impl Calls for Blocking {
    fn call(&mut self, c: Call) -> Outcome {
        match c {
            Call::Init => done(self.0.init()),
            Call::Stop => done(self.0.stop()),
            Call::ResetDevice => done(self.0.reset_device()),
            Call::Poll => match self.0.poll() {
                Ok(Some(s)) => scan_outcome(s),
                Ok(None) => Outcome::Done,
                Err(e) => Outcome::Failed(e),
            },
            Call::NextScan => match self.0.next_scan() {
                Ok(s) => scan_outcome(s),
                Err(e) => Outcome::Failed(e),
            },
        }
    }
    fn counters(&self) -> Counters {
        self.0.counters()
    }
}

/// What a session did: every call with its outcome, and the counters at the end.
#[derive(Debug, PartialEq, Eq)]
pub struct Session {
    /// Per call: what it was and how it ended.
    pub calls: Vec<(Call, Outcome)>,
    /// The driver's counters after the last call.
    pub counters: Counters,
}

/// Runs a driver made by `make` (from the mock UART, delay and clock, and the settings)
/// through the calls chosen by the script's bytes until the script is spent; checks every
/// call's time budget. With `poll` false a `poll` is a `next_scan`.
pub fn session<D: Calls>(
    data: &[u8],
    poll: bool,
    make: impl FnOnce(Mock, Config) -> D,
) -> Option<Session> {
    let (settings, script) = data.split_first_chunk::<SETTINGS>()?;
    let cfg = config(settings);
    let s8 = settings[8];
    let mut emu_cfg = EmulatorConfig {
        initial_baud: Baud::ALL[usize::from(s8 & 3)],
        ..EmulatorConfig::default()
    };
    if s8 & 4 != 0 {
        emu_cfg.refused_bauds = vec![Baud::B500000];
    }
    if s8 & 8 != 0 {
        emu_cfg.unsupported = vec![0x3A, 0x31];
    }
    let line = Rc::new(RefCell::new(Line {
        script: script.iter().copied().collect(),
        rx: VecDeque::new(),
        now_ns: 0,
        quiet_ns: 0,
        origin_ms: 0u32.wrapping_sub(u32::from(settings[7]) * 4),
        host_baud: 9600,
        emu: Emulator::from_config(emu_cfg),
        polls: 0,
    }));
    let mut lms = make(Mock(line.clone()), cfg);
    let (init, next_scan, command) = budget_ms(&cfg);
    let mut calls = Vec::new();
    let mut scans = 0;
    let mut op = 0usize;
    // Each round consumes script bytes or ends (a quiet line after the script).
    loop {
        let spent_before = line.borrow().script.is_empty();
        let t0 = line.borrow().quiet_ns;
        let sel = line.borrow().script.front().copied().unwrap_or(0);
        op += 1;
        let (call, budget) = match (sel as usize + op) % 8 {
            0 => (Call::Init, init),
            1 => (Call::Stop, command),
            2 => (Call::ResetDevice, command),
            3 if poll => (Call::Poll, OVERSHOOT_MS),
            _ => (Call::NextScan, next_scan),
        };
        let outcome = lms.call(call);
        if matches!(outcome, Outcome::Scan(..)) {
            scans += 1;
        }
        calls.push((call, outcome));
        let l = line.borrow();
        let took_ms = (l.quiet_ns - t0) / 1_000_000;
        assert!(
            took_ms <= budget,
            "{call:?} waited {took_ms} ms on a quiet line, budget {budget} ms ({cfg:?})"
        );
        let c = lms.counters();
        assert!(c.scans as usize >= scans);
        if spent_before && l.script.is_empty() {
            break;
        }
        if op > 4096 {
            break;
        }
    }
    Some(Session {
        counters: lms.counters(),
        calls,
    })
}

/// Runs the blocking driver's calls, chosen by the script's bytes, until the script is spent;
/// returns the number of scans delivered.
pub fn lms_driver(data: &[u8]) -> usize {
    let Some(s) = session(data, true, |m, cfg| {
        Blocking(Driver::new(m.clone(), m.clone(), m, cfg))
    }) else {
        return 0;
    };
    s.calls
        .iter()
        .filter(|(_, o)| matches!(o, Outcome::Scan(..)))
        .count()
}

/// The blocking driver's session on `data` with `poll` calls made `next_scan` (the
/// async driver has no `poll`), for comparison.
pub fn blocking_session_without_poll(data: &[u8]) -> Option<Session> {
    session(data, false, |m, cfg| {
        Blocking(Driver::new(m.clone(), m.clone(), m, cfg))
    })
}

/// Seed inputs: `(name, bytes)`. Sessions where the emulator answers everything (a device at
/// 9600 Bd switched to 38 400, one refusing 500 000 Bd, one without `3A`/`31`, one with the
/// clock about to wrap), the protocol `vectors` as raw replies, and a quiet line.
pub fn seeds(vectors: &[Vec<u8>]) -> Vec<(String, Vec<u8>)> {
    // Settings: driver baud, variant (index 1: 180° at 0.5°) and unit mm; timeouts; tries 3,
    // 2 re-inits; silence 1000 ms; poll 496 µs; 250 ms baud-switch wait; clock origin; device.
    let settings = |baud: u8, origin: u8, device: u8| -> Vec<u8> {
        vec![
            baud | 1 << 2 | 1 << 5,
            200,
            250,
            3 | 2 << 2,
            125,
            31,
            250,
            origin,
            device,
        ]
    };
    let emulator = |steps: usize| vec![0xC0 | 5u8; steps];
    let mut out = vec![
        (
            "emulator-38400".to_string(),
            [settings(2, 0, 0), emulator(600)].concat(),
        ),
        (
            "emulator-500k-refused".to_string(),
            [settings(3, 0, 4), emulator(600)].concat(),
        ),
        (
            "emulator-no-type-status".to_string(),
            [settings(2, 0, 8), emulator(600)].concat(),
        ),
        (
            "emulator-clock-wraps".to_string(),
            [settings(2, 5, 0), emulator(600)].concat(),
        ),
        ("quiet-line".to_string(), settings(0, 0, 0)),
    ];
    let mut raw = settings(0, 0, 0);
    for v in vectors.iter().filter(|v| v.get(1) == Some(&0x80)) {
        for chunk in v.chunks(64) {
            raw.push(0x40 | (chunk.len() as u8 - 1));
            raw.extend_from_slice(chunk);
            raw.push(0x02);
        }
    }
    out.push(("vectors-raw".to_string(), raw));
    out
}
