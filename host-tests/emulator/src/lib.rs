//! LMS200 device emulator: a state machine fed host bytes that produces timed device bytes.
//!
//! * [`Emulator`]: the device (ACK before every reply, status byte 0x10, baud switch applied
//!   after the reply is sent at the old rate, variants, units via installation mode + `77`,
//!   measuring modes, request mode and `30` single scans, continuous B0 output at the rate the
//!   baud and variant allow, reset `10`, incorrect command `92`), with deterministic fault
//!   injection ([`Faults`]).
//! * [`RangeSource`]: where the ranges come from ([`RoomSource`], [`TaggedSource`], or the scene
//!   simulator).
//! * [`link`]: an in-process byte link with virtual time, usable by the firmware driver through
//!   `embedded-io` (host baud modelled, bytes garbled when it differs from the device's).
//! * `serve` (cargo feature `serve`, default): real-time transports: pseudo-terminal and TCP
//!   (`pfe emulate`).

#![forbid(unsafe_code)]

pub mod link;
#[cfg(feature = "serve")]
pub mod serve;
pub mod source;
pub mod telegram;

mod commands;
mod config;
mod report;
mod scans;

pub use config::{EmulatorConfig, Faults};
pub use link::{HostPort, Link, LinkClock, LinkDelay, LinkError};
pub use report::{EmulatorReport, SentScan};
#[cfg(feature = "serve")]
pub use serve::{serve_pty, serve_tcp, serve_tcp_with, RunLimits};
pub use source::{RangeSource, RoomSource, SourceKind, TaggedSource};

use std::collections::VecDeque;

use lms2xx::codec::frame::{Decoder, Event, HOST_ADDRESS, MAX_TELEGRAM, NAK};
use lms2xx::codec::reply::{code as rcode, ConfigBlock};
use lms2xx::codec::types::{Baud, Variant};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// One byte on its way to the host.
#[derive(Clone, Copy, Debug)]
struct TxByte {
    at_us: u64,
    byte: u8,
    baud: u32,
    scan: Option<u32>,
}

/// The emulated LMS200.
pub struct Emulator {
    cfg: EmulatorConfig,
    source: Box<dyn RangeSource>,
    decoder: Decoder<MAX_TELEGRAM>,
    baud: Baud,
    pending_baud: Option<(u64, Baud)>,
    install: bool,
    streaming: bool,
    next_scan_us: u64,
    variant: Variant,
    block: ConfigBlock,
    tx: VecDeque<TxByte>,
    line_free_us: u64,
    silent_until_us: u64,
    reboot_at_us: Option<u64>,
    rng: ChaCha8Rng,
    nak_left: u32,
    now_us: u64,
    hold: bool,
    report: EmulatorReport,
}

fn byte_time_us(baud: u32) -> u64 {
    // 10 bit times per byte (8N1), rounded up.
    (10_000_000u64).div_ceil(u64::from(baud.max(1)))
}

impl Emulator {
    /// A device at power-on with `cfg`, drawing ranges from `source`.
    pub fn new(cfg: EmulatorConfig, source: Box<dyn RangeSource>) -> Self {
        Self {
            source,
            decoder: Decoder::with_address(HOST_ADDRESS),
            baud: cfg.initial_baud,
            pending_baud: None,
            install: false,
            streaming: false,
            next_scan_us: 0,
            variant: cfg.variant,
            block: cfg.config,
            tx: VecDeque::new(),
            line_free_us: 0,
            silent_until_us: 0,
            reboot_at_us: None,
            rng: ChaCha8Rng::seed_from_u64(cfg.seed),
            nak_left: cfg.faults.nak_commands,
            now_us: 0,
            hold: false,
            report: EmulatorReport::default(),
            cfg,
        }
    }

    /// A device with the built-in source of `cfg.source`.
    pub fn from_config(cfg: EmulatorConfig) -> Self {
        let src = cfg.source.build();
        Self::new(cfg, src)
    }

    /// Current device baud.
    pub fn baud(&self) -> Baud {
        self.baud
    }
    /// True while streaming B0 continuously.
    pub fn is_streaming(&self) -> bool {
        self.streaming
    }
    /// Current variant.
    pub fn variant(&self) -> Variant {
        self.variant
    }
    /// Current configuration block.
    pub fn config_block(&self) -> ConfigBlock {
        self.block
    }
    /// What happened so far.
    pub fn report(&self) -> &EmulatorReport {
        &self.report
    }
    /// Mutable fault settings (e.g. to start injecting mid-run).
    pub fn faults_mut(&mut self) -> &mut Faults {
        &mut self.cfg.faults
    }
    /// Makes the next `n` commands be answered with NAK.
    pub fn nak_next(&mut self, n: u32) {
        self.nak_left = n;
    }
    /// While `hold` is set, continuous output skips scans (a congested transport: the device
    /// then sends the newest complete scan once the line is free).
    pub fn set_hold(&mut self, hold: bool) {
        self.hold = hold;
    }
    /// Bytes queued and not yet taken by the host.
    pub fn queued(&self) -> usize {
        self.tx.len()
    }
    /// Earliest time a byte becomes available to the host, if any is queued.
    pub fn next_byte_at(&self) -> Option<u64> {
        self.tx.front().map(|b| b.at_us)
    }

    /// Time one B0 telegram takes on the line at the current baud, µs.
    pub fn scan_period_us(&self) -> u64 {
        let n = self.variant.values();
        let extra = usize::from(self.block.realtime_index());
        let bytes = (2 * n + 10 + extra) as u64;
        let line = bytes * byte_time_us(self.baud.bps());
        let mirror = (1e6 / f64::from(self.variant.max_rate_hz())) as u64;
        line.max(mirror)
    }

    fn apply_pending(&mut self, t: u64) {
        if let Some((at, b)) = self.pending_baud {
            if t >= at {
                self.baud = b;
                self.pending_baud = None;
                self.decoder.clear();
            }
        }
    }

    /// Queues `bytes` on the line no earlier than `at`; returns the end time.
    fn emit(&mut self, at: u64, bytes: &[u8], scan: Option<u32>) -> u64 {
        let mut t = at.max(self.line_free_us);
        self.apply_pending(t);
        let bt = byte_time_us(self.baud.bps());
        for &b in bytes {
            t += bt;
            self.tx.push_back(TxByte {
                at_us: t,
                byte: b,
                baud: self.baud.bps(),
                scan,
            });
        }
        self.report.bytes_out += bytes.len() as u64;
        self.line_free_us = t;
        t
    }

    fn reply(&mut self, at: u64, payload: &[u8]) -> u64 {
        let mut p = payload.to_vec();
        p.push(self.cfg.status);
        let Some(mut t) = telegram::device_telegram(&p) else {
            return at;
        };
        if self.cfg.faults.damage_replies && self.damage(&mut t) {
            self.report.damaged_replies += 1;
        }
        self.emit(at, &t, None)
    }

    /// Host bytes arrive at `now_us`. `host_baud` is the host's line speed (`None`: always the
    /// device's, as over TCP).
    pub fn receive(&mut self, now_us: u64, host_baud: Option<u32>, bytes: &[u8]) {
        self.advance(now_us);
        if self.reboot_at_us.is_some() {
            return; // rebooting: deaf
        }
        if host_baud.is_some_and(|b| b != self.baud.bps()) {
            self.report.garbled_in += bytes.len() as u64;
            self.decoder.clear();
            return;
        }
        let mut rest = bytes;
        loop {
            let crc_before = self.decoder.stats().crc_errors;
            let (used, ev) = self.decoder.feed(rest);
            let payload = match ev {
                Some(Event::Telegram(t)) => Some(t.payload().to_vec()),
                _ => None,
            };
            rest = rest.get(used..).unwrap_or(&[]);
            if self.decoder.stats().crc_errors > crc_before {
                self.report.bad_commands += 1;
                let at = now_us + self.cfg.ack_delay_us;
                self.emit(at, &[NAK], None);
            }
            match payload {
                Some(p) => self.command(now_us, &p),
                None if rest.is_empty() => break,
                None => {}
            }
        }
    }

    /// Runs the device up to `now_us`: baud switches, reboots, continuous output, faults.
    pub fn advance(&mut self, now_us: u64) {
        self.now_us = self.now_us.max(now_us);
        self.apply_pending(now_us);
        if let Some(at) = self.reboot_at_us {
            if now_us < at {
                return;
            }
            self.reboot_at_us = None;
            self.baud = Baud::B9600;
            self.decoder.clear();
            let mut p = vec![rcode::POWER_ON];
            p.extend(self.cfg.type_string.as_bytes());
            self.reply(at, &p);
        }
        while self.streaming && self.next_scan_us <= now_us {
            let at = self.next_scan_us;
            let period = self.scan_period_us();
            self.next_scan_us = at + period;
            if self.hold || at < self.silent_until_us || self.line_free_us > at + period {
                continue; // silent, or the line is still busy: this scan is skipped
            }
            let sent = self.report.scans.len() as u32;
            if self.cfg.faults.reset_after_scans == Some(sent) {
                self.cfg.faults.reset_after_scans = None;
                self.reset(at);
                return;
            }
            if self.cfg.faults.silence_after_scans == Some(sent) {
                self.cfg.faults.silence_after_scans = None;
                self.silent_until_us = at + u64::from(self.cfg.faults.silence_ms) * 1000;
                continue;
            }
            let t = self.make_b0();
            self.send_b0(at, t);
        }
    }

    /// Moves the bytes due by `now_us` into `out`. Bytes sent at a baud other than `host_baud`
    /// arrive garbled (and mark their scan damaged).
    pub fn take_ready(&mut self, now_us: u64, host_baud: Option<u32>, out: &mut Vec<u8>) {
        self.advance(now_us);
        while self.tx.front().is_some_and(|b| b.at_us <= now_us) {
            let Some(b) = self.tx.pop_front() else { break };
            if host_baud.is_some_and(|h| h != b.baud) {
                self.report.garbled_out += 1;
                if let Some(s) = b.scan.and_then(|s| self.report.scans.get_mut(s as usize)) {
                    s.damaged = true;
                }
                // A receiver at the wrong rate sees fewer or more bytes of junk.
                if self.rng.gen_bool(0.7) {
                    out.push(self.rng.gen());
                }
            } else {
                out.push(b.byte);
            }
        }
    }
}
