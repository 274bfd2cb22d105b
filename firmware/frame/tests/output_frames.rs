//! Output frames: round trips, stream shapes, corruption detection, and the format checked
//! against independent implementations (the `cobs` crate and `crc32fast`).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

use pfe_core::{CircleFeature, Feature, LineFeature, Point};
use pfe_frame::{
    crc32, max_frame_len, write_report, write_scan, write_scan_with_pose, Counters, DecodeError,
    Feed, Frame, FrameDecoder, Header, PoseBlock, PoseCov, PoseFailure, PoseStatus, Report,
    ScanHeader, ScanStatus, Stage, MAX_FEATURES, WIRE_VERSION,
};

fn line(i: u16) -> Feature {
    Feature::Line(LineFeature::new(
        i,
        i + 20,
        19,
        -2.5 + f32::from(i) * 0.01,
        1234.567 + f32::from(i),
        1.5e-7,
        3.25,
        -2.0e-5,
        Point::new(100.0, -0.0),
        Point::new(f32::MIN_POSITIVE, 7e30),
    ))
}

fn circle(i: u16) -> Feature {
    Feature::Circle(CircleFeature::new(
        i,
        i + 9,
        10,
        Point::new(1500.25, -320.5),
        100.0 + f32::from(i),
        [[1.0, 0.5, -0.25], [0.5, 2.0, 0.0], [-0.25, 0.0, 3.0]],
        -3.0,
        3.1,
    ))
}

fn header(seq: u32, n: u16) -> ScanHeader {
    ScanHeader {
        seq,
        time_ms: 4_000_000_000 - seq,
        counters: Counters {
            telegrams_ok: 1000 + seq,
            crc_dropped: 3,
            bytes_skipped: 70_000,
            reinits: 1,
        },
        valid: 355,
        segments: 9,
        dropped: 0,
        n_features: n,
        status: ScanStatus::FeatureCapacity,
    }
}

fn scan_frame(seq: u32, features: &[Feature]) -> Vec<u8> {
    let mut out = Vec::new();
    write_scan(&mut Writer(&mut out), &header(seq, 0), features).unwrap();
    out
}

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

/// Feeds `chunks` and collects every frame / error.
fn decode_chunks<'a>(
    dec: &mut FrameDecoder<8192>,
    chunks: impl IntoIterator<Item = &'a [u8]>,
) -> Vec<Result<Frame, DecodeError>> {
    let mut out = Vec::new();
    for chunk in chunks {
        let mut rest = chunk;
        loop {
            match dec.feed(rest) {
                Feed::Consumed => break,
                Feed::Frame { frame, remaining } => {
                    out.push(Ok(frame));
                    rest = remaining;
                }
                Feed::Error { error, remaining } => {
                    out.push(Err(error));
                    rest = remaining;
                }
            }
        }
    }
    out
}

fn mixed() -> Vec<Feature> {
    (0..12)
        .map(|i| {
            if i % 3 == 0 {
                circle(i * 25)
            } else {
                line(i * 25)
            }
        })
        .collect()
}

fn bits(f: &Feature) -> Vec<u32> {
    match f {
        Feature::Line(l) => [
            l.alpha,
            l.rho,
            l.var_alpha,
            l.var_rho,
            l.cov_alpha_rho,
            l.start.x,
            l.start.y,
            l.end.x,
            l.end.y,
        ]
        .iter()
        .map(|v| v.to_bits())
        .collect(),
        Feature::Circle(c) => c
            .cov
            .iter()
            .flatten()
            .chain([c.center.x, c.center.y, c.radius, c.start_angle, c.end_angle].iter())
            .map(|v| v.to_bits())
            .collect(),
        Feature::Object(o) => o.values().iter().map(|v| v.to_bits()).collect(),
        _ => Vec::new(),
    }
}

#[test]
fn round_trip_is_bit_exact() {
    let feats = mixed();
    let wire = scan_frame(42, &feats);
    assert_eq!(wire.last(), Some(&0));
    assert_eq!(
        wire.iter().filter(|b| **b == 0).count(),
        1,
        "one zero: the terminator"
    );
    assert!(wire.len() <= max_frame_len(feats.len()));
    let got = decode_chunks(&mut FrameDecoder::new(), [&wire[..]]);
    assert_eq!(got.len(), 1);
    let frame = got[0].as_ref().unwrap();
    assert_eq!(frame.header, Header::Scan(header(42, 12)));
    let back: Vec<Feature> = frame.features.to_vec();
    assert_eq!(back, feats);
    for (a, b) in back.iter().zip(&feats) {
        assert_eq!(bits(a), bits(b), "bit-exact, including -0.0");
    }
}

#[test]
fn empty_scan_and_reports_round_trip() {
    let reports = [
        Report::Stack {
            used: 2400,
            size: 16384,
        },
        Report::Timing {
            seq: 3,
            stage: Stage::Pipeline,
            ticks: 16_000_000,
            points: 361,
        },
        Report::Done { scans: u32::MAX },
    ];
    let mut wire = scan_frame(0, &[]);
    for r in &reports {
        write_report(&mut Writer(&mut wire), r).unwrap();
    }
    let got = decode_chunks(&mut FrameDecoder::new(), [&wire[..]]);
    assert_eq!(got.len(), 4);
    let f0 = got[0].as_ref().unwrap();
    assert_eq!(f0.scan().unwrap().n_features, 0);
    assert!(f0.features.is_empty());
    for (g, r) in got[1..].iter().zip(&reports) {
        assert_eq!(g.as_ref().unwrap().header, Header::Report(*r));
    }
}

#[test]
fn format_matches_independent_cobs_and_crc32() {
    let feats = mixed();
    let wire = scan_frame(9, &feats);
    let body = &wire[..wire.len() - 1];
    let raw = cobs::decode_vec(body).expect("the cobs crate decodes our frame");
    let (payload, crc) = raw.split_at(raw.len() - 4);
    assert_eq!(
        u32::from_le_bytes(crc.try_into().unwrap()),
        crc32fast::hash(payload)
    );
    assert_eq!(crc32(0, b"123456789"), 0xCBF4_3926);
    // The payload starts with the version byte, then the postcard header: variant 0 (Scan),
    // then seq 9 as a varint.
    assert_eq!(&payload[..3], &[WIRE_VERSION, 0, 9]);
    // A frame built by the cobs crate from our payload decodes too (encoders agree).
    let mut other = cobs::encode_vec(&raw);
    other.push(0);
    assert_eq!(other, wire);
}

#[test]
fn long_zero_free_runs_use_full_cobs_blocks() {
    // 64 lines with no zero bytes in their floats give runs longer than 254 bytes.
    let feats: Vec<Feature> = (1..=MAX_FEATURES as u16).map(|i| line(i + 1)).collect();
    let wire = scan_frame(0x0102_0304, &feats);
    let raw = cobs::decode_vec(&wire[..wire.len() - 1]).unwrap();
    assert!(raw.len() > 600);
    let got = decode_chunks(&mut FrameDecoder::new(), [&wire[..]]);
    assert_eq!(got[0].as_ref().unwrap().features.len(), MAX_FEATURES);
}

#[test]
fn stream_shapes() {
    let a = scan_frame(1, &mixed());
    let b = scan_frame(2, &[line(5)]);
    let mut both = a.clone();
    both.extend_from_slice(&b);
    let seqs = |r: Vec<Result<Frame, DecodeError>>| -> Vec<Result<u32, DecodeError>> {
        r.into_iter()
            .map(|f| f.map(|f| f.scan().unwrap().seq))
            .collect()
    };
    // All at once (two frames in one chunk).
    assert_eq!(
        seqs(decode_chunks(&mut FrameDecoder::new(), [&both[..]])),
        [Ok(1), Ok(2)]
    );
    // Byte by byte.
    assert_eq!(
        seqs(decode_chunks(&mut FrameDecoder::new(), both.chunks(1))),
        [Ok(1), Ok(2)]
    );
    // Split at every position.
    for cut in 0..both.len() {
        let (x, y) = both.split_at(cut);
        assert_eq!(
            seqs(decode_chunks(&mut FrameDecoder::new(), [x, y])),
            [Ok(1), Ok(2)],
            "cut at {cut}"
        );
    }
    // Joining mid-frame: the tail of `a` is rejected, `b` survives.
    let tail = &both[a.len() / 2..];
    let got = seqs(decode_chunks(&mut FrameDecoder::new(), [tail]));
    assert_eq!(got.len(), 2);
    assert!(got[0].is_err());
    assert_eq!(got[1], Ok(2));
    // Leading zeros (resync markers) are ignored.
    let mut z = vec![0, 0, 0];
    z.extend_from_slice(&b);
    assert_eq!(
        seqs(decode_chunks(&mut FrameDecoder::new(), [&z[..]])),
        [Ok(2)]
    );
}

#[test]
fn every_single_bit_flip_is_detected() {
    let wire = scan_frame(77, &mixed());
    let good = scan_frame(78, &[circle(3)]);
    for byte in 0..wire.len() - 1 {
        for bit in 0..8 {
            let mut bad = wire.clone();
            bad[byte] ^= 1 << bit;
            bad.extend_from_slice(&good);
            let got = decode_chunks(&mut FrameDecoder::new(), [&bad[..]]);
            let frames: Vec<&Frame> = got.iter().filter_map(|r| r.as_ref().ok()).collect();
            assert_eq!(frames.len(), 1, "byte {byte} bit {bit}: {got:?}");
            assert_eq!(frames[0].scan().unwrap().seq, 78, "the next frame survives");
        }
    }
}

#[test]
fn crc_error_carries_both_values() {
    let mut raw = cobs::decode_vec(&{
        let w = scan_frame(5, &[line(1)]);
        w[..w.len() - 1].to_vec()
    })
    .unwrap();
    let n = raw.len();
    raw[n - 1] ^= 0x80; // damage the CRC itself
    let mut wire = cobs::encode_vec(&raw);
    wire.push(0);
    let got = decode_chunks(&mut FrameDecoder::new(), [&wire[..]]);
    match got[0] {
        Err(DecodeError::Crc { expected, got }) => assert_eq!(expected ^ got, 0x8000_0000),
        ref other => panic!("{other:?}"),
    }
}

#[test]
fn overflow_resets_and_next_frame_decodes() {
    let big = scan_frame(1, &mixed());
    let small = scan_frame(2, &[]);
    let mut dec = FrameDecoder::<64>::new();
    let mut stream = big.clone();
    stream.extend_from_slice(&small);
    let mut rest = &stream[..];
    let mut out = Vec::new();
    loop {
        match dec.feed(rest) {
            Feed::Consumed => break,
            Feed::Frame { frame, remaining } => {
                out.push(Ok(frame.scan().unwrap().seq));
                rest = remaining;
            }
            Feed::Error { error, remaining } => {
                out.push(Err(error));
                rest = remaining;
            }
        }
    }
    assert_eq!(out, [Err(DecodeError::Overflow), Ok(2)]);
}

#[test]
fn too_many_features_and_trailing_bytes_are_rejected() {
    let feats: Vec<Feature> = (0..MAX_FEATURES as u16 + 1).map(line).collect();
    let wire = scan_frame(1, &feats);
    let got = decode_chunks(&mut FrameDecoder::new(), [&wire[..]]);
    assert_eq!(got, [Err(DecodeError::TooManyFeatures { n: 65 })]);

    // A report followed by an extra byte, with a valid CRC.
    let mut w = Vec::new();
    write_report(&mut Writer(&mut w), &Report::Done { scans: 1 }).unwrap();
    let mut raw = cobs::decode_vec(&w[..w.len() - 1]).unwrap();
    raw.truncate(raw.len() - 4);
    raw.push(0x55);
    let crc = crc32fast::hash(&raw);
    raw.extend_from_slice(&crc.to_le_bytes());
    let mut wire = cobs::encode_vec(&raw);
    wire.push(0);
    let got = decode_chunks(&mut FrameDecoder::new(), [&wire[..]]);
    assert_eq!(got, [Err(DecodeError::TrailingBytes)]);

    // Garbage between zeros never panics and never yields a frame.
    let got = decode_chunks(
        &mut FrameDecoder::new(),
        [&[0xFF, 1, 2, 0, 3, 0, 9, 9, 9, 9, 9, 0][..]],
    );
    assert!(got.iter().all(|r| r.is_err()), "{got:?}");
}

/// Re-frames `wire`'s payload after `edit` with a fresh CRC (an intact frame of other content).
fn reframed(wire: &[u8], edit: impl FnOnce(&mut Vec<u8>)) -> Vec<u8> {
    let mut raw = cobs::decode_vec(&wire[..wire.len() - 1]).unwrap();
    raw.truncate(raw.len() - 4);
    edit(&mut raw);
    let crc = crc32fast::hash(&raw);
    raw.extend_from_slice(&crc.to_le_bytes());
    let mut out = cobs::encode_vec(&raw);
    out.push(0);
    out
}

#[test]
fn version_is_the_first_payload_byte_and_time_travels() {
    let wire = scan_frame(3, &[line(1)]);
    let raw = cobs::decode_vec(&wire[..wire.len() - 1]).unwrap();
    assert_eq!(raw[0], WIRE_VERSION);
    assert_eq!(WIRE_VERSION, 4);
    let got = decode_chunks(&mut FrameDecoder::new(), [&wire[..]]);
    assert_eq!(
        got[0].as_ref().unwrap().scan().unwrap().time_ms,
        4_000_000_000 - 3
    );
}

#[test]
fn an_intact_frame_of_another_version_is_dropped_not_misparsed() {
    let good = scan_frame(1, &mixed());
    let mut stream = Vec::new();
    for v in [0u8, 1, 5, 0xFF] {
        stream.extend(reframed(&good, |raw| raw[0] = v));
    }
    // Version 5 with a payload that would also parse as version 4.
    stream.extend(reframed(&good, |raw| raw[0] = 5));
    stream.extend_from_slice(&scan_frame(2, &[]));
    let got = decode_chunks(&mut FrameDecoder::new(), [&stream[..]]);
    let errs: Vec<_> = got
        .iter()
        .filter_map(|r| r.as_ref().err().copied())
        .collect();
    assert_eq!(
        errs,
        [0u8, 1, 5, 0xFF, 5].map(|version| DecodeError::UnknownVersion { version })
    );
    assert_eq!(got.last().unwrap().as_ref().unwrap().scan().unwrap().seq, 2);
    // A damaged frame is a CRC error even when the damage is in the version byte.
    let mut bad = good.clone();
    bad[1] ^= 0x01;
    let got = decode_chunks(&mut FrameDecoder::new(), [&bad[..]]);
    assert!(matches!(got[..], [Err(DecodeError::Crc { .. })]), "{got:?}");
}

/// A small object round-trips bit for bit (tag 2, its seven floats in declaration order).
#[test]
fn an_object_round_trips() {
    let o = Feature::Object(pfe_core::ObjectFeature::new(
        40,
        43,
        4,
        pfe_core::Point::new(1234.5, -67.25),
        [[16.5, -2.0], [-2.0, 9.25]],
        38.0,
    ));
    let features = [line(1), o, circle(60)];
    let wire = scan_frame(9, &features);
    let got = decode_chunks(&mut FrameDecoder::new(), [&wire[..]]);
    let frame = got[0].as_ref().unwrap();
    assert_eq!(frame.features.len(), 3);
    for (a, b) in frame.features.iter().zip(&features) {
        assert_eq!(bits(a), bits(b));
        assert_eq!(a, b);
    }
}

/// Version 2 frames (lines and circles, the same layout) still decode: a frame of version 2
/// built byte by byte here, as postcard wrote it (version, header variant 0, seq, time,
/// four link counters, valid, segments, dropped, n_features, status 0; then one line).
#[test]
fn a_version_2_frame_still_decodes() {
    let mut raw = vec![2u8, 0, 7, 100, 1, 0, 0, 0, 181, 1, 3, 0, 1, 0];
    // A line: tag 0, first 5, last 20, points 16, then α, ρ, σ_α², σ_ρ², cov, start, end.
    raw.extend_from_slice(&[0, 5, 20, 16]);
    let values = [0.5f32, 2000.0, 1e-4, 4.0, -0.01, 1.0, 2.0, 3.0, 4.0];
    for v in values {
        raw.extend_from_slice(&v.to_le_bytes());
    }
    let crc = crc32fast::hash(&raw);
    raw.extend_from_slice(&crc.to_le_bytes());
    let mut wire = cobs::encode_vec(&raw);
    wire.push(0);
    let got = decode_chunks(&mut FrameDecoder::new(), [&wire[..]]);
    let frame = got[0].as_ref().unwrap();
    let h = frame.scan().unwrap();
    assert_eq!((h.seq, h.time_ms, h.valid, h.n_features), (7, 100, 181, 1));
    let [Feature::Line(l)] = frame.features[..] else {
        panic!("{:?}", frame.features)
    };
    assert_eq!((l.first, l.last, l.points), (5, 20, 16));
    assert_eq!(l.values(), values);
}

#[test]
fn a_feature_with_an_unknown_variant_or_overlong_varint_is_rejected() {
    let good = scan_frame(1, &[line(1)]);
    let hdr_len = {
        let raw = cobs::decode_vec(&good[..good.len() - 1]).unwrap();
        // line(1): tag 0, first 1, last 21, points 19: 1 byte each; then the pose block `None`.
        raw.len() - 4 - (4 + 9 * 4) - 1
    };
    let tag3 = reframed(&good, |raw| raw[hdr_len] = 3);
    // Tag 2 (a small object) is not in version 2.
    let old_tag2 = reframed(&good, |raw| {
        raw[0] = 2;
        raw[hdr_len] = 2;
    });
    // Tag 2 is fine in version 3 (then no pose block follows).
    let v3_tag2 = reframed(&good, |raw| {
        raw[0] = 3;
        raw.pop();
    });
    let got = decode_chunks(&mut FrameDecoder::new(), [&v3_tag2[..]]);
    assert!(got[0].is_ok(), "{got:?}");
    let long = reframed(&good, |raw| {
        raw[hdr_len + 1] = 0x81;
        raw.insert(hdr_len + 2, 0x80);
        raw.insert(hdr_len + 3, 0x80);
    });
    for wire in [tag3, old_tag2, long] {
        let got = decode_chunks(&mut FrameDecoder::new(), [&wire[..]]);
        assert_eq!(got, [Err(DecodeError::Payload)]);
    }
}

mod props {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Any bytes, in any chunking, never panic; a good frame after a zero always decodes.
        #[test]
        fn noise_then_frame(noise in proptest::collection::vec(any::<u8>(), 0..600),
                            cut in 0usize..700) {
            let good = scan_frame(31, &mixed());
            let mut stream = noise.clone();
            stream.push(0);
            stream.extend_from_slice(&good);
            let cut = cut.min(stream.len());
            let got = decode_chunks(&mut FrameDecoder::new(), [&stream[..cut], &stream[cut..]]);
            let last = got.last().unwrap().as_ref().unwrap();
            prop_assert_eq!(last.scan().unwrap().seq, 31);
            prop_assert_eq!(last.features.len(), 12);
        }

        /// Features of any bit patterns (zero bytes anywhere, runs of every length): the frame
        /// is exactly what the `cobs` crate makes of the postcard payload and its CRC-32.
        #[test]
        fn any_payload_matches_independent_cobs(
            words in proptest::collection::vec((any::<u32>(), 0u8..4), 5..400),
            lens in proptest::collection::vec(0u16..400, 1..64),
            sparse in 0u32..10,
        ) {
            // Bit patterns with a zero byte in a random place, in one word of 2^sparse (the
            // rest made zero-free): long zero-free runs fill COBS blocks at every offset.
            let f = |i: usize| {
                let (w, z) = words[i % words.len()];
                f32::from_bits(if (w >> 7) % (1 << sparse) == 0 {
                    w & !(0xFF << (8 * u32::from(z)))
                } else {
                    w | 0x0101_0101
                })
            };
            let feats: Vec<Feature> = lens
                .iter()
                .enumerate()
                .map(|(k, &n)| {
                    let i = 9 * k;
                    Feature::Line(LineFeature::new(n, n.wrapping_mul(3), n / 2, f(i), f(i + 1), f(i + 2), f(i + 3), f(i + 4), Point::new(f(i + 5), f(i + 6)), Point::new(f(i + 7), f(i + 8))))
                })
                .collect();
            let wire = scan_frame(u32::from(lens[0]), &feats);
            let raw = cobs::decode_vec(&wire[..wire.len() - 1]).unwrap();
            let (payload, crc) = raw.split_at(raw.len() - 4);
            prop_assert_eq!(u32::from_le_bytes(crc.try_into().unwrap()), crc32fast::hash(payload));
            let mut other = cobs::encode_vec(&raw);
            other.push(0);
            prop_assert_eq!(other, wire);
        }

        /// Random damage to a frame (any bytes replaced) never yields a different frame.
        #[test]
        fn damage_never_yields_a_wrong_frame(pos in proptest::collection::vec((0usize..400, 1u8..=255), 1..6)) {
            let wire = scan_frame(5, &mixed());
            let mut bad = wire.clone();
            let n = bad.len() - 1;
            for (p, x) in pos {
                bad[p % n] ^= x;
            }
            let got = decode_chunks(&mut FrameDecoder::new(), [&bad[..]]);
            for f in got.iter().flatten() {
                prop_assert_eq!(f.scan().unwrap().seq, 5);
                let want: Vec<Feature> = mixed();
                prop_assert_eq!(f.features.as_slice(), want.as_slice());
            }
        }
    }
}

/// A pose block with every field distinct, the covariance a little asymmetric (as computed).
fn pose_block(status: PoseStatus) -> PoseBlock {
    let cov = |k: f32| {
        [
            [25.0 * k, 1.5, -0.01],
            [1.5000001, 36.0 * k, 0.02],
            [-0.01, 0.02, 4e-5 * k],
        ]
    };
    PoseBlock {
        rel: PoseCov {
            x: 123.25,
            y: -4.5,
            theta: 0.0625,
            cov: cov(1.0),
        },
        pose: PoseCov {
            x: -9876.5,
            y: 43210.0,
            theta: -3.0,
            cov: cov(7.0),
        },
        status,
    }
}

/// The pose block of a version-4 scan frame round-trips bit for bit, for every status, after
/// features and with none; a frame written without one decodes with `pose: None`.
#[test]
fn the_pose_block_round_trips() {
    let statuses = [
        PoseStatus::Ok,
        PoseStatus::Degenerate {
            direction: [0.6, -0.8, 1e-3],
        },
        PoseStatus::None(PoseFailure::NoConsensus),
        PoseStatus::None(PoseFailure::Other),
    ];
    for (k, status) in statuses.into_iter().enumerate() {
        let p = pose_block(status);
        for features in [vec![], mixed()] {
            let mut w = Vec::new();
            let h = ScanHeader {
                seq: k as u32,
                ..ScanHeader::default()
            };
            write_scan_with_pose(&mut Writer(&mut w), &h, &features, Some(&p)).unwrap();
            assert!(w.len() <= max_frame_len(features.len()));
            let got = decode_chunks(&mut FrameDecoder::new(), [&w[..]]);
            let frame = got[0].as_ref().unwrap();
            assert_eq!(frame.features.len(), features.len());
            let q = frame.pose.expect("a pose block");
            let bits = |b: &PoseBlock| {
                let mut v = Vec::new();
                for c in [b.rel, b.pose] {
                    v.extend([c.x, c.y, c.theta].map(f32::to_bits));
                    v.extend(c.cov.iter().flatten().map(|x| x.to_bits()));
                }
                v
            };
            assert_eq!(bits(&q), bits(&p));
            assert_eq!(q.status, p.status);
        }
    }
    let got = decode_chunks(&mut FrameDecoder::new(), [&scan_frame(3, &[line(1)])[..]]);
    assert_eq!(got[0].as_ref().unwrap().pose, None);
}

/// A version-4 scan frame without its pose block, or with a broken one, is damage; a
/// version-3 frame with one has trailing bytes; a version-3 timing report of a pose stage is
/// damage.
#[test]
fn a_missing_or_broken_pose_block_is_rejected() {
    let mut good = Vec::new();
    let p = pose_block(PoseStatus::Ok);
    write_scan_with_pose(
        &mut Writer(&mut good),
        &ScanHeader::default(),
        &[line(1)],
        Some(&p),
    )
    .unwrap();
    let cut = reframed(&good, |raw| raw.truncate(raw.len() - 12 * 4 - 1));
    let none = reframed(&scan_frame(1, &[line(1)]), |raw| {
        raw.pop();
    });
    let bad_tag = reframed(&scan_frame(1, &[line(1)]), |raw| {
        *raw.last_mut().unwrap() = 2;
    });
    let bad_status = reframed(&good, |raw| {
        *raw.last_mut().unwrap() = 9;
    });
    for wire in [cut, none, bad_tag, bad_status] {
        let got = decode_chunks(&mut FrameDecoder::new(), [&wire[..]]);
        assert_eq!(got, [Err(DecodeError::Payload)]);
    }
    let v3 = reframed(&good, |raw| raw[0] = 3);
    let got = decode_chunks(&mut FrameDecoder::new(), [&v3[..]]);
    assert_eq!(got, [Err(DecodeError::TrailingBytes)]);
    let report = |version: u8, stage: Stage| {
        let mut w = Vec::new();
        write_report(
            &mut Writer(&mut w),
            &Report::Timing {
                seq: 1,
                stage,
                ticks: 5,
                points: 361,
            },
        )
        .unwrap();
        let wire = reframed(&w, |raw| raw[0] = version);
        decode_chunks(&mut FrameDecoder::new(), [&wire[..]])
    };
    assert!(report(4, Stage::Pose)[0].is_ok());
    assert!(report(3, Stage::Pipeline)[0].is_ok());
    assert_eq!(report(3, Stage::PipelinePose), [Err(DecodeError::Payload)]);
}
