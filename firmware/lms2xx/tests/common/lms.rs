//! A scripted LMS200 on the far side of a mock UART, written from the protocol notes
//! (../shared/docs/lms200-protocol.md), not from the firmware's codec: its own CRC (§1), its own
//! telegrams, the replies of §4–§7. Time is the shared [`Time`]: each byte arrives one
//! character time (10 bits) after the previous one, at the rate the device sends at; bytes sent
//! at another rate than the host UART's are lost.

use std::collections::VecDeque;

use super::Time;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct E;
impl embedded_io::Error for E {
    fn kind(&self) -> embedded_io::ErrorKind {
        embedded_io::ErrorKind::Other
    }
}

/// The telegram CRC of §1 (one shift per byte, polynomial 0x8005, previous:current byte word).
pub fn crc16(data: &[u8]) -> u16 {
    let (mut crc, mut prev) = (0u16, 0u8);
    for &b in data {
        crc = if crc & 0x8000 != 0 {
            ((crc & 0x7FFF) << 1) ^ 0x8005
        } else {
            crc << 1
        };
        crc ^= u16::from_be_bytes([prev, b]);
        prev = b;
    }
    crc
}

/// `STX | 0x80 | LEN | payload | CRC` (device → host).
pub fn device_telegram(payload: &[u8]) -> Vec<u8> {
    let len = u16::try_from(payload.len()).unwrap_or(u16::MAX);
    let mut t = vec![0x02, 0x80];
    t.extend_from_slice(&len.to_le_bytes());
    t.extend_from_slice(payload);
    let crc = crc16(&t);
    t.extend_from_slice(&crc.to_le_bytes());
    t
}

/// B1 baud word (§6).
fn baud_word(bps: u32) -> u16 {
    match bps {
        9600 => 0x8067,
        19200 => 0x8033,
        38400 => 0x8019,
        _ => 0x8001,
    }
}

/// Reply status byte real devices send (§3).
pub const STATUS: u8 = 0x10;

pub struct Lms {
    time: Time,
    /// Rate the host UART is set to.
    pub host_bps: u32,
    /// Rate the device runs at.
    pub dev_bps: u32,
    /// Every `set_baud` of the host, in order.
    pub host_bauds: Vec<u32>,
    inbox: Vec<u8>,
    /// (arrival µs, byte, rate it was sent at).
    out: VecDeque<(u64, u8, u32)>,
    line_free_at: u64,
    /// Payloads of the host telegrams the device understood, in order.
    pub commands: Vec<Vec<u8>>,
    streaming: bool,
    install: bool,
    next_scan_at: u64,
    /// Scans emitted so far (1 = first).
    pub scans_sent: u32,
    /// Time between scans, µs (the line may make it longer).
    pub scan_period_us: u64,
    /// Scan angle and resolution (1/100°).
    pub variant: (u16, u16),
    /// The 34-byte configuration block (§5; byte 5 measuring mode, byte 6 unit).
    pub config: [u8; 34],
    /// Answer `31` (else `92`, incorrect command).
    pub answer_status: bool,
    /// Answer the next command with a power-on message `90` instead.
    pub power_on_next: bool,
    /// Scans (by number) sent with the restart bit (0x20) in their status byte.
    pub restart_scans: Vec<u32>,
    /// Scans (by number) replaced by a power-on message `90`: the device restarted, in
    /// request mode.
    pub power_on_scans: Vec<u32>,
    /// Bytes sent instead of the ACK and reply to command number `.0` (0 = first).
    pub replace_reply: Option<(usize, Vec<u8>)>,
    /// Unit bits (14–15 of the count word) of the scans, when not the configured unit's.
    pub scan_unit_bits: Option<u16>,
    /// Times (µs) at which the host polled `read_ready` and nothing had arrived, with its rate.
    pub idle_polls: Vec<(u64, u32)>,
    /// Unrequested telegrams (payloads) sent right after the scan of the given number.
    pub stray_after_scan: Vec<(u32, Vec<u8>)>,
}

impl Lms {
    /// A device at `dev_bps`, 180° at 0.5°, mm, measuring mode 0, in request mode.
    pub fn new(time: Time, dev_bps: u32) -> Self {
        let mut config = [0u8; 34];
        config[0] = 0x46;
        config[6] = 1;
        Self {
            time,
            host_bps: 9600,
            dev_bps,
            host_bauds: Vec::new(),
            inbox: Vec::new(),
            out: VecDeque::new(),
            line_free_at: 0,
            commands: Vec::new(),
            streaming: false,
            install: false,
            next_scan_at: 0,
            scans_sent: 0,
            scan_period_us: 1_000_000 * 2 / 75,
            variant: (180, 50),
            config,
            answer_status: true,
            power_on_next: false,
            restart_scans: Vec::new(),
            replace_reply: None,
            power_on_scans: Vec::new(),
            scan_unit_bits: None,
            idle_polls: Vec::new(),
            stray_after_scan: Vec::new(),
        }
    }

    fn now(&self) -> u64 {
        self.time.0.get()
    }

    /// Commands received with code `code` (first payload byte).
    pub fn sent(&self, code: u8) -> Vec<&Vec<u8>> {
        self.commands.iter().filter(|c| c[0] == code).collect()
    }

    fn values(&self) -> usize {
        usize::from(self.variant.0) * 100 / usize::from(self.variant.1) + 1
    }

    fn send(&mut self, bytes: &[u8], start: u64) {
        let byte_us = 10_000_000 / u64::from(self.dev_bps);
        let mut t = start.max(self.line_free_at);
        for &b in bytes {
            t += byte_us;
            self.out.push_back((t, b, self.dev_bps));
        }
        self.line_free_at = t;
    }

    fn reply(&mut self, payload: &[u8]) {
        let start = self.now() + 1000;
        self.send(&[0x06], start);
        let t = device_telegram(payload);
        self.send(&t, start);
    }

    /// Emits the scans due by now (continuous output, §7: values 1000 + i in the unit of
    /// config byte 6, count word bits 14–15 the unit).
    fn generate(&mut self) {
        while self.streaming && self.next_scan_at <= self.now() {
            self.scans_sent += 1;
            if self.power_on_scans.contains(&self.scans_sent) {
                self.streaming = false;
                let t = device_telegram(&[&[0x90][..], b"LMS200", &[STATUS]].concat());
                let at = self.next_scan_at;
                self.send(&t, at);
                return;
            }
            let n = self.values();
            let unit = self.scan_unit_bits.unwrap_or(u16::from(self.config[6])) << 14;
            let count = unit | u16::try_from(n).unwrap_or(0);
            let mut p = vec![0xB0];
            p.extend_from_slice(&count.to_le_bytes());
            for i in 0..n {
                p.extend_from_slice(&(1000 + i as u16).to_le_bytes());
            }
            let restart = self.restart_scans.contains(&self.scans_sent);
            p.push(if restart { STATUS | 0x20 } else { STATUS });
            let t = device_telegram(&p);
            let at = self.next_scan_at;
            self.send(&t, at);
            let n = self.scans_sent;
            for (_, payload) in self.stray_after_scan.clone().iter().filter(|s| s.0 == n) {
                let t = device_telegram(payload);
                self.send(&t, at);
            }
            self.next_scan_at = (at + self.scan_period_us).max(self.line_free_at);
        }
    }

    fn handle(&mut self, p: Vec<u8>) {
        self.commands.push(p.clone());
        if let Some((i, bytes)) = self.replace_reply.take() {
            if i + 1 == self.commands.len() {
                let start = self.now() + 1000;
                self.send(&bytes, start);
                return;
            }
            self.replace_reply = Some((i, bytes));
        }
        if std::mem::take(&mut self.power_on_next) {
            self.streaming = false;
            let mut r = vec![0x90];
            r.extend_from_slice(b"LMS200");
            r.push(STATUS);
            self.reply(&r);
            return;
        }
        let ok = |code: u8, data: &[u8]| {
            let mut r = vec![code];
            r.extend_from_slice(data);
            r.push(STATUS);
            r
        };
        match (p[0], p.get(1).copied()) {
            (0x20, Some(m)) => {
                let r = ok(0xA0, &[0]);
                self.reply(&r);
                match m {
                    0x00 => self.install = &p[2..] == b"SICK_LMS",
                    0x24 => {
                        self.streaming = true;
                        self.next_scan_at = self.line_free_at;
                    }
                    0x25 => {
                        self.streaming = false;
                        self.install = false;
                    }
                    0x40 => self.dev_bps = 38400,
                    0x41 => self.dev_bps = 19200,
                    0x42 => self.dev_bps = 9600,
                    0x48 => self.dev_bps = 500_000,
                    _ => {}
                }
            }
            (0x31, _) if self.answer_status => {
                let mut d = vec![0u8; 152];
                let at = |i: usize| i - 1; // payload offset → data offset
                d[at(1)..at(8)].copy_from_slice(b"V02.10 ");
                d[at(8)] = if self.streaming { 0x24 } else { 0x25 };
                d[at(102)] = self.config[5];
                d[at(107)..at(109)].copy_from_slice(&self.variant.0.to_le_bytes());
                d[at(109)..at(111)].copy_from_slice(&self.variant.1.to_le_bytes());
                d[at(116)..at(118)].copy_from_slice(&baud_word(self.dev_bps).to_le_bytes());
                d[at(122)] = self.config[6];
                let r = ok(0xB1, &d);
                self.reply(&r);
            }
            (0x3A, _) => {
                let r = ok(0xBA, b"LMS200;30106");
                self.reply(&r);
            }
            (0x74, _) => {
                let c = self.config;
                let r = ok(0xF4, &c);
                self.reply(&r);
            }
            (0x77, _) if self.install && p.len() == 35 => {
                self.config.copy_from_slice(&p[1..]);
                let mut d = vec![1];
                d.extend_from_slice(&p[1..]);
                let r = ok(0xF7, &d);
                self.reply(&r);
            }
            (0x10, None) => {
                // Reset (§4): `91` at the current rate, then the device restarts at 9600 and
                // sends the power-on message `90` + text.
                let r = ok(0x91, &[]);
                self.reply(&r);
                self.streaming = false;
                self.install = false;
                self.dev_bps = 9600;
                let r = ok(0x90, b"LMS200");
                let t = device_telegram(&r);
                let start = self.now() + 1000;
                self.send(&t, start);
            }
            (0x3B, _) if p.len() == 5 => {
                self.variant = (
                    u16::from_le_bytes([p[1], p[2]]),
                    u16::from_le_bytes([p[3], p[4]]),
                );
                // BB 01 aa aa rr rr (§4).
                let r = ok(0xBB, &[&[1u8][..], &p[1..]].concat());
                self.reply(&r);
            }
            _ => {
                let r = ok(0x92, &[]);
                self.reply(&r);
            }
        }
    }

    fn take_telegrams(&mut self) {
        loop {
            while self.inbox.first().is_some_and(|&b| b != 0x02) {
                self.inbox.remove(0);
            }
            if self.inbox.len() < 4 {
                return;
            }
            let len = usize::from(u16::from_le_bytes([self.inbox[2], self.inbox[3]]));
            let total = len + 6;
            if self.inbox.len() < total {
                return;
            }
            let t: Vec<u8> = self.inbox.drain(..total).collect();
            let crc = u16::from_le_bytes([t[total - 2], t[total - 1]]);
            if t[1] != 0x00 || crc16(&t[..total - 2]) != crc {
                let start = self.now() + 1000;
                self.send(&[0x15], start);
                continue;
            }
            self.handle(t[4..total - 2].to_vec());
        }
    }

    /// Drops bytes that arrived at another rate than the host's; true when one is readable.
    fn ready(&mut self) -> bool {
        self.generate();
        let now = self.now();
        while let Some(&(t, _, bps)) = self.out.front() {
            if t > now {
                return false;
            }
            if bps == self.host_bps {
                return true;
            }
            self.out.pop_front();
        }
        false
    }
}

impl embedded_io::ErrorType for Lms {
    type Error = E;
}
impl embedded_io::Read for Lms {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, E> {
        let mut n = 0;
        while n < buf.len() && self.ready() {
            if let Some((_, b, _)) = self.out.pop_front() {
                buf[n] = b;
                n += 1;
            }
        }
        Ok(n)
    }
}
impl embedded_io::ReadReady for Lms {
    fn read_ready(&mut self) -> Result<bool, E> {
        let r = self.ready();
        if !r {
            let now = self.now();
            self.idle_polls.push((now, self.host_bps));
        }
        Ok(r)
    }
}
impl embedded_io::Write for Lms {
    fn write(&mut self, b: &[u8]) -> Result<usize, E> {
        // Bytes at another rate than the device's are garbage to it.
        if self.host_bps == self.dev_bps {
            self.inbox.extend_from_slice(b);
            self.take_telegrams();
        }
        Ok(b.len())
    }
    fn flush(&mut self) -> Result<(), E> {
        Ok(())
    }
}
impl lms2xx::driver::SetBaud for Lms {
    fn set_baud(&mut self, bps: u32) -> Result<(), E> {
        self.host_bps = bps;
        self.host_bauds.push(bps);
        Ok(())
    }
}
