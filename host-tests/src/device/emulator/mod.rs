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
//! * [`serve`]: real-time transports: pseudo-terminal and TCP (`pfe emulate`).

pub mod link;
pub mod serve;
pub mod source;
pub mod telegram;

pub use link::{HostPort, Link, LinkClock, LinkDelay, LinkError};
pub use serve::{serve_pty, serve_tcp, serve_tcp_with, RunLimits};
pub use source::{RangeSource, RoomSource, SourceKind, TaggedSource};

use std::collections::VecDeque;

use firmware::lms::command::{code as ccode, mode as cmode, PASSWORD};
use firmware::lms::frame::{Decoder, Event, ACK, HOST_ADDRESS, MAX_TELEGRAM, NAK};
use firmware::lms::reply::{code as rcode, status_offset, ConfigBlock};
use firmware::lms::types::{Baud, MeasuringMode, Unit, Variant};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Fault injection on the device's output, deterministic from [`EmulatorConfig::seed`].
/// Probabilities are per B0 telegram; at most one damaging fault hits one telegram.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Faults {
    /// Flip one bit of one byte.
    pub bit_flip: f64,
    /// Drop one byte.
    pub drop_byte: f64,
    /// Send one byte twice.
    pub duplicate_byte: f64,
    /// Cut the telegram short.
    pub truncate: f64,
    /// Insert 1–40 random bytes before the telegram (does not damage it).
    pub garbage: f64,
    /// After this many B0 telegrams, stay silent for `silence_ms` (streaming resumes after).
    pub silence_after_scans: Option<u32>,
    /// Length of the silence, ms.
    pub silence_ms: u32,
    /// After this many B0 telegrams, reset spontaneously (back to 9600, request mode, 0x90).
    pub reset_after_scans: Option<u32>,
    /// Answer this many of the next commands with NAK instead of ACK + reply.
    pub nak_commands: u32,
    /// Apply the damaging faults (flip, drop, duplicate, truncate) to replies as well.
    pub damage_replies: bool,
}

/// Emulator settings.
#[derive(Clone, Debug)]
pub struct EmulatorConfig {
    /// Baud at power-on (9600 on a real device).
    pub initial_baud: Baud,
    /// Variant at power-on.
    pub variant: Variant,
    /// Configuration block at power-on (unit, measuring mode, availability).
    pub config: ConfigBlock,
    /// Type string (BA reply).
    pub type_string: String,
    /// Status byte of every reply.
    pub status: u8,
    /// Delay from the end of a command to the ACK, µs.
    pub ack_delay_us: u64,
    /// Delay from the ACK to the reply, µs.
    pub reply_delay_us: u64,
    /// Time from a reset to the power-on message, µs.
    pub reset_time_us: u64,
    /// Seed of the fault injection and garbling.
    pub seed: u64,
    /// Faults to inject.
    pub faults: Faults,
    /// Built-in scan source (used by [`serve_tcp`] and `pfe emulate`).
    pub source: SourceKind,
    /// Command codes this device does not implement: answered `92` (incorrect command), as
    /// a variant or a simpler emulator might.
    pub unsupported: Vec<u8>,
    /// Baud rates this device cannot switch to: `20 4x` for them is answered `A0 01` and the
    /// device stays at its rate (an RS-232 LMS200 has no 500 000 Bd).
    pub refused_bauds: Vec<Baud>,
}

impl Default for EmulatorConfig {
    fn default() -> Self {
        Self {
            initial_baud: Baud::B9600,
            variant: Variant::A180_R050,
            config: ConfigBlock::default_mm(),
            type_string: "LMS200;30106".into(),
            status: 0x10,
            ack_delay_us: 1200,
            reply_delay_us: 2000,
            reset_time_us: 200_000,
            seed: 1,
            faults: Faults::default(),
            source: SourceKind::Room,
            unsupported: Vec::new(),
            refused_bauds: Vec::new(),
        }
    }
}

/// A scan the emulator sent.
#[derive(Clone, Debug, PartialEq)]
pub struct SentScan {
    /// Sequence number (0-based) of B0 telegrams sent.
    pub seq: u32,
    /// The value words sent.
    pub words: Vec<u16>,
    /// The ranges (mm) the source produced.
    pub ranges_mm: Vec<f32>,
    /// Unit and measuring mode in force.
    pub unit: Unit,
    /// Measuring mode in force.
    pub mode: MeasuringMode,
    /// True when a fault or a baud mismatch damaged it on the way.
    pub damaged: bool,
}

/// One byte on its way to the host.
#[derive(Clone, Copy, Debug)]
struct TxByte {
    at_us: u64,
    byte: u8,
    baud: u32,
    scan: Option<u32>,
}

/// Counters and logs of one emulator run.
#[derive(Clone, Debug, Default)]
pub struct EmulatorReport {
    /// Commands received with a good CRC (code bytes, in order).
    pub commands: Vec<u8>,
    /// B0 telegrams sent.
    pub scans: Vec<SentScan>,
    /// Host bytes dropped because the host's baud differed from the device's.
    pub garbled_in: u64,
    /// Device bytes garbled because the host's baud differed.
    pub garbled_out: u64,
    /// Host telegrams with a bad CRC (answered with NAK).
    pub bad_commands: u32,
    /// Device bytes sent.
    pub bytes_out: u64,
    /// Resets (commanded or injected).
    pub resets: u32,
    /// Replies damaged by [`Faults::damage_replies`].
    pub damaged_replies: u32,
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

    fn command(&mut self, now: u64, p: &[u8]) {
        let Some((&cmd, data)) = p.split_first() else {
            return;
        };
        self.report.commands.push(cmd);
        let ack_at = now + self.cfg.ack_delay_us;
        if self.nak_left > 0 {
            self.nak_left -= 1;
            self.emit(ack_at, &[NAK], None);
            return;
        }
        let t = self.emit(ack_at, &[ACK], None);
        let at = t + self.cfg.reply_delay_us;
        if self.cfg.unsupported.contains(&cmd) {
            self.reply(at, &[rcode::INCORRECT]);
            return;
        }
        match (cmd, data) {
            (ccode::MODE, [m, pw @ ..]) => {
                let m = *m;
                if m == cmode::INSTALL {
                    let ok = pw == PASSWORD.as_slice();
                    self.install = ok;
                    self.reply(at, &[rcode::MODE, if ok { 0 } else { 1 }]);
                    return;
                }
                self.install = false;
                if Baud::from_mode_code(m).is_some_and(|b| self.cfg.refused_bauds.contains(&b)) {
                    self.reply(at, &[rcode::MODE, 1]);
                    return;
                }
                let end = self.reply(at, &[rcode::MODE, 0]);
                if let Some(b) = Baud::from_mode_code(m) {
                    self.pending_baud = Some((end, b));
                } else if m == cmode::CONTINUOUS {
                    if !self.streaming {
                        self.streaming = true;
                        self.next_scan_us = end + 5000;
                    }
                } else if m == cmode::ON_REQUEST {
                    self.streaming = false;
                }
            }
            (ccode::REQUEST_VALUES, _) => {
                let t = self.make_b0();
                self.send_b0(at, t);
            }
            (ccode::STATUS, []) => {
                let b1 = self.b1();
                self.reply(at, &b1);
            }
            (ccode::ERRORS, []) => {
                self.reply(at, &[rcode::ERRORS]);
            }
            (ccode::TYPE, []) => {
                let mut p = vec![rcode::TYPE];
                p.extend(self.cfg.type_string.as_bytes());
                self.reply(at, &p);
            }
            (ccode::VARIANT, [a0, a1, r0, r1]) => {
                let v = Variant::new(
                    u16::from_le_bytes([*a0, *a1]),
                    u16::from_le_bytes([*r0, *r1]),
                );
                let ok = v.is_valid();
                if ok {
                    self.variant = v;
                }
                self.reply(at, &[rcode::VARIANT, u8::from(ok), *a0, *a1, *r0, *r1]);
            }
            (ccode::GET_CONFIG, []) => {
                let mut p = vec![rcode::CONFIG];
                p.extend(self.block.as_bytes());
                self.reply(at, &p);
            }
            (ccode::SET_CONFIG, block) => {
                let parsed = ConfigBlock::from_bytes(block);
                let ok = self.install && parsed.is_some();
                if let (true, Some(b)) = (ok, parsed) {
                    self.block = b;
                }
                let mut p = vec![rcode::CONFIG_SET, u8::from(ok)];
                p.extend(parsed.unwrap_or(self.block).as_bytes());
                self.reply(at, &p);
            }
            (ccode::RESET, []) => {
                self.reply(at, &[rcode::RESET_ACK]);
                self.reset(self.line_free_us);
            }
            _ => {
                self.reply(at, &[rcode::INCORRECT]);
            }
        }
    }

    /// Device reset at `t`: deaf for the reset time, then 9600 baud, request mode, 0x90.
    fn reset(&mut self, t: u64) {
        self.report.resets += 1;
        self.streaming = false;
        self.install = false;
        self.pending_baud = None;
        self.decoder.clear();
        self.reboot_at_us = Some(t + self.cfg.reset_time_us);
    }

    /// The operating mode B1 reports (payload index 8): `00` in installation mode, `24` while
    /// streaming, `25` (values on request, the power-on mode) otherwise.
    pub fn operating_mode(&self) -> u8 {
        if self.install {
            cmode::INSTALL
        } else if self.streaming {
            cmode::CONTINUOUS
        } else {
            cmode::ON_REQUEST
        }
    }

    /// The B1 payload (code + 152 data bytes) at S1's offsets (protocol notes §6).
    fn b1(&self) -> Vec<u8> {
        let mut p = vec![0u8; status_offset::PAYLOAD_LEN - 1];
        p[0] = rcode::STATUS;
        p[1..8].copy_from_slice(b"V02.10 ");
        p[status_offset::OPERATING_MODE] = self.operating_mode();
        p[status_offset::DEVICE_STATUS] = 0;
        p[10..18].copy_from_slice(b"07380000");
        // 18: variant type (0 = standard type 6); 124–130: PROM software version.
        p[18] = 0;
        p[124..131].copy_from_slice(b"V02.10 ");
        p[status_offset::MEASURING_MODE] = self.block.measuring_mode().0;
        p[status_offset::SCAN_ANGLE..status_offset::SCAN_ANGLE + 2]
            .copy_from_slice(&self.variant.angle_deg.to_le_bytes());
        p[status_offset::RESOLUTION..status_offset::RESOLUTION + 2]
            .copy_from_slice(&self.variant.resolution_cdeg.to_le_bytes());
        p[status_offset::BAUD..status_offset::BAUD + 2]
            .copy_from_slice(&self.baud.status_word().to_le_bytes());
        p[status_offset::ADDRESS] = 0;
        p[status_offset::UNIT] = self.block.unit().map_or(0, Unit::config_byte);
        p
    }

    /// Encodes range `mm` as a code for the current unit and mode.
    pub fn encode_range(mm: f32, unit: Unit, mode: MeasuringMode) -> u16 {
        let mask = mode.range_mask();
        if !mm.is_finite() || mm <= 0.0 {
            return mask;
        }
        let v = (mm / unit.mm_per_unit()).round();
        if v > f32::from(mode.max_valid()) {
            if mode.range_bits() >= 16 {
                mode.max_valid()
            } else {
                mask - 8
            }
        } else {
            v as u16
        }
    }

    fn make_b0(&mut self) -> (Vec<u8>, u32) {
        let n = self.variant.values();
        let step = self.variant.resolution_deg();
        let ranges = self.source.next_scan(n, self.variant.start_deg(), step);
        let unit = self.block.unit().unwrap_or(Unit::Cm);
        let mode = self.block.measuring_mode();
        let words: Vec<u16> = (0..n)
            .map(|i| Self::encode_range(ranges.get(i).copied().unwrap_or(f32::NAN), unit, mode))
            .collect();
        let seq = self.report.scans.len() as u32;
        let count = (n as u16 & 0x3FF) | (unit.count_bits() << 14);
        let mut p = vec![rcode::VALUES];
        p.extend(count.to_le_bytes());
        for w in &words {
            p.extend(w.to_le_bytes());
        }
        if self.block.realtime_index() {
            p.push(seq as u8);
        }
        p.push(self.cfg.status);
        let t = telegram::device_telegram(&p).unwrap_or_default();
        self.report.scans.push(SentScan {
            seq,
            words,
            ranges_mm: ranges,
            unit,
            mode,
            damaged: false,
        });
        (t, seq)
    }

    /// Applies at most one damaging fault to telegram `t`; true when it was damaged.
    fn damage(&mut self, t: &mut Vec<u8>) -> bool {
        let f = &self.cfg.faults;
        let (pf, pd, pu, pt) = (f.bit_flip, f.drop_byte, f.duplicate_byte, f.truncate);
        let r: f64 = self.rng.gen();
        let len = t.len();
        if len < 2 {
            return false;
        }
        if r < pf {
            let i = self.rng.gen_range(0..len);
            t[i] ^= 1 << self.rng.gen_range(0..8);
        } else if r < pf + pd {
            t.remove(self.rng.gen_range(0..len));
        } else if r < pf + pd + pu {
            let i = self.rng.gen_range(0..len);
            let b = t[i];
            t.insert(i, b);
        } else if r < pf + pd + pu + pt {
            t.truncate(self.rng.gen_range(1..len));
        } else {
            return false;
        }
        true
    }

    fn send_b0(&mut self, at: u64, (mut t, seq): (Vec<u8>, u32)) {
        if self.damage(&mut t) {
            if let Some(s) = self.report.scans.get_mut(seq as usize) {
                s.damaged = true;
            }
        }
        if self.rng.gen_bool(self.cfg.faults.garbage.clamp(0.0, 1.0)) {
            let n = self.rng.gen_range(1..=40);
            let g: Vec<u8> = (0..n).map(|_| self.rng.gen()).collect();
            self.emit(at, &g, None);
        }
        self.emit(at, &t, Some(seq));
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
