//! Output-frame facts the other tests leave open, checked against the COBS definition, not
//! against the code's own output (docs/TESTING.md, mutation section).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

use pfe_core::{CircleFeature, Feature, Point};
use pfe_frame::{
    decode_frame, max_frame_len, write_scan, Counters, DecodeError, EncodeError, Feed,
    FrameDecoder, Header, ScanHeader, ScanStatus, MAX_FEATURE_LEN, MAX_POSE_LEN, WIRE_VERSION,
};

/// `embedded_io::Write` for a `Vec` (the firmware crate has no `std` feature of embedded-io).
struct Writer<'a>(&'a mut Vec<u8>);
impl embedded_io::ErrorType for Writer<'_> {
    type Error = core::convert::Infallible;
}
impl embedded_io::Write for Writer<'_> {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        self.0.extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
}

/// Unsigned LEB128 from its definition (docs/FRAME.md): 7 bits a byte, least significant
/// group first, the high bit set on every byte but the last.
fn leb128(mut v: u32) -> Vec<u8> {
    let mut out = Vec::new();
    loop {
        let low = (v % 128) as u8;
        v /= 128;
        if v == 0 {
            out.push(low);
            return out;
        }
        out.push(low + 128);
    }
}

/// A frame body (COBS, without the terminator) around `raw` by the `cobs` crate.
fn cobs_body(raw: &[u8]) -> Vec<u8> {
    cobs::encode_vec(raw)
}

/// `raw` followed by its CRC-32/ISO-HDLC (by `crc32fast`), little-endian.
fn with_crc(payload: &[u8]) -> Vec<u8> {
    let mut raw = payload.to_vec();
    raw.extend(crc32fast::hash(payload).to_le_bytes());
    raw
}

/// `max_frame_len` covers the worst case of COBS: `raw` bytes (header ≤ 64, features, pose
/// block ≤ 110, CRC 4)
/// take one code byte per started run of 254, plus the terminating zero; and it adds no more
/// than one byte of slack beyond that.
#[test]
fn max_frame_len_is_the_cobs_worst_case() {
    for n in [0usize, 1, 2, 3, 10, 33, 64] {
        let raw = 64 + n * MAX_FEATURE_LEN + MAX_POSE_LEN + 4;
        let worst = raw + raw.div_ceil(254) + 1;
        let got = max_frame_len(n);
        assert!(got >= worst, "{n} features: {got} < {worst}");
        assert!(got <= worst + 1, "{n} features: {got} > {worst} + 1");
    }
}

/// COBS output holds no zero byte: a zero code inside a frame is broken COBS, whatever the
/// rest would decode to. (Hand-made: code 3 → two data bytes and a zero, then a zero code.)
#[test]
fn a_zero_code_byte_is_broken_cobs() {
    let mut buf = [0x03, 0x11, 0x22, 0x00, 0x01];
    assert_eq!(decode_frame(&mut buf), Err(DecodeError::Cobs));
    // A code that runs past the end.
    let mut buf = [0x05, 0x11, 0x22];
    assert_eq!(decode_frame(&mut buf), Err(DecodeError::Cobs));
}

/// The error messages say what went wrong, with the values involved.
#[test]
fn error_messages_name_the_values() {
    let crc = DecodeError::Crc {
        expected: 0x1234_5678,
        got: 0x0BAD_F00D,
    }
    .to_string();
    assert!(
        crc.contains("0x12345678") && crc.contains("0x0badf00d"),
        "{crc}"
    );
    let v = DecodeError::UnknownVersion { version: 7 }.to_string();
    assert!(
        v.contains('7') && v.contains(&WIRE_VERSION.to_string()),
        "{v}"
    );
    let n = DecodeError::TooManyFeatures { n: 999 }.to_string();
    assert!(n.contains("999"), "{n}");
    let others = [
        DecodeError::Overflow,
        DecodeError::Cobs,
        DecodeError::TooShort,
        DecodeError::Payload,
        DecodeError::TrailingBytes,
    ]
    .map(|e| e.to_string());
    for (i, m) in others.iter().enumerate() {
        assert!(!m.is_empty());
        assert!(!others[..i].contains(m), "two errors read {m:?}");
    }
    let w = EncodeError::Write("uart gone").to_string();
    assert!(w.contains("uart gone"), "{w}");
    assert!(!EncodeError::<()>::Serialize.to_string().is_empty());
}

/// The LEB128 helper these tests build payloads with gives the textbook vectors and the two
/// of docs/FRAME.md (`300` → `ac 02`, `123456` → `c0 c4 07`).
#[test]
fn leb128_helper_gives_the_definitions_vectors() {
    let cases: [(u32, &[u8]); 9] = [
        (0, &[0x00]),
        (127, &[0x7f]),
        (128, &[0x80, 0x01]),
        (300, &[0xac, 0x02]),
        (16383, &[0xff, 0x7f]),
        (16384, &[0x80, 0x80, 0x01]),
        (123_456, &[0xc0, 0xc4, 0x07]),
        (2_097_152, &[0x80, 0x80, 0x80, 0x01]),
        (u32::MAX, &[0xff, 0xff, 0xff, 0xff, 0x0f]),
    ];
    for (v, want) in cases {
        assert_eq!(leb128(v), want, "{v}");
    }
}

/// A circle whose encoding holds no zero byte (variant 1, beam indices below 128, every f32
/// with four non-zero bytes).
fn zero_free_circle(k: u8) -> Feature {
    let f = |i: u32| f32::from_bits(0x4123_4567 + u32::from(k) * 0x0001_0100 + i * 0x0101_0101);
    Feature::Circle(CircleFeature::new(
        10 + u16::from(k),
        30 + u16::from(k),
        17,
        Point::new(f(0), f(1)),
        f(2),
        [[f(3), f(4), f(5)], [f(6), f(7), f(8)], [f(9), f(10), f(11)]],
        f(12),
        f(13),
    ))
}

/// The payload of `Header::Scan(h)` followed by circles, built from docs/FRAME.md's tables
/// alone (version, variant index, the header's integers as LEB128 in table order, status
/// index; a circle as variant 1, first, last, points, then its 14 f32 little-endian; then the
/// pose block `None`, one byte 00).
fn spec_scan_payload(h: &ScanHeader, circles: &[Feature]) -> Vec<u8> {
    let mut p = vec![4u8, 0];
    let c = &h.counters;
    for v in [
        h.seq,
        h.time_ms,
        c.telegrams_ok,
        c.crc_dropped,
        c.bytes_skipped,
        c.reinits,
    ] {
        p.extend(leb128(v));
    }
    for v in [h.valid, h.segments, h.dropped, circles.len() as u16] {
        p.extend(leb128(u32::from(v)));
    }
    p.extend(leb128(match h.status {
        ScanStatus::Ok => 0,
        ScanStatus::FeatureCapacity => 1,
        ScanStatus::TooManyReadings => 2,
        ScanStatus::InvalidInput => 3,
    }));
    for f in circles {
        let Feature::Circle(c) = f else {
            panic!("circles only")
        };
        p.extend(leb128(1));
        for v in [c.first, c.last, c.points] {
            p.extend(leb128(u32::from(v)));
        }
        let cov = c.cov;
        for v in [c.center.x, c.center.y, c.radius]
            .into_iter()
            .chain(cov.into_iter().flatten())
            .chain([c.start_angle, c.end_angle])
        {
            p.extend(v.to_le_bytes());
        }
    }
    p.push(0);
    p
}

/// COBS (Cheshire & Baker): a run of 254 non-zero bytes is one block of code 0xFF with no
/// implied zero after it, even when more blocks follow; a zero right after such a run is an
/// empty block `01`. A scan frame whose payload is `02 00` then 321 zero-free bytes is
/// encoded `02 02`, `ff` + the next 254 payload bytes, then the rest; with a zero put at
/// payload byte 256 the block after the `ff` one is `01`. Both are byte for byte what the
/// `cobs` crate makes of the payload built from docs/FRAME.md plus `crc32fast`'s CRC, and
/// the decoder gives back exactly the values encoded.
#[test]
fn a_full_cobs_block_followed_by_more_adds_no_zero() {
    let h = ScanHeader {
        seq: 127,
        time_ms: 128,
        counters: Counters {
            telegrams_ok: 16383,
            crc_dropped: 16384,
            bytes_skipped: u32::MAX,
            reinits: 300,
        },
        valid: 355,
        segments: 9,
        dropped: 1,
        n_features: 5,
        status: ScanStatus::FeatureCapacity,
    };
    for zero_at_256 in [false, true] {
        let mut circles: Vec<Feature> = (0..5).map(zero_free_circle).collect();
        if zero_at_256 {
            // Circle 3 starts at payload byte 23 + 3·60 = 203; its f32s at 207, so byte 256
            // is byte 1 of f32 number 12 (start_angle).
            if let Feature::Circle(c) = &mut circles[3] {
                c.start_angle = f32::from_bits(0x4123_0067);
            }
        }
        let payload = spec_scan_payload(&h, &circles);
        // The header by hand: 04 (version) 00 (Scan), then 127, 128, 16383, 16384,
        // u32::MAX, 300, 355, 9, 1, 5 as LEB128, then 01 (FeatureCapacity).
        assert_eq!(
            payload[..23],
            [
                0x04, 0x00, 0x7f, 0x80, 0x01, 0xff, 0x7f, 0x80, 0x80, 0x01, 0xff, 0xff, 0xff, 0xff,
                0x0f, 0xac, 0x02, 0xe3, 0x02, 0x09, 0x01, 0x05, 0x01
            ]
        );
        assert_eq!(payload.len(), 23 + 5 * 60 + 1);
        // The last byte is the pose block `None`.
        let zeros: Vec<usize> = (2..payload.len()).filter(|&i| payload[i] == 0).collect();
        let last = payload.len() - 1;
        assert_eq!(
            zeros,
            if zero_at_256 {
                vec![256, last]
            } else {
                vec![last]
            }
        );

        let mut wire = Vec::new();
        write_scan(&mut Writer(&mut wire), &h, &circles).unwrap();
        let mut want = cobs_body(&with_crc(&payload));
        want.push(0);
        assert_eq!(
            wire, want,
            "the cobs crate's encoding of the spec's payload"
        );
        assert_eq!(wire[..3], [0x02, 0x04, 0xff]);
        assert_eq!(wire[3..257], payload[2..256]);
        if zero_at_256 {
            assert_eq!(
                wire[257], 0x01,
                "the zero after a full block: an empty block"
            );
        }

        let mut body = wire[..wire.len() - 1].to_vec();
        let frame = decode_frame(&mut body).unwrap();
        assert_eq!(frame.header, Header::Scan(h));
        assert_eq!(frame.features.as_slice(), &circles[..]);
    }
}

/// docs/FRAME.md: a frame is dropped as too short only when it has fewer than 5 bytes after
/// COBS decoding (a version byte and a CRC is the least). So 1 to 4 bytes are `TooShort`
/// (even 4 zero bytes, the CRC of the empty payload), while exactly 5 bytes with a good
/// CRC reach the version check (version 5: `UnknownVersion`) or, at version 4, the header
/// parser (no header: `Payload`).
#[test]
fn five_decoded_bytes_are_not_too_short() {
    for raw in [
        &[0x11][..],
        &[0x11, 0x22],
        &[0x11, 0x22, 0x33],
        &[0x11, 0x22, 0x33, 0x44],
        &[0, 0, 0, 0],
    ] {
        let mut body = cobs_body(raw);
        assert_eq!(
            decode_frame(&mut body),
            Err(DecodeError::TooShort),
            "{raw:?}"
        );
    }
    let mut body = cobs_body(&with_crc(&[5]));
    assert_eq!(
        decode_frame(&mut body),
        Err(DecodeError::UnknownVersion { version: 5 })
    );
    let mut body = cobs_body(&with_crc(&[WIRE_VERSION]));
    assert_eq!(decode_frame(&mut body), Err(DecodeError::Payload));
}

/// The test vector of docs/FRAME.md (its hex block: 127 bytes with the terminator) as it was in
/// version 2 (version byte 02, its CRC): the decoder still reads it.
const SPEC_VECTOR: [u8; 127] = [
    0x02, 0x02, 0x01, 0x0c, 0xc0, 0xc4, 0x07, 0xac, 0x02, 0x02, 0x11, 0x01, 0x9a, 0x01, 0x02, 0x02,
    0x02, 0x01, 0x0b, 0x70, 0xf2, 0x01, 0x83, 0x01, 0x5c, 0xfd, 0xa3, 0xb7, 0xd9, 0x10, 0xfa, 0x44,
    0xfd, 0xfc, 0xa5, 0x34, 0x2d, 0xfe, 0x30, 0x3e, 0x69, 0x8d, 0xbc, 0xb7, 0x01, 0x51, 0xfa, 0x44,
    0xb5, 0x98, 0xa8, 0xc4, 0x99, 0x01, 0xfa, 0x44, 0xa8, 0x32, 0x96, 0x44, 0x01, 0xf3, 0x01, 0x89,
    0x02, 0x17, 0xac, 0x04, 0x96, 0x44, 0xe1, 0xfb, 0x60, 0x44, 0x1a, 0x0b, 0x16, 0x43, 0xb4, 0x90,
    0x0a, 0x41, 0x50, 0x42, 0x8e, 0x40, 0xa4, 0x79, 0xd1, 0x40, 0x60, 0x42, 0x8e, 0x40, 0x96, 0x41,
    0x84, 0x40, 0x10, 0x7d, 0x7c, 0x40, 0x58, 0x79, 0xd1, 0x40, 0xa0, 0x7c, 0x7c, 0x40, 0x30, 0x69,
    0xb3, 0x40, 0x9f, 0x8b, 0xb0, 0xbf, 0x6c, 0x5f, 0x20, 0x40, 0x30, 0xcb, 0xbf, 0xfb, 0x00,
];

/// The test vector of docs/FRAME.md as it was in version 3 (the same frame as
/// [`SPEC_VECTOR`] with version byte 03 and its CRC): the decoder still reads it, without a
/// pose block.
const SPEC_VECTOR_V3: [u8; 127] = [
    0x02, 0x03, 0x01, 0x0c, 0xc0, 0xc4, 0x07, 0xac, 0x02, 0x02, 0x11, 0x01, 0x9a, 0x01, 0x02, 0x02,
    0x02, 0x01, 0x0b, 0x70, 0xf2, 0x01, 0x83, 0x01, 0x5c, 0xfd, 0xa3, 0xb7, 0xd9, 0x10, 0xfa, 0x44,
    0xfd, 0xfc, 0xa5, 0x34, 0x2d, 0xfe, 0x30, 0x3e, 0x69, 0x8d, 0xbc, 0xb7, 0x01, 0x51, 0xfa, 0x44,
    0xb5, 0x98, 0xa8, 0xc4, 0x99, 0x01, 0xfa, 0x44, 0xa8, 0x32, 0x96, 0x44, 0x01, 0xf3, 0x01, 0x89,
    0x02, 0x17, 0xac, 0x04, 0x96, 0x44, 0xe1, 0xfb, 0x60, 0x44, 0x1a, 0x0b, 0x16, 0x43, 0xb4, 0x90,
    0x0a, 0x41, 0x50, 0x42, 0x8e, 0x40, 0xa4, 0x79, 0xd1, 0x40, 0x60, 0x42, 0x8e, 0x40, 0x96, 0x41,
    0x84, 0x40, 0x10, 0x7d, 0x7c, 0x40, 0x58, 0x79, 0xd1, 0x40, 0xa0, 0x7c, 0x7c, 0x40, 0x30, 0x69,
    0xb3, 0x40, 0x9f, 0x8b, 0xb0, 0xbf, 0x6c, 0x5f, 0x20, 0x40, 0xf8, 0x37, 0x4d, 0x17, 0x00,
];

/// Both older forms of the spec's test vector (versions 2 and 3) decode to its values, with
/// no pose block.
#[test]
fn the_version_2_and_3_spec_vectors_still_decode() {
    for v in [SPEC_VECTOR, SPEC_VECTOR_V3] {
        let mut body = v[..v.len() - 1].to_vec();
        let frame = decode_frame(&mut body).unwrap();
        check_spec_frame(&frame.header, &frame.features);
        assert_eq!(frame.pose, None);
    }
}

/// The frame of docs/FRAME.md's test vector, with the values the page reads from it.
fn check_spec_frame(header: &Header, features: &[Feature]) {
    let want = ScanHeader {
        seq: 0,
        time_ms: 123_456,
        counters: Counters {
            telegrams_ok: 300,
            crc_dropped: 2,
            bytes_skipped: 17,
            reinits: 1,
        },
        valid: 154,
        segments: 2,
        dropped: 0,
        n_features: 2,
        status: ScanStatus::Ok,
    };
    assert_eq!(*header, Header::Scan(want));
    let [Feature::Line(l), Feature::Circle(c)] = features else {
        panic!("a line and a circle: {features:?}")
    };
    assert_eq!((l.first, l.last, l.points), (112, 242, 131));
    assert_eq!(l.rho, 2000.0265);
    assert_eq!((c.first, c.last, c.points), (243, 265, 23));
    assert_eq!(c.radius, 150.04337);
}

/// A receiver collects bytes up to a `0x00` (docs/FRAME.md): the spec's test vector, followed
/// by two more bytes, fed in two pieces split at every byte boundary, gives its frame once,
/// with exactly the bytes after the terminator in the piece that held it left over (none of
/// them consumed, the terminator not among them); fed a byte at a time, every byte before
/// the terminator is consumed.
#[test]
fn feeding_the_spec_vector_split_anywhere_leaves_exactly_the_bytes_after_it() {
    let mut data = SPEC_VECTOR.to_vec();
    data.extend([0x55, 0x66]);
    let end = SPEC_VECTOR.len();
    for k in 0..=data.len() {
        let mut dec = FrameDecoder::<4096>::new();
        let (first, second) = data.split_at(k);
        let (frame, remaining) = match dec.feed(first) {
            Feed::Consumed => {
                assert!(k < end, "split {k}: the terminator was in the first piece");
                match dec.feed(second) {
                    Feed::Frame { frame, remaining } => (frame, remaining),
                    other => panic!("split {k}: {other:?}"),
                }
            }
            Feed::Frame { frame, remaining } => {
                assert!(k >= end, "split {k}: a frame before its terminator");
                (frame, remaining)
            }
            Feed::Error { error, .. } => panic!("split {k}: {error:?}"),
        };
        check_spec_frame(&frame.header, &frame.features);
        // What follows the terminator in the piece that held it.
        let after = if k < end { &data[end..] } else { &data[end..k] };
        assert_eq!(remaining, after, "split {k}");
    }
    let mut dec = FrameDecoder::<4096>::new();
    for (i, b) in SPEC_VECTOR.iter().enumerate() {
        match dec.feed(core::slice::from_ref(b)) {
            Feed::Consumed => assert!(i + 1 < end, "byte {i}"),
            Feed::Frame { frame, remaining } => {
                assert_eq!(i + 1, end, "byte {i}");
                assert!(remaining.is_empty(), "byte {i}: {remaining:?}");
                check_spec_frame(&frame.header, &frame.features);
            }
            Feed::Error { error, .. } => panic!("byte {i}: {error:?}"),
        }
    }
}

/// docs/FRAME.md sizes frames with 70 bytes a feature and 110 for the pose block: at most 64
/// features make a decoded frame of ≤ 64 + 64·70 + 110 + 4 = 4658 bytes and an encoded one of
/// ≤ 4678 bytes with its terminator (4658 + ⌈4658/254⌉ = 19 code bytes + 1). The largest feature really encoded, a
/// circle with 3-byte beam indices (variant 1 byte, 3 × 3 bytes, 14 f32 = 56 bytes: 66),
/// fits the 70.
#[test]
fn max_feature_len_and_max_frame_len_are_the_frame_md_figures() {
    assert_eq!(MAX_FEATURE_LEN, 70);
    assert_eq!(MAX_POSE_LEN, 110);
    assert_eq!(max_frame_len(64), 4678);
    assert_eq!(max_frame_len(0), 64 + 110 + 4 + 1 + 1);
    let big = Feature::Circle(CircleFeature::new(
        u16::MAX,
        u16::MAX,
        u16::MAX,
        Point::new(1.0, 2.0),
        3.0,
        [[4.0; 3]; 3],
        5.0,
        6.0,
    ));
    let h = ScanHeader::default();
    let payload_len = |features: &[Feature]| {
        let mut wire = Vec::new();
        write_scan(&mut Writer(&mut wire), &h, features).unwrap();
        cobs::decode_vec(&wire[..wire.len() - 1]).unwrap().len()
    };
    let one = payload_len(&[big]) - payload_len(&[]);
    assert_eq!(one, 66);
    assert!(one <= MAX_FEATURE_LEN);
}
