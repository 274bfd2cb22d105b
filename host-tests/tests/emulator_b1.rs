//! The emulator's B1 status reply, field by field at the offsets of the protocol notes §6
//! (written out here, not taken from the firmware's `status_offset`), after each command that
//! changes a field: operating mode (8), measuring mode (102), scan angle (107–108),
//! resolution (109–110), baud word (116–117), unit (122).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: a panic fails the test

use lms200_emulator::{Emulator, EmulatorConfig};
use lms2xx::codec::frame::{encode_telegram, Decoder, Event, MAX_TELEGRAM};
use lms2xx::codec::reply::ConfigBlock;
use lms2xx::codec::types::{MeasuringMode, Unit};

const OPERATING_MODE: usize = 8;
const DEVICE_STATUS: usize = 9;
const VARIANT_TYPE: usize = 18;
const MEASURING_MODE: usize = 102;
const SCAN_ANGLE: usize = 107;
const RESOLUTION: usize = 109;
const BAUD: usize = 116;
const PERMANENT_BAUD: usize = 119;
const ADDRESS: usize = 120;
const UNIT: usize = 122;

/// An emulator driven in virtual time.
struct Bench {
    emu: Emulator,
    now: u64,
    dec: Decoder<MAX_TELEGRAM>,
}

impl Bench {
    fn new() -> Self {
        let mut b = Self {
            emu: Emulator::from_config(EmulatorConfig::default()),
            now: 0,
            dec: Decoder::new(),
        };
        // Past the power-on message.
        b.payloads(1_000_000);
        b
    }

    /// Device payloads sent within the next `us` microseconds.
    fn payloads(&mut self, us: u64) -> Vec<Vec<u8>> {
        let mut out = Vec::new();
        let end = self.now + us;
        while self.now < end {
            self.now += 1000;
            self.emu.take_ready(self.now, None, &mut out);
        }
        let mut got = Vec::new();
        let mut rest = &out[..];
        loop {
            let (u, ev) = self.dec.feed(rest);
            rest = &rest[u..];
            match ev {
                Some(Event::Telegram(t)) => got.push(t.payload().to_vec()),
                Some(_) => {}
                None => return got,
            }
        }
    }

    /// Sends `payload` and returns the reply to it (the first payload with `reply_code`).
    fn command(&mut self, payload: &[u8], reply_code: u8) -> Vec<u8> {
        let mut buf = [0u8; 64];
        let n = encode_telegram(0x00, payload, &mut buf).unwrap();
        self.emu.receive(self.now, None, &buf[..n]);
        self.payloads(2_000_000)
            .into_iter()
            .find(|p| p.first() == Some(&reply_code))
            .unwrap_or_else(|| panic!("no {reply_code:02X} reply to {payload:02X?}"))
    }

    fn b1(&mut self) -> Vec<u8> {
        let p = self.command(&[0x31], 0xB1);
        assert_eq!(p.len(), 1 + 152 + 1, "code, 152 data bytes, status");
        p
    }

    fn mode(&mut self, m: u8, extra: &[u8]) {
        let p = self.command(&[&[0x20, m][..], extra].concat(), 0xA0);
        assert_eq!(p.get(1), Some(&0), "20 {m:02X} refused");
    }
}

fn word(p: &[u8], i: usize) -> u16 {
    u16::from_le_bytes([p[i], p[i + 1]])
}

#[test]
fn b1_reports_the_operating_mode() {
    let mut b = Bench::new();
    assert_eq!(b.b1()[OPERATING_MODE], 0x25, "power-on: values on request");
    b.mode(0x00, b"SICK_LMS");
    assert_eq!(b.b1()[OPERATING_MODE], 0x00, "installation mode");
    b.mode(0x25, &[]);
    assert_eq!(b.b1()[OPERATING_MODE], 0x25, "after 20 25");
    b.mode(0x24, &[]);
    assert_eq!(b.b1()[OPERATING_MODE], 0x24, "streaming after 20 24");
    b.mode(0x25, &[]);
    assert_eq!(b.b1()[OPERATING_MODE], 0x25, "back on request");
    let p = b.b1();
    assert_eq!(&p[1..8], b"V02.10 ");
    assert_eq!(p[DEVICE_STATUS], 0);
    assert_eq!(p[VARIANT_TYPE], 0);
    assert_eq!((p[PERMANENT_BAUD], p[ADDRESS]), (0, 0));
}

#[test]
fn b1_fields_follow_the_commands_that_change_them() {
    let mut b = Bench::new();
    let p = b.b1();
    assert_eq!((word(&p, SCAN_ANGLE), word(&p, RESOLUTION)), (180, 50));
    assert_eq!(word(&p, BAUD), 0x8067, "9600");
    assert_eq!(p[UNIT], 1, "mm at power-on (as configured)");
    // Variant 100° / 0.25°.
    let r = b.command(&[0x3B, 100, 0, 25, 0], 0xBB);
    assert_eq!(r[1], 1, "variant accepted");
    let p = b.b1();
    assert_eq!((word(&p, SCAN_ANGLE), word(&p, RESOLUTION)), (100, 25));
    // Unit cm and another measuring mode through installation mode + 77.
    let mut block = ConfigBlock::default_mm();
    let old_mode = block.measuring_mode().0;
    let new_mode = if old_mode == 0x06 { 0x00 } else { 0x06 };
    block.set_unit(Unit::Cm);
    block.set_measuring_mode(MeasuringMode(new_mode));
    b.mode(0x00, b"SICK_LMS");
    let r = b.command(&[&[0x77][..], block.as_bytes()].concat(), 0xF7);
    assert_eq!(r[1], 1, "config accepted");
    let p = b.b1();
    assert_eq!(p[UNIT], 0, "cm");
    assert_eq!(p[MEASURING_MODE], new_mode);
    // Baud 38400: the word changes after the reply (sent at the old rate).
    b.mode(0x40, &[]);
    assert_eq!(word(&b.b1(), BAUD), 0x8019, "38400");
    b.mode(0x41, &[]);
    assert_eq!(word(&b.b1(), BAUD), 0x8033, "19200");
}
