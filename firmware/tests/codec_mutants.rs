//! Codec facts the other tests leave open, each checked against the protocol notes
//! (lms200-protocol.md, lms200-test-vectors.txt) or plain arithmetic, never against the code's
//! own output. Each test kills a cargo-mutants survivor (docs/TESTING.md, mutation section).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

mod common;

use firmware::lms::command::{Command, PASSWORD};
use firmware::lms::frame::{encode_parts, encode_telegram, Decoder, Event, MAX_TELEGRAM};
use firmware::lms::reply::{parse_reply, Reply, ReplyOptions, Status};
use firmware::lms::types::{Baud, Variant};

/// Command codes and their reply codes (§4 table; reply = request + 0x80, `20 xx` → A0,
/// `10` → 91).
#[test]
fn command_codes_and_reply_codes_follow_the_table() {
    let block = firmware::lms::reply::ConfigBlock::default_mm();
    let cases: [(Command<'_>, u8, u8); 13] = [
        (Command::Install(&PASSWORD), 0x20, 0xA0),
        (Command::SetBaud(Baud::B38400), 0x20, 0xA0),
        (Command::Continuous, 0x20, 0xA0),
        (Command::OnRequest, 0x20, 0xA0),
        (Command::Mode(0x10), 0x20, 0xA0),
        (Command::SetVariant(Variant::A180_R050), 0x3B, 0xBB),
        (Command::Status, 0x31, 0xB1),
        (Command::ErrorLog, 0x32, 0xB2),
        (Command::Type, 0x3A, 0xBA),
        (Command::GetConfig, 0x74, 0xF4),
        (Command::SetConfig(&block), 0x77, 0xF7),
        (Command::RequestValues(1), 0x30, 0xB0),
        (Command::Reset, 0x10, 0x91),
    ];
    for (cmd, code, reply) in cases {
        assert_eq!(cmd.code(), code, "{cmd:?}");
        assert_eq!(cmd.reply_code(), reply, "{cmd:?}");
    }
}

/// The largest telegram is 812 bytes (§1): a payload of 812 − 6 = 806 bytes is encodable,
/// one byte more is not.
#[test]
fn the_largest_telegram_encodes_and_one_byte_more_does_not() {
    let mut out = vec![0u8; 1024];
    let payload = vec![0xB0u8; 806];
    assert_eq!(encode_telegram(0x80, &payload, &mut out), Ok(812));
    assert_eq!(&out[..4], &[0x02, 0x80, 0x26, 0x03]); // LEN 806 = 0x0326
    let (a, b) = payload.split_at(400);
    assert_eq!(encode_parts(0x80, &[a, b], &mut out), Ok(812));
    assert!(encode_telegram(0x80, &[0xB0; 807], &mut out).is_err());
}

/// A stray STX with a wrong address, then an ACK and a good reply: the ACK is an event and the
/// reply is delivered, however the bytes are chunked (the address is checked at its byte).
#[test]
fn wrong_address_is_rejected_at_its_byte_in_any_chunking() {
    // STX, host address (wrong for a device→host decoder), ACK, then `A0 00 10` (vector).
    let stream = [
        0x02, 0x00, 0x06, 0x02, 0x80, 0x03, 0x00, 0xA0, 0x00, 0x10, 0x16, 0x0A,
    ];
    let reply = stream[3..].to_vec();
    for split in 0..=stream.len() {
        let mut dec = Decoder::<MAX_TELEGRAM>::new();
        let mut events = Vec::new();
        for chunk in [&stream[..split], &stream[split..]] {
            let mut rest = chunk;
            loop {
                let (used, ev) = dec.feed(rest);
                rest = &rest[used..];
                match ev {
                    Some(Event::Ack) => events.push(None),
                    Some(Event::Nak) => panic!("no NAK in the stream"),
                    Some(Event::Telegram(t)) => events.push(Some(t.raw().to_vec())),
                    None => break,
                }
            }
        }
        assert_eq!(events, vec![None, Some(reply.clone())], "split at {split}");
        assert_eq!(dec.stats().acks, 1, "split at {split}");
        // STX and the wrong address byte.
        assert_eq!(dec.stats().bytes_skipped, 2, "split at {split}");
    }
}

/// Status byte bits (§3): bits 0–2 the error level, bit 5 restart, bit 6 implausible, bit 7 pollution; real devices send
/// 0x10, which sets none of them.
#[test]
fn status_bits_follow_the_protocol() {
    let flags = |s: u8| {
        let s = Status(s);
        (s.restart(), s.implausible(), s.pollution())
    };
    assert_eq!(flags(0x10), (false, false, false));
    assert_eq!(flags(0x20), (true, false, false));
    assert_eq!(flags(0x40), (false, true, false));
    assert_eq!(flags(0x80), (false, false, true));
    assert_eq!(flags(0xF0), (true, true, true));
    // Bits 0–2: 0 ok, 1 info, 2 warning, 3 error, 4 fatal error.
    for (s, error) in [
        (0x10, false),
        (0x11, false),
        (0x12, false),
        (0x13, true),
        (0x14, true),
    ] {
        assert_eq!(Status(s).general(), s & 7);
        assert_eq!(Status(s).is_error(), error, "{s:#04x}");
    }
}

/// B1 byte 8 is the operating mode (§6).
#[test]
fn b1_operating_mode_is_byte_8() {
    for mode in [0x24u8, 0x25, 0x00] {
        let mut p = vec![0u8; 154];
        p[0] = 0xB1;
        p[8] = mode;
        p[9] = 0x55;
        p[153] = 0x10;
        let r = parse_reply(&p, ReplyOptions::default()).unwrap();
        let Reply::Status(s) = r.reply else {
            panic!("not a status reply")
        };
        assert_eq!(s.operating_mode(), Some(mode));
    }
}

/// Baud rates: bps ↔ rate for all four (§4), and the B1 baud words (§6: 0x8067 9600, 0x8033
/// 19200, 0x8019 38400, 0x8001 500k).
#[test]
fn baud_rates_and_status_words_follow_the_protocol() {
    let table = [
        (9600, Baud::B9600, 0x8067),
        (19200, Baud::B19200, 0x8033),
        (38400, Baud::B38400, 0x8019),
        (500_000, Baud::B500000, 0x8001),
    ];
    for (bps, baud, word) in table {
        assert_eq!(Baud::from_bps(bps), Some(baud));
        assert_eq!(baud.status_word(), word);
        assert_eq!(Baud::from_status_word(word), Some(baud));
    }
    assert_eq!(Baud::from_bps(115_200), None);
}

/// Resolution in degrees and the mirror's scan-rate limit (§8: 75 Hz, 2 or 4 interlaced turns
/// at 0.5° / 0.25°).
#[test]
fn variant_resolution_and_rate_limit() {
    let table = [
        (Variant::A180_R100, 1.0, 75.0),
        (Variant::A180_R050, 0.5, 37.5),
        (Variant::A100_R100, 1.0, 75.0),
        (Variant::A100_R050, 0.5, 37.5),
        (Variant::A100_R025, 0.25, 18.75),
    ];
    for (v, res, hz) in table {
        assert_eq!(v.resolution_deg(), res, "{v:?}");
        assert_eq!(v.max_rate_hz(), hz, "{v:?}");
        // Interlaced turns × scan time = 1/75 s per turn.
        assert_eq!(75.0 / v.max_rate_hz(), 1.0 / v.resolution_deg(), "{v:?}");
    }
}

/// The largest scan, 100° at 0.25° (401 values), makes the largest telegram, 2 × 401 + 10 =
/// 812 bytes (§1, §7): the decoder delivers it.
#[test]
fn the_largest_scan_telegram_decodes() {
    let raw = common::b0_telegram(401, 2000);
    let n = raw.len();
    assert_eq!(n, 812);
    let mut dec = Decoder::<MAX_TELEGRAM>::new();
    let (used, ev) = dec.feed(&raw[..n]);
    assert_eq!(used, 812);
    let Some(Event::Telegram(t)) = ev else {
        panic!("no telegram: {ev:?}")
    };
    let Reply::Values(v) = parse_reply(t.payload(), ReplyOptions::default())
        .unwrap()
        .reply
    else {
        panic!("not a B0")
    };
    assert_eq!(v.len(), 401);
    assert_eq!(v.word(400), Some(2400));
}

/// B2 is `n × (type, code)` (§4): one pair parses, an odd data length does not.
#[test]
fn error_log_is_pairs() {
    let r = parse_reply(&[0xB2, 0x03, 0x41, 0x10], ReplyOptions::default()).unwrap();
    let Reply::ErrorLog(log) = r.reply else {
        panic!("not an error log")
    };
    assert_eq!(log.entries().collect::<Vec<_>>(), vec![(0x03, 0x41)]);
    let empty = parse_reply(&[0xB2, 0x10], ReplyOptions::default()).unwrap();
    assert!(matches!(empty.reply, Reply::ErrorLog(l) if l.is_empty()));
    assert!(parse_reply(&[0xB2, 0x03, 0x10], ReplyOptions::default()).is_err());
}

/// Count-word unit bits 14–15 (§7): 00 cm, 01 mm, 10 dm (CARMEN), 11 undefined.
#[test]
fn count_word_unit_bits() {
    use firmware::lms::types::Unit;
    assert_eq!(Unit::from_count_bits(0), Some(Unit::Cm));
    assert_eq!(Unit::from_count_bits(1), Some(Unit::Mm));
    assert_eq!(Unit::from_count_bits(2), Some(Unit::Dm));
    assert_eq!(Unit::from_count_bits(3), None);
    assert_eq!(Unit::Dm.mm_per_unit(), 100.0);
}
