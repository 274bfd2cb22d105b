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

use lms2xx::codec::command::{Command, PASSWORD};
use lms2xx::codec::frame::{encode_parts, encode_telegram, Decoder, Event, MAX_TELEGRAM};
use lms2xx::codec::reply::{parse_reply, Reply, ReplyOptions, Status};
use lms2xx::codec::types::{Baud, Variant};

/// Command codes and their reply codes (§4 table; reply = request + 0x80, `20 xx` → A0,
/// `10` → 91).
#[test]
fn command_codes_and_reply_codes_follow_the_table() {
    let block = lms2xx::codec::reply::ConfigBlock::default_mm();
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
    use lms2xx::codec::types::Unit;
    assert_eq!(Unit::from_count_bits(0), Some(Unit::Cm));
    assert_eq!(Unit::from_count_bits(1), Some(Unit::Mm));
    assert_eq!(Unit::from_count_bits(2), Some(Unit::Dm));
    assert_eq!(Unit::from_count_bits(3), None);
    assert_eq!(Unit::Dm.mm_per_unit(), 100.0);
}

/// Baud mode codes of `20 xx` (§4 table, traces A–D): 0x40 38 400, 0x41 19 200, 0x42 9600,
/// 0x48 500 000; the other `20 xx` modes (0x24 continuous, 0x25 request, 0x00 install) are no
/// rate.
#[test]
fn baud_mode_codes_follow_the_table() {
    for (code, baud) in [
        (0x40, Baud::B38400),
        (0x41, Baud::B19200),
        (0x42, Baud::B9600),
        (0x48, Baud::B500000),
    ] {
        assert_eq!(Baud::from_mode_code(code), Some(baud), "{code:#04x}");
    }
    for code in [0x00, 0x24, 0x25, 0x43, 0x47] {
        assert_eq!(Baud::from_mode_code(code), None, "{code:#04x}");
    }
}

/// Values per scan (§7: 181 at 180°/1°, 361 at 180°/0.5°, 101, 201, 401 at 100°), and each
/// count names its variant; a count no variant has names none.
#[test]
fn value_counts_name_their_variant() {
    let table = [
        (Variant::new(180, 100), 181),
        (Variant::new(180, 50), 361),
        (Variant::new(100, 100), 101),
        (Variant::new(100, 50), 201),
        (Variant::new(100, 25), 401),
    ];
    for (v, n) in table {
        assert_eq!(v.values(), n, "{v:?}");
        assert_eq!(Variant::from_values(n), Some(v), "{n} values");
    }
    for n in [0, 180, 360, 362, 721] {
        assert_eq!(Variant::from_values(n), None, "{n} values");
    }
}

/// Bearing of value 0 (§7: value 0 at the right-hand edge; S7 maps 180° to −90°…+90° and 100°
/// to −50°…+50°). Measured from the right-hand edge of the full 180° field that is 0° for a
/// 180° scan and 40° for a 100° scan.
#[test]
fn variant_start_angles_follow_s7() {
    for (v, centred, from_edge) in [
        (Variant::A180_R100, -90.0, 0.0),
        (Variant::A180_R050, -90.0, 0.0),
        (Variant::A100_R100, -50.0, 40.0),
        (Variant::A100_R050, -50.0, 40.0),
        (Variant::A100_R025, -50.0, 40.0),
    ] {
        assert_eq!(v.start_deg(), centred, "{v:?}");
        assert_eq!(v.start_deg() + 90.0, from_edge, "{v:?}");
    }
}

/// Unit codes: count-word bits 14–15 (§7: 00 cm, 01 mm, 10 dm) and config byte 6 / B1 byte 122
/// (§5, §6: 0 cm, 1 mm, S5 2 dm).
#[test]
fn unit_codes_of_count_word_and_config() {
    use lms2xx::codec::types::Unit;
    for (unit, code) in [(Unit::Cm, 0u8), (Unit::Mm, 1), (Unit::Dm, 2)] {
        assert_eq!(unit.count_bits(), u16::from(code), "{unit:?}");
        assert_eq!(Unit::from_config(code), Some(unit), "{code}");
        assert_eq!(unit.config_byte(), code, "{unit:?}");
    }
    assert_eq!(Unit::from_config(3), None);
    assert_eq!(Unit::from_config(0xFF), None);
}

/// Largest valid range code (§7): 8182 in the 8 m / 80 m modes (8183 is "> maximum"), 32758 in
/// the 32 m modes (32759 "> maximum"); the reserved codes are defined only below 8191 / 16383 /
/// 32767, so in the 16-bit modes (0x0F immediate, 0x3F reflectivity) every word is a value.
#[test]
fn largest_valid_code_per_measuring_mode() {
    use lms2xx::codec::types::MeasuringMode;
    for m in [0x00, 0x01, 0x02] {
        assert_eq!(MeasuringMode(m).max_valid(), 8182, "mode {m:#04x}");
    }
    for m in [0x05, 0x06] {
        assert_eq!(MeasuringMode(m).max_valid(), 32758, "mode {m:#04x}");
    }
    for m in [0x0F, 0x3F] {
        assert_eq!(MeasuringMode(m).max_valid(), 0xFFFF, "mode {m:#04x}");
    }
}

/// The error Display texts name their values: a bad LEN and the protocol's limit (812 − 6 =
/// 806, §1), both CRCs (the vector `20 24` has CRC 0x0834, §1), a reply's code and lengths.
#[test]
fn error_messages_name_their_values() {
    use lms2xx::codec::frame::FrameError;
    use lms2xx::codec::reply::ReplyError;
    let s = FrameError::BadLength(900).to_string();
    assert!(s.contains("900") && s.contains("806"), "{s}");
    let s = FrameError::Crc {
        expected: 0x0834,
        got: 0x0835,
    }
    .to_string();
    assert!(s.contains("0x0834") && s.contains("0x0835"), "{s}");
    for e in [
        FrameError::Truncated,
        FrameError::TrailingBytes,
        FrameError::NoStx,
        FrameError::BufferTooSmall,
    ] {
        assert!(!e.to_string().is_empty(), "{e:?}");
    }
    let s = ReplyError::Length {
        code: 0xB0,
        expected: 726,
        got: 21,
    }
    .to_string();
    assert!(
        s.contains("0xb0") && s.contains("726") && s.contains("21"),
        "{s}"
    );
    assert!(!ReplyError::Empty.to_string().is_empty());
}

/// Framing (§1): LEN 0 and LEN above 806 are bad lengths even with a good CRC; a telegram
/// short of its LEN is truncated, one with bytes after its CRC has trailing bytes; the address
/// byte of a device telegram is 0x80, of a host telegram 0x00.
#[test]
fn telegram_framing_errors_and_address() {
    use common::lms::{crc16, device_telegram};
    use lms2xx::codec::frame::{FrameError, Telegram};
    let with_crc = |mut t: Vec<u8>| {
        let c = crc16(&t);
        t.extend_from_slice(&c.to_le_bytes());
        t
    };
    let zero = with_crc(vec![0x02, 0x80, 0x00, 0x00]);
    assert_eq!(Telegram::parse(&zero), Err(FrameError::BadLength(0)));
    let mut big = vec![0x02, 0x80, 0x27, 0x03]; // LEN 807
    big.resize(4 + 807, 0xB0);
    let big = with_crc(big);
    assert_eq!(Telegram::parse(&big), Err(FrameError::BadLength(807)));

    let a0 = device_telegram(&[0xA0, 0x00, 0x10]);
    let t = Telegram::parse(&a0).unwrap();
    assert_eq!(t.address(), 0x80);
    for cut in 1..=4 {
        assert_eq!(
            Telegram::parse(&a0[..a0.len() - cut]),
            Err(FrameError::Truncated),
            "{cut} bytes short"
        );
    }
    let mut long = a0.clone();
    long.push(0x06);
    assert_eq!(Telegram::parse(&long), Err(FrameError::TrailingBytes));

    // `20 24` from the vectors: host address 0x00.
    let cmd = [0x02, 0x00, 0x02, 0x00, 0x20, 0x24, 0x34, 0x08];
    assert_eq!(Telegram::parse(&cmd).unwrap().address(), 0x00);
}

/// Decodes `chunks` with at most 8 calls per chunk, so a decoder that repeats itself fails
/// instead of hanging; `None` marks an ACK.
fn bounded_decode(dec: &mut Decoder<MAX_TELEGRAM>, chunks: &[&[u8]]) -> Vec<Option<Vec<u8>>> {
    let mut events = Vec::new();
    for chunk in chunks {
        let mut rest = *chunk;
        for _ in 0..8 {
            let (used, ev) = dec.feed(rest);
            rest = &rest[used..];
            match ev {
                Some(Event::Ack) => events.push(None),
                Some(Event::Nak) => events.push(Some(vec![0x15])),
                Some(Event::Telegram(t)) => events.push(Some(t.raw().to_vec())),
                None => break,
            }
        }
    }
    events
}

/// Each telegram of a stream is delivered once (the §7 vector B0 and A0 telegrams back to
/// back, an ACK between them): once delivered, a telegram leaves the buffer, nothing is
/// pending and nothing is skipped.
#[test]
fn a_delivered_telegram_is_delivered_once() {
    let a0 = vec![0x02, 0x80, 0x03, 0x00, 0xA0, 0x00, 0x10, 0x16, 0x0A];
    let b0 = vec![
        0x02, 0x80, 0x0A, 0x00, 0xB0, 0x03, 0x00, 0x64, 0x00, 0xC8, 0x00, 0x2C, 0x01, 0x10, 0xBE,
        0x64,
    ];
    let stream = [&b0[..], &[0x06], &a0[..], &b0[..]].concat();
    let want = vec![Some(b0.clone()), None, Some(a0.clone()), Some(b0.clone())];
    // One chunk, then the same bytes one at a time and as telegram-sized chunks.
    let mut dec = Decoder::<MAX_TELEGRAM>::new();
    assert_eq!(bounded_decode(&mut dec, &[&stream]), want);
    let bytes: Vec<&[u8]> = stream.chunks(1).collect();
    let mut dec1 = Decoder::<MAX_TELEGRAM>::new();
    assert_eq!(bounded_decode(&mut dec1, &bytes), want);
    let mut dec2 = Decoder::<MAX_TELEGRAM>::new();
    assert_eq!(bounded_decode(&mut dec2, &[&b0, &[0x06], &a0, &b0]), want);
    for d in [&mut dec, &mut dec1, &mut dec2] {
        // The last telegram was delivered: an empty feed drops it and returns nothing.
        assert!(d.feed(&[]).1.is_none());
        assert_eq!(d.pending(), 0);
        assert_eq!(d.stats().bytes_skipped, 0);
        assert_eq!(d.stats().telegrams, 3);
        assert_eq!(d.stats().acks, 1);
    }
}

/// Dropped candidates are counted by cause and in total (a bad CRC, a LEN of 0, a LEN that
/// fits the protocol but not a small buffer), and `reset_stats` zeroes every counter.
#[test]
fn dropped_counts_every_rejected_candidate_and_reset_zeroes() {
    let mut bad_crc = vec![0x02, 0x80, 0x03, 0x00, 0xA0, 0x00, 0x10, 0x16, 0x0A];
    bad_crc[8] ^= 0xFF;
    let zero_len = [0x02, 0x80, 0x00, 0x00];
    // B0 of 361 values: LEN 0x02D6 (trace A), too long for a 64-byte buffer.
    let long = [0x02, 0x80, 0xD6, 0x02];
    let mut dec = Decoder::<64>::new();
    for chunk in [&bad_crc[..], &zero_len, &long] {
        let mut rest = chunk;
        for _ in 0..8 {
            let (used, ev) = dec.feed(rest);
            rest = &rest[used..];
            assert!(ev.is_none(), "{ev:?}");
            if rest.is_empty() {
                break;
            }
        }
    }
    let s = dec.stats();
    assert_eq!((s.crc_errors, s.bad_length, s.overflows), (1, 1, 1));
    assert_eq!(s.dropped(), 3);
    assert!(s.bytes_skipped > 0);
    dec.reset_stats();
    assert_eq!(dec.stats(), lms2xx::codec::frame::DecoderStats::default());
    assert_eq!(dec.stats().dropped(), 0);
    assert_eq!(dec.stats().bytes_skipped, 0);
}

/// B0 count word (§7): bits 0–9 the count, 11–12 the partial-scan index (0–3), bit 13 the
/// partial-scan flag; a telegram with no value is empty.
#[test]
fn count_word_partial_bits_and_empty_scans() {
    let opts = ReplyOptions::default();
    for (index, partial) in [(0u16, false), (1, true), (2, true), (3, true), (3, false)] {
        let cw = (1u16 << 14) | (index << 11) | (u16::from(partial) << 13) | 2;
        let [c0, c1] = cw.to_le_bytes();
        let p = [0xB0, c0, c1, 0xE8, 0x03, 0xE9, 0x03, 0x10];
        let Reply::Values(v) = parse_reply(&p, opts).unwrap().reply else {
            panic!("not a B0")
        };
        assert_eq!(v.partial_index(), index as u8, "{cw:#06x}");
        assert_eq!(v.is_partial(), partial, "{cw:#06x}");
        assert_eq!(v.len(), 2);
        assert!(!v.is_empty());
    }
    let Reply::Values(v) = parse_reply(&[0xB0, 0x00, 0x40, 0x10], opts).unwrap().reply else {
        panic!("not a B0")
    };
    assert!(v.is_empty());
    assert_eq!(v.len(), 0);
}

/// B2 error log (§4: n × (type, code), 0 pairs = no errors): three pairs are three entries.
#[test]
fn error_log_length_counts_pairs() {
    let p = [0xB2, 0x03, 0x41, 0x02, 0x07, 0x04, 0x0A, 0x10];
    let Reply::ErrorLog(log) = parse_reply(&p, ReplyOptions::default()).unwrap().reply else {
        panic!("not an error log")
    };
    assert_eq!(log.len(), 3);
    assert!(!log.is_empty());
    assert_eq!(
        log.entries().collect::<Vec<_>>(),
        vec![(0x03, 0x41), (0x02, 0x07), (0x04, 0x0A)]
    );
    let Reply::ErrorLog(one) = parse_reply(&[0xB2, 0x03, 0x41, 0x10], ReplyOptions::default())
        .unwrap()
        .reply
    else {
        panic!("not an error log")
    };
    assert_eq!(one.len(), 1);
}

/// Configuration block (§5): 34 bytes, or 32 from older clients (S5, S6); other lengths are not
/// a block. Byte 4 is availability, flag 0x02 the real-time scan index.
#[test]
fn config_block_lengths_and_availability_byte() {
    use lms2xx::codec::reply::ConfigBlock;
    let opts = ReplyOptions::default();
    for n in [32usize, 34] {
        let mut p = vec![0xF4];
        p.extend((0..n).map(|i| i as u8 + 0x40));
        p.push(0x10);
        let Reply::Config(c) = parse_reply(&p, opts).unwrap().reply else {
            panic!("not a config reply")
        };
        assert_eq!(c.as_bytes().len(), n);
        assert_eq!(c.availability(), 0x44, "byte 4");
    }
    for n in [0usize, 31, 33, 35, 36] {
        let mut p = vec![0xF4];
        p.resize(1 + n, 0);
        p.push(0x10);
        assert!(parse_reply(&p, opts).is_err(), "{n} config bytes");
        assert!(ConfigBlock::from_bytes(&p[1..=n]).is_none(), "{n} bytes");
    }

    let mut b = [0u8; 34];
    b[4] = 0x02;
    let c = ConfigBlock::from_bytes(&b).unwrap();
    assert_eq!(c.availability(), 0x02);
    assert!(c.realtime_index());
    b[4] = 0x05; // high availability, dazzle no effect: no index
    let c = ConfigBlock::from_bytes(&b).unwrap();
    assert_eq!(c.availability(), 0x05);
    assert!(!c.realtime_index());

    let mut c = ConfigBlock::default_mm();
    assert_eq!(c.availability(), 0);
    c.set_availability(0x03);
    assert_eq!(c.as_bytes()[4], 0x03);
    assert_eq!(c.availability(), 0x03);
    assert!(c.realtime_index());
    c.set_availability(0x01);
    assert!(!c.realtime_index());
}

/// Runs `scenario` on another thread; if it panics or has not returned within 5 s the whole
/// test binary exits with a failure at once, because a hung thread (this one, or another test
/// hung by the same fault) would otherwise keep the binary running until an outside timeout.
fn within_5_s(what: &str, scenario: impl FnOnce() + Send + 'static) {
    let (tx, rx) = std::sync::mpsc::channel();
    let worker = std::thread::spawn(move || {
        scenario();
        let _ = tx.send(());
    });
    match rx.recv_timeout(std::time::Duration::from_secs(5)) {
        Ok(()) => worker.join().unwrap(),
        // The panic message is already printed.
        Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
            eprintln!("{what} failed");
            std::process::exit(101);
        }
        Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
            eprintln!("{what} did not return within 5 s");
            std::process::exit(101);
        }
    }
}

/// The decoder returns on every input and, fed the rest until it reports nothing, delivers the
/// good telegrams of the vectors (A0, B0 3 values) and the ACK / NAK bytes between them, past a
/// STX with the host address, a telegram with a bad CRC, a LEN of 0 and line noise (§1, §2). Named to sort first, so it starts
/// before any other test of this binary can hang.
#[test]
fn a_decoder_always_returns() {
    within_5_s("the decoder", || {
        let a0 = vec![0x02, 0x80, 0x03, 0x00, 0xA0, 0x00, 0x10, 0x16, 0x0A];
        let b0 = vec![
            0x02, 0x80, 0x0A, 0x00, 0xB0, 0x03, 0x00, 0x64, 0x00, 0xC8, 0x00, 0x2C, 0x01, 0x10,
            0xBE, 0x64,
        ];
        let mut bad = a0.clone();
        bad[8] ^= 0xFF;
        // Noise, an ACK, a STX with the host address (wrong here), a bad CRC, noise, …
        let stream = [
            &[0x55, 0x06, 0x02, 0x00][..],
            &bad,
            &[0x55],
            &a0,
            &b0,
            &[0x02, 0x80, 0x00, 0x00, 0x15],
            &a0,
        ]
        .concat();
        let want = vec![
            None,
            Some(a0.clone()),
            Some(b0.clone()),
            Some(vec![0x15]),
            Some(a0.clone()),
        ];
        for size in [1, 2, 3, 7, stream.len()] {
            let mut dec = Decoder::<MAX_TELEGRAM>::new();
            let chunks: Vec<&[u8]> = stream.chunks(size).collect();
            let mut events = Vec::new();
            for chunk in chunks {
                let mut rest = chunk;
                for _ in 0..1000 {
                    let (used, ev) = dec.feed(rest);
                    rest = &rest[used..];
                    match ev {
                        Some(Event::Ack) => events.push(None),
                        Some(Event::Nak) => events.push(Some(vec![0x15])),
                        Some(Event::Telegram(t)) => events.push(Some(t.raw().to_vec())),
                        None => break,
                    }
                }
            }
            assert_eq!(events, want, "chunks of {size}");
        }
    });
}
