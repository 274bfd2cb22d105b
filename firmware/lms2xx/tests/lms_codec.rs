//! Codec tests against the published protocol test vectors (lms200-test-vectors.txt) and the
//! full 732-byte B0 telegram (lms200-b0-full-180-050-mm.txt), embedded here verbatim.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

use lms2xx::codec::crc::crc16;
use lms2xx::codec::frame::{encode_telegram, Decoder, Event, Telegram, MAX_TELEGRAM};
use lms2xx::codec::reply::{parse_reply, RangeCode, Reply, ReplyOptions};
use lms2xx::codec::types::{MeasuringMode, Unit};

/// (description, telegram hex, CRC) from lms200-test-vectors.txt.
const VECTORS: &[(&str, &str, u16)] = &[
    ("cmd 20 24 (continuous)", "02 00 02 00 20 24 34 08", 0x0834),
    (
        "cmd 20 25 (request mode)",
        "02 00 02 00 20 25 35 08",
        0x0835,
    ),
    ("cmd 20 40 (38400)", "02 00 02 00 20 40 50 08", 0x0850),
    ("cmd 20 41 (19200)", "02 00 02 00 20 41 51 08", 0x0851),
    ("cmd 20 42 (9600)", "02 00 02 00 20 42 52 08", 0x0852),
    ("cmd 20 48 (500000)", "02 00 02 00 20 48 58 08", 0x0858),
    (
        "cmd 20 00 SICK_LMS (install)",
        "02 00 0A 00 20 00 53 49 43 4B 5F 4C 4D 53 BE C5",
        0xC5BE,
    ),
    (
        "cmd 3B B4 00 32 00 (180/0.5)",
        "02 00 05 00 3B B4 00 32 00 3B 1F",
        0x1F3B,
    ),
    (
        "cmd 3B B4 00 64 00 (180/1.0)",
        "02 00 05 00 3B B4 00 64 00 97 49",
        0x4997,
    ),
    (
        "cmd 3B 64 00 19 00 (100/0.25)",
        "02 00 05 00 3B 64 00 19 00 E7 72",
        0x72E7,
    ),
    ("cmd 31 (status)", "02 00 01 00 31 15 12", 0x1215),
    ("cmd 32 (errors)", "02 00 01 00 32 16 12", 0x1216),
    ("cmd 3A (type)", "02 00 01 00 3A 1E 12", 0x121E),
    ("cmd 74 (get config)", "02 00 01 00 74 50 12", 0x1250),
    (
        "cmd 30 01 (request all values)",
        "02 00 02 00 30 01 31 18",
        0x1831,
    ),
    (
        "rsp A0 00 10 (mode ok, st=0x10)",
        "02 80 03 00 A0 00 10 16 0A",
        0x0A16,
    ),
    (
        "rsp A0 00 00 (mode ok, st=0x00)",
        "02 80 03 00 A0 00 00 06 0A",
        0x0A06,
    ),
    (
        "rsp BB 01 B4 00 32 00 10",
        "02 80 07 00 BB 01 B4 00 32 00 10 03 9D",
        0x9D03,
    ),
    (
        "rsp B0 (5 values, mm, st=0x10)",
        "02 80 0E 00 B0 05 40 E8 03 E9 03 EA 03 EB 03 FF 1F 10 1F 93",
        0x931F,
    ),
    (
        "rsp B0 (3 values 100/200/300 cm)",
        "02 80 0A 00 B0 03 00 64 00 C8 00 2C 01 10 BE 64",
        0x64BE,
    ),
];

/// lms200-b0-full-180-050-mm.txt (crc 0x3AF8).
const B0_FULL: &str = concat!(
    "02 80 D6 02 B0 69 41 FF 1F FE 1F F7 1F EB 23 EC 43 ED 83 EE 03 EF 03 F0 ",
    "03 F1 03 F2 03 F3 03 F4 03 F5 03 F6 03 F7 03 F8 03 F9 03 FA 03 FB 03 FC ",
    "03 FD 03 FE 03 FF 03 00 04 01 04 02 04 03 04 04 04 05 04 06 04 07 04 08 ",
    "04 09 04 0A 04 0B 04 0C 04 0D 04 0E 04 0F 04 10 04 11 04 12 04 13 04 14 ",
    "04 15 04 16 04 17 04 18 04 19 04 1A 04 1B 04 1C 04 1D 04 1E 04 1F 04 20 ",
    "04 21 04 22 04 23 04 24 04 25 04 26 04 27 04 28 04 29 04 2A 04 2B 04 2C ",
    "04 2D 04 2E 04 2F 04 30 04 31 04 32 04 33 04 34 04 35 04 36 04 37 04 38 ",
    "04 39 04 3A 04 3B 04 3C 04 3D 04 3E 04 3F 04 40 04 41 04 42 04 43 04 44 ",
    "04 45 04 46 04 47 04 48 04 49 04 4A 04 4B 04 4C 04 4D 04 4E 04 4F 04 50 ",
    "04 51 04 52 04 53 04 54 04 55 04 56 04 57 04 58 04 59 04 5A 04 5B 04 5C ",
    "04 5D 04 5E 04 5F 04 60 04 61 04 62 04 63 04 64 04 65 04 66 04 67 04 68 ",
    "04 69 04 6A 04 6B 04 6C 04 6D 04 6E 04 6F 04 70 04 71 04 72 04 73 04 74 ",
    "04 75 04 76 04 77 04 78 04 79 04 7A 04 7B 04 7C 04 7D 04 7E 04 7F 04 80 ",
    "04 81 04 82 04 83 04 84 04 85 04 86 04 87 04 88 04 89 04 8A 04 8B 04 8C ",
    "04 8D 04 8E 04 8F 04 90 04 91 04 92 04 93 04 94 04 95 04 96 04 97 04 98 ",
    "04 99 04 9A 04 9B 04 9C 04 9D 04 9E 04 9F 04 A0 04 A1 04 A2 04 A3 04 A4 ",
    "04 A5 04 A6 04 A7 04 A8 04 A9 04 AA 04 AB 04 AC 04 AD 04 AE 04 AF 04 B0 ",
    "04 B1 04 B2 04 B3 04 B4 04 B5 04 B6 04 B7 04 B8 04 B9 04 BA 04 BB 04 BC ",
    "04 BD 04 BE 04 BF 04 C0 04 C1 04 C2 04 C3 04 C4 04 C5 04 C6 04 C7 04 C8 ",
    "04 C9 04 CA 04 CB 04 CC 04 CD 04 CE 04 CF 04 D0 04 D1 04 D2 04 D3 04 D4 ",
    "04 D5 04 D6 04 D7 04 D8 04 D9 04 DA 04 DB 04 DC 04 DD 04 DE 04 DF 04 E0 ",
    "04 E1 04 E2 04 E3 04 E4 04 E5 04 E6 04 E7 04 E8 04 E9 04 EA 04 EB 04 EC ",
    "04 ED 04 EE 04 EF 04 F0 04 F1 04 F2 04 F3 04 F4 04 F5 04 F6 04 F7 04 F8 ",
    "04 F9 04 FA 04 FB 04 FC 04 FD 04 FE 04 FF 04 00 05 01 05 02 05 03 05 04 ",
    "05 05 05 06 05 07 05 08 05 09 05 0A 05 0B 05 0C 05 0D 05 0E 05 0F 05 10 ",
    "05 11 05 12 05 13 05 14 05 15 05 16 05 17 05 18 05 19 05 1A 05 1B 05 1C ",
    "05 1D 05 1E 05 1F 05 20 05 21 05 22 05 23 05 24 05 25 05 26 05 27 05 28 ",
    "05 29 05 2A 05 2B 05 2C 05 2D 05 2E 05 2F 05 30 05 31 05 32 05 33 05 34 ",
    "05 35 05 36 05 37 05 38 05 39 05 3A 05 3B 05 3C 05 3D 05 3E 05 3F 05 40 ",
    "05 41 05 42 05 43 05 44 05 45 05 46 05 47 05 48 05 49 05 4A 05 4B 05 4C ",
    "05 4D 05 4E 05 4F 05 50 05 10 F8 3A ",
);

fn hex(s: &str) -> Vec<u8> {
    s.split_whitespace()
        .map(|h| u8::from_str_radix(h, 16).unwrap())
        .collect()
}

#[derive(Debug, Clone, PartialEq, Eq)]
enum Ev {
    Ack,
    Nak,
    T(Vec<u8>),
}

/// Feeds `chunks` one after another, draining every event.
fn run<const N: usize>(dec: &mut Decoder<N>, chunks: &[&[u8]]) -> Vec<Ev> {
    let mut out = Vec::new();
    for chunk in chunks {
        let mut rest = *chunk;
        loop {
            let (used, ev) = dec.feed(rest);
            assert!(used <= rest.len());
            rest = &rest[used..];
            match ev {
                Some(Event::Ack) => out.push(Ev::Ack),
                Some(Event::Nak) => out.push(Ev::Nak),
                Some(Event::Telegram(t)) => out.push(Ev::T(t.raw().to_vec())),
                None => {
                    assert!(rest.is_empty(), "decoder stopped with input left");
                    break;
                }
            }
        }
    }
    out
}

fn decode(chunks: &[&[u8]]) -> (Vec<Ev>, lms2xx::codec::frame::DecoderStats) {
    let mut d = Decoder::<MAX_TELEGRAM>::new();
    let ev = run(&mut d, chunks);
    (ev, d.stats())
}

#[test]
fn crc_matches_every_vector() {
    for (name, h, crc) in VECTORS {
        let t = hex(h);
        let body = &t[..t.len() - 2];
        assert_eq!(crc16(body), *crc, "{name}");
        assert_eq!(
            t[t.len() - 2..],
            crc.to_le_bytes(),
            "{name}: low byte first"
        );
        assert!(Telegram::parse(&t).is_ok(), "{name}");
    }
}

#[test]
fn crc_of_full_b0_telegram() {
    let t = hex(B0_FULL);
    assert_eq!(t.len(), 732);
    assert_eq!(crc16(&t[..730]), 0x3AF8);
    assert!(Telegram::parse(&t).is_ok());
}

#[test]
fn encoders_reproduce_command_vectors() {
    use lms2xx::codec::command::{Command, PASSWORD};
    use lms2xx::codec::types::{Baud, Variant};
    let cases: Vec<(Command, &str)> = vec![
        (Command::Continuous, "cmd 20 24 (continuous)"),
        (Command::OnRequest, "cmd 20 25 (request mode)"),
        (Command::SetBaud(Baud::B38400), "cmd 20 40 (38400)"),
        (Command::SetBaud(Baud::B19200), "cmd 20 41 (19200)"),
        (Command::SetBaud(Baud::B9600), "cmd 20 42 (9600)"),
        (Command::SetBaud(Baud::B500000), "cmd 20 48 (500000)"),
        (Command::Install(&PASSWORD), "cmd 20 00 SICK_LMS (install)"),
        (
            Command::SetVariant(Variant::A180_R050),
            "cmd 3B B4 00 32 00 (180/0.5)",
        ),
        (
            Command::SetVariant(Variant::A180_R100),
            "cmd 3B B4 00 64 00 (180/1.0)",
        ),
        (
            Command::SetVariant(Variant::A100_R025),
            "cmd 3B 64 00 19 00 (100/0.25)",
        ),
        (Command::Status, "cmd 31 (status)"),
        (Command::ErrorLog, "cmd 32 (errors)"),
        (Command::Type, "cmd 3A (type)"),
        (Command::GetConfig, "cmd 74 (get config)"),
        (Command::RequestValues(1), "cmd 30 01 (request all values)"),
    ];
    for (cmd, name) in cases {
        let want = VECTORS
            .iter()
            .find(|v| v.0 == name)
            .map(|v| hex(v.1))
            .unwrap();
        let mut buf = [0u8; 64];
        let n = cmd.encode(&mut buf).unwrap();
        assert_eq!(&buf[..n], &want[..], "{name}");
        // A buffer one byte short is an error, not a panic or truncation.
        assert!(cmd.encode(&mut buf[..n - 1]).is_err());
    }
}

#[test]
fn set_config_and_reset_encode_with_valid_crc() {
    use lms2xx::codec::command::Command;
    use lms2xx::codec::reply::ConfigBlock;
    let mut cfg = ConfigBlock::default_mm();
    cfg.set_unit(Unit::Cm);
    let mut buf = [0u8; 64];
    let n = Command::SetConfig(&cfg).encode(&mut buf).unwrap();
    // Trace D: sicktoolbox sets cm with this exact telegram.
    let want = hex("02 00 23 00 77 46 00 00 00 00 00 00 00 00 02 02 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 02 00 CA F9");
    assert_eq!(&buf[..n], &want[..]);
    let n = Command::Reset.encode(&mut buf).unwrap();
    assert!(Telegram::parse(&buf[..n]).is_ok());
    assert_eq!(&buf[..5], &[0x02, 0x00, 0x01, 0x00, 0x10]);
}

#[test]
fn replies_parse() {
    let opts = ReplyOptions::default();
    let a0 = hex("02 80 03 00 A0 00 10 16 0A");
    let t = Telegram::parse(&a0).unwrap();
    let r = parse_reply(t.payload(), opts).unwrap();
    assert_eq!(r.reply, Reply::Mode(0));
    assert_eq!(r.status.0, 0x10);
    assert!(!r.status.is_error());

    let bb = hex("02 80 07 00 BB 01 B4 00 32 00 10 03 9D");
    let r = parse_reply(Telegram::parse(&bb).unwrap().payload(), opts).unwrap();
    assert_eq!(
        r.reply,
        Reply::Variant {
            ok: true,
            variant: lms2xx::codec::types::Variant::A180_R050
        }
    );

    let ba = hex("02 80 0E 00 BA 4C 4D 53 32 30 30 3B 33 30 31 30 36 10 DD 97");
    let r = parse_reply(Telegram::parse(&ba).unwrap().payload(), opts).unwrap();
    assert_eq!(r.reply, Reply::Type(b"LMS200;30106"));

    let b2 = hex("02 80 02 00 B2 10 3F 13");
    let r = parse_reply(Telegram::parse(&b2).unwrap().payload(), opts).unwrap();
    match r.reply {
        Reply::ErrorLog(l) => assert!(l.is_empty()),
        other => panic!("{other:?}"),
    }

    let f4 = hex("02 80 24 00 F4 46 00 00 00 00 00 01 00 00 02 02 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 02 00 10 2A 78");
    let r = parse_reply(Telegram::parse(&f4).unwrap().payload(), opts).unwrap();
    match r.reply {
        Reply::Config(c) => {
            assert_eq!(c.unit(), Some(Unit::Mm));
            assert_eq!(c.measuring_mode(), MeasuringMode(0));
            assert!(!c.realtime_index());
            assert_eq!(c, lms2xx::codec::reply::ConfigBlock::default_mm());
        }
        other => panic!("{other:?}"),
    }

    let f7 = hex("02 80 25 00 F7 01 46 00 00 00 00 06 01 00 00 02 02 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 02 00 10 5C FE");
    let r = parse_reply(Telegram::parse(&f7).unwrap().payload(), opts).unwrap();
    match r.reply {
        Reply::ConfigSet { ok, config } => {
            assert!(ok);
            assert_eq!(config.measuring_mode(), MeasuringMode(6));
        }
        other => panic!("{other:?}"),
    }

    for (code, want) in [
        (0x90u8, "PowerOn"),
        (0x91, "ResetAck"),
        (0x92, "IncorrectCommand"),
    ] {
        let mut buf = [0u8; 32];
        let n = encode_telegram(0x80, &[code, b'x', 0x10], &mut buf).unwrap();
        let r = parse_reply(Telegram::parse(&buf[..n]).unwrap().payload(), opts).unwrap();
        let got = match r.reply {
            Reply::PowerOn(d) | Reply::ResetAck(d) | Reply::IncorrectCommand(d) => {
                assert_eq!(d, b"x");
                format!("{:?}", r.reply)
            }
            other => panic!("{other:?}"),
        };
        assert!(got.starts_with(want), "{got}");
    }
    // Malformed lengths are errors.
    assert!(parse_reply(&[0xA0, 0x10], opts).is_err());
    assert!(parse_reply(&[0xBB, 0x01, 0x10], opts).is_err());
    assert!(parse_reply(&[], opts).is_err());
}

#[test]
fn b1_status_fields() {
    // A B1 payload laid out per sicktoolbox offsets.
    let mut p = vec![0u8; 154];
    p[0] = 0xB1;
    p[1..8].copy_from_slice(b"V02.10 ");
    p[102] = 6;
    p[107..109].copy_from_slice(&180u16.to_le_bytes());
    p[109..111].copy_from_slice(&50u16.to_le_bytes());
    p[116..118].copy_from_slice(&0x8019u16.to_le_bytes());
    p[122] = 1;
    p[153] = 0x10;
    let r = parse_reply(&p, ReplyOptions::default()).unwrap();
    let Reply::Status(s) = r.reply else { panic!() };
    assert_eq!(s.software_version(), Some(&b"V02.10 "[..]));
    assert_eq!(s.measuring_mode(), Some(MeasuringMode(6)));
    assert_eq!(s.variant(), Some(lms2xx::codec::types::Variant::A180_R050));
    assert_eq!(s.baud(), Some(lms2xx::codec::types::Baud::B38400));
    assert_eq!(s.unit(), Some(Unit::Mm));
    // A short B1 gives None, never a panic.
    let short = parse_reply(&p[..50], ReplyOptions::default()).unwrap();
    let Reply::Status(s) = short.reply else {
        panic!()
    };
    assert_eq!(s.variant(), None);
}

#[test]
fn b0_small_vectors_decode() {
    let opts = ReplyOptions::default();
    let t = hex("02 80 0E 00 B0 05 40 E8 03 E9 03 EA 03 EB 03 FF 1F 10 1F 93");
    let r = parse_reply(Telegram::parse(&t).unwrap().payload(), opts).unwrap();
    let Reply::Values(v) = r.reply else { panic!() };
    assert_eq!(v.len(), 5);
    assert_eq!(v.unit(), Some(Unit::Mm));
    let m = MeasuringMode::default();
    let codes: Vec<_> = (0..5).map(|i| v.measurement(i, m).unwrap().kind).collect();
    assert_eq!(
        codes,
        [
            RangeCode::Valid(1000),
            RangeCode::Valid(1001),
            RangeCode::Valid(1002),
            RangeCode::Valid(1003),
            RangeCode::NotValid
        ]
    );
    let t = hex("02 80 0A 00 B0 03 00 64 00 C8 00 2C 01 10 BE 64");
    let r = parse_reply(Telegram::parse(&t).unwrap().payload(), opts).unwrap();
    let Reply::Values(v) = r.reply else { panic!() };
    assert_eq!(v.unit(), Some(Unit::Cm));
    assert_eq!(v.words().collect::<Vec<_>>(), [100, 200, 300]);
}

#[test]
fn b0_full_telegram_decodes() {
    let t = hex(B0_FULL);
    let tel = Telegram::parse(&t).unwrap();
    let r = parse_reply(tel.payload(), ReplyOptions::default()).unwrap();
    assert_eq!(r.status.0, 0x10);
    let Reply::Values(v) = r.reply else { panic!() };
    assert_eq!(v.len(), 361);
    assert_eq!(v.unit(), Some(Unit::Mm));
    assert!(!v.is_partial());
    assert_eq!(v.partial_index(), 0);
    let m = MeasuringMode::default();
    let k = |i| v.measurement(i, m).unwrap();
    assert_eq!(k(0).kind, RangeCode::NotValid);
    assert_eq!(k(1).kind, RangeCode::Dazzling);
    assert_eq!(k(2).kind, RangeCode::TooFar);
    // 0x23EB: 1003 mm with flag bit 13 (field A); 0x43EC field B; 0x83ED dazzle bit.
    assert_eq!((k(3).code, k(3).flags), (1003, 0b001));
    assert_eq!((k(4).code, k(4).flags), (1004, 0b010));
    assert_eq!((k(5).code, k(5).flags), (1005, 0b100));
    for i in 6..361 {
        assert_eq!(k(i).kind, RangeCode::Valid(1000 + i as u16), "value {i}");
        assert_eq!(k(i).flags, 0);
    }
    let mut codes = [0u16; 401];
    assert_eq!(v.range_codes(m, &mut codes), 361);
    assert_eq!(codes[360], 1360);
    // In the 32 m mode (MRPT) the same word 0x1FFF is a plain 8191 mm.
    assert_eq!(
        v.measurement(0, MeasuringMode(6)).unwrap().kind,
        RangeCode::Valid(8191)
    );
    // With the real-time index option the same payload no longer fits: an error, no panic.
    assert!(parse_reply(
        tel.payload(),
        ReplyOptions::default().with_realtime_index(true)
    )
    .is_err());
}

#[test]
fn b0_realtime_index_option() {
    let mut buf = [0u8; 32];
    let n = encode_telegram(
        0x80,
        &[0xB0, 0x02, 0x40, 0x10, 0x00, 0x20, 0x00, 0x7A, 0x10],
        &mut buf,
    )
    .unwrap();
    let t = Telegram::parse(&buf[..n]).unwrap();
    let r = parse_reply(
        t.payload(),
        ReplyOptions::default().with_realtime_index(true),
    )
    .unwrap();
    let Reply::Values(v) = r.reply else { panic!() };
    assert_eq!(v.scan_index(), Some(0x7A));
    assert_eq!(v.words().collect::<Vec<_>>(), [16, 32]);
    assert_eq!(r.status.0, 0x10);
}

#[test]
fn reserved_codes_per_mode() {
    use RangeCode::*;
    let m8 = MeasuringMode(0);
    let m16 = MeasuringMode(4);
    let m32 = MeasuringMode(6);
    assert_eq!(RangeCode::classify(8182, m8), Valid(8182));
    assert_eq!(RangeCode::classify(8183, m8), TooFar);
    assert_eq!(RangeCode::classify(8186, m8), ErrorChannel1);
    assert_eq!(RangeCode::classify(8187, m8), SnrTooSmall);
    assert_eq!(RangeCode::classify(8188, m8), Reserved(8188));
    assert_eq!(RangeCode::classify(8189, m8), OperationOverflow);
    assert_eq!(RangeCode::classify(16382, m16), Dazzling);
    assert_eq!(RangeCode::classify(16375, m16), TooFar);
    assert_eq!(RangeCode::classify(32767, m32), NotValid);
    assert_eq!(RangeCode::classify(32759, m32), TooFar);
    assert_eq!(
        RangeCode::classify(0xFFFF, MeasuringMode(0x0F)),
        Valid(0xFFFF)
    );
    // Flag bits per mode: 0x01 reflectivity in bits 13-15.
    let m = lms2xx::codec::reply::Measurement::decode(0xE005, MeasuringMode(1));
    assert_eq!((m.code, m.flags), (5, 7));
    let m = lms2xx::codec::reply::Measurement::decode(0xC005, MeasuringMode(3));
    assert_eq!((m.code, m.flags), (5, 3));
}

// ---------------------------------------------------------------- stream shapes

fn a0() -> Vec<u8> {
    hex("02 80 03 00 A0 00 10 16 0A")
}
fn b0_small() -> Vec<u8> {
    hex("02 80 0E 00 B0 05 40 E8 03 E9 03 EA 03 EB 03 FF 1F 10 1F 93")
}

#[test]
fn stream_shapes() {
    let a = a0();
    let b = b0_small();
    let full = hex(B0_FULL);
    let mut stream = vec![0x06];
    stream.extend(&a);
    stream.extend(&full);
    stream.extend(&b);
    let want = vec![
        Ev::Ack,
        Ev::T(a.clone()),
        Ev::T(full.clone()),
        Ev::T(b.clone()),
    ];

    // empty
    let (ev, st) = decode(&[]);
    assert!(ev.is_empty());
    assert_eq!(st, Default::default());
    let (ev, _) = decode(&[&[]]);
    assert!(ev.is_empty());
    // all at once
    let (ev, st) = decode(&[&stream]);
    assert_eq!(ev, want);
    assert_eq!(
        (st.telegrams, st.acks, st.bytes_skipped, st.dropped()),
        (3, 1, 0, 0)
    );
    // byte by byte
    let chunks: Vec<&[u8]> = stream.chunks(1).collect();
    assert_eq!(decode(&chunks).0, want);
    // split at every position (covers split frames and STX at the end of a chunk)
    for k in 0..=stream.len() {
        let (x, y) = stream.split_at(k);
        assert_eq!(decode(&[x, y]).0, want, "split at {k}");
    }
    // odd chunk sizes
    for size in [2, 3, 5, 7, 64, 731, 733] {
        let chunks: Vec<&[u8]> = stream.chunks(size).collect();
        assert_eq!(decode(&chunks).0, want, "chunks of {size}");
    }
    // two in one chunk
    let two = [a.clone(), a.clone()].concat();
    assert_eq!(decode(&[&two]).0, vec![Ev::T(a.clone()), Ev::T(a.clone())]);
    // garbage before, including false starts (STX + wrong address, STX + bad length, NAK)
    let mut g = vec![0x00, 0xFF, 0x02, 0x00, 0x02, 0x80, 0xFF, 0xFF, 0x15, 0x33];
    let glen = g.len();
    g.extend(&a);
    let (ev, st) = decode(&[&g]);
    assert_eq!(ev, vec![Ev::Nak, Ev::T(a.clone())]);
    assert_eq!(
        st.bytes_skipped as usize,
        glen - 1,
        "all garbage but the NAK skipped"
    );
    assert_eq!(st.bad_length, 1);
    // STX at the very end: nothing yet, then completes
    let mut d = Decoder::<MAX_TELEGRAM>::new();
    assert!(run(&mut d, &[&[0x55, 0x02]]).is_empty());
    assert_eq!(d.pending(), 1);
    assert_eq!(run(&mut d, &[&a[1..]]), vec![Ev::T(a.clone())]);
}

#[test]
fn bad_crc_then_good_starting_inside_it() {
    let a = a0();
    let b = b0_small();
    // A damaged telegram whose LEN covers a complete good telegram.
    let len = 1 + a.len() + 3;
    let mut bad = vec![0x02, 0x80, len as u8, 0x00, 0xB0];
    bad.extend(&a);
    bad.extend([0x11, 0x22, 0x33]);
    bad.extend([0xDE, 0xAD]); // wrong CRC
    assert!(Telegram::parse(&bad).is_err());
    let mut stream = bad.clone();
    stream.extend(&b);
    for k in [1, 3, stream.len()] {
        let chunks: Vec<&[u8]> = stream.chunks(k).collect();
        let (ev, st) = decode(&chunks);
        assert_eq!(ev, vec![Ev::T(a.clone()), Ev::T(b.clone())], "chunk {k}");
        assert_eq!(st.crc_errors, 1);
        // Skipped: the bad STX + its 4 other header bytes before `a`, then 3 + 2 after.
        assert_eq!(st.bytes_skipped, 5 + 5);
    }
}

#[test]
fn truncated_telegram_does_not_swallow_later_ones() {
    let full = hex(B0_FULL);
    let a = a0();
    let mut stream = full[..300].to_vec();
    for _ in 0..100 {
        stream.extend(&a);
    }
    let (ev, st) = decode(&[&stream]);
    assert_eq!(ev.len(), 100);
    assert!(ev.iter().all(|e| *e == Ev::T(a.clone())));
    assert_eq!(st.crc_errors, 1);
    assert_eq!(st.bytes_skipped, 300);
}

#[test]
fn oversized_length_rejected_before_buffering() {
    // LEN 807 (> 806) is rejected at once: the next telegram follows right after the header.
    let a = a0();
    let mut s = vec![0x02, 0x80, 0x27, 0x03];
    s.extend(&a);
    let (ev, st) = decode(&[&s]);
    assert_eq!(ev, vec![Ev::T(a.clone())]);
    assert_eq!(st.bad_length, 1);
    // A small decoder rejects a B0 that would not fit and counts an overflow.
    let mut d = Decoder::<64>::new();
    let full = hex(B0_FULL);
    let mut s = full.clone();
    s.extend(&a);
    let ev = run(&mut d, &[&s]);
    // Value bytes 0x06 / 0x15 after the rejected header read as ACK / NAK: unavoidable.
    assert_eq!(ev.last(), Some(&Ev::T(a)));
    assert_eq!(ev.iter().filter(|e| matches!(e, Ev::T(_))).count(), 1);
    let st = d.stats();
    assert_eq!(st.overflows, 1);
    assert_eq!((st.bytes_skipped + st.acks + st.naks) as usize, full.len());
}

#[test]
fn host_address_decoder_reads_commands() {
    let mut d = Decoder::<MAX_TELEGRAM>::with_address(0x00);
    let t = hex("02 00 02 00 20 24 34 08");
    assert_eq!(run(&mut d, &[&t]), vec![Ev::T(t.clone())]);
    // Device telegrams are not accepted by a host-address decoder.
    assert!(run(&mut d, &[&a0()]).is_empty());
}

// ---------------------------------------------------------------- properties

mod props {
    use super::*;
    use proptest::prelude::*;

    fn telegram() -> impl Strategy<Value = Vec<u8>> {
        prop::collection::vec(any::<u8>(), 1..60).prop_map(|p| {
            let mut buf = [0u8; 80];
            let n = encode_telegram(0x80, &p, &mut buf).unwrap();
            buf[..n].to_vec()
        })
    }

    /// Garbage without STX/ACK/NAK, so no false start can hide a real telegram.
    fn garbage() -> impl Strategy<Value = Vec<u8>> {
        prop::collection::vec(
            any::<u8>().prop_filter("no STX/ACK/NAK", |b| ![0x02, 0x06, 0x15].contains(b)),
            0..20,
        )
    }

    proptest! {
        #[test]
        fn valid_frames_in_garbage_all_delivered(
            parts in prop::collection::vec((garbage(), telegram()), 0..12),
            chunk in 1usize..100,
        ) {
            let mut stream = Vec::new();
            let mut want = Vec::new();
            let mut skipped = 0;
            for (g, t) in &parts {
                stream.extend(g);
                skipped += g.len();
                stream.extend(t);
                want.push(Ev::T(t.clone()));
            }
            let chunks: Vec<&[u8]> = stream.chunks(chunk).collect();
            let (ev, st) = decode(&chunks);
            prop_assert_eq!(ev, want);
            prop_assert_eq!(st.bytes_skipped as usize, skipped);
            prop_assert_eq!(st.dropped(), 0);
        }

        #[test]
        fn corrupted_frames_never_accepted_intact_ones_survive(
            frames in prop::collection::vec((telegram(), prop::option::of((any::<usize>(), 1u8..=255))), 1..12),
            arbitrary in prop::collection::vec(any::<u8>(), 0..40),
            chunk in 1usize..100,
        ) {
            let mut stream = arbitrary.clone();
            let mut intact = Vec::new();
            let mut originals = Vec::new();
            for (t, flips) in &frames {
                // One damaged byte per telegram: the LMS checksum always detects that (it
                // misses some two-byte errors, e.g. 0x40 then 0x80 in adjacent bytes).
                let mut c = t.clone();
                if let Some((pos, x)) = flips {
                    let i = pos % c.len();
                    c[i] ^= x;
                }
                if c == *t { intact.push(t.clone()); }
                originals.push(t.clone());
                stream.extend(&c);
            }
            // Filler so a candidate whose LEN was damaged upwards completes (and fails) before
            // the stream ends; otherwise the telegrams inside it are merely still pending.
            stream.extend([0u8; MAX_TELEGRAM]);
            let chunks: Vec<&[u8]> = stream.chunks(chunk).collect();
            let (ev, _) = decode(&chunks);
            let got: Vec<Vec<u8>> = ev.into_iter().filter_map(|e| match e { Ev::T(t) => Some(t), _ => None }).collect();
            // Every delivered telegram has a good CRC by construction; it must be one we sent
            // undamaged (a damaged one passing the 16-bit check is a 2^-16 event).
            for g in &got {
                prop_assert!(intact.contains(g), "damaged telegram accepted: {:02x?}", g);
            }
            // Every intact telegram after the last damaged one must be delivered, in order.
            let tail: Vec<_> = frames.iter().rev().take_while(|(_, f)| {
                f.is_none()
            }).map(|(t, _)| t.clone()).collect::<Vec<_>>().into_iter().rev().collect();
            prop_assert!(got.ends_with(&tail), "intact tail lost");
        }

        #[test]
        fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..2000), chunk in 1usize..900) {
            let chunks: Vec<&[u8]> = bytes.chunks(chunk).collect();
            let mut d = Decoder::<MAX_TELEGRAM>::new();
            let ev = run(&mut d, &chunks);
            let telegram_bytes: usize = ev.iter().map(|e| if let Ev::T(t) = e { t.len() } else { 0 }).sum();
            for e in ev {
                if let Ev::T(t) = e {
                    prop_assert!(Telegram::parse(&t).is_ok());
                    let _ = parse_reply(&t[4..t.len() - 2], ReplyOptions::default());
                    let _ = parse_reply(&t[4..t.len() - 2], ReplyOptions::default().with_realtime_index(true));
                }
            }
            // Conservation: every byte is in a telegram, skipped, an ACK/NAK, or still pending.
            let s = d.stats();
            prop_assert_eq!(
                telegram_bytes + (s.bytes_skipped + s.acks + s.naks) as usize + d.pending(),
                bytes.len()
            );
        }
    }
}

/// `range_codes` (two values a word) agrees with decoding value by value, for every count
/// of values, output length and measuring mode, with flag bits set in the words.
#[test]
fn range_codes_match_value_by_value() {
    use lms2xx::codec::reply::MeasuredValues;
    for n in 0..=9usize {
        let mut payload = vec![0xB0, n as u8, 0x00];
        for i in 0..n {
            // Range bits plus flag bits above them.
            let w = 0xE000u16 | (1000 + 37 * i as u16);
            payload.extend_from_slice(&w.to_le_bytes());
        }
        payload.push(0x10);
        let v = MeasuredValues::parse(&payload, ReplyOptions::default()).unwrap();
        for mode in [MeasuringMode(0), MeasuringMode(6)] {
            for len in 0..=10usize {
                let mut out = [0xFFFFu16; 10];
                let k = v.range_codes(mode, &mut out[..len]);
                assert_eq!(k, n.min(len), "n {n} len {len}");
                for (i, &code) in out.iter().enumerate() {
                    let want = if i < k {
                        v.word(i).unwrap() & mode.range_mask()
                    } else {
                        0xFFFF
                    };
                    assert_eq!(code, want, "n {n} len {len} value {i}");
                }
            }
        }
    }
}
