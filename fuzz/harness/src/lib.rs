//! Bodies of the cargo-fuzz targets in `fuzz/fuzz_targets/`: each takes the fuzzer's bytes,
//! drives one parser or the extractor and checks its invariants with `assert!` (a failed
//! assertion is a crash libFuzzer reports, like any panic in the code under test).
//!
//! The bodies live in this ordinary library so that the same checks also run under plain
//! `cargo test` (`tests/regressions.rs` replays every committed regression input and the
//! generated seeds) without nightly or libFuzzer. [`seeds`] writes the seed corpora.
//!
//! ```
//! // The protocol's reference B0 telegram, all at once (chunk byte 0), must decode.
//! let mut input = vec![0x00, 0x00];
//! input.extend([0x02, 0x80, 0x0A, 0x00, 0xB0, 0x03, 0x00, 0x64, 0x00, 0xC8, 0x00, 0x2C, 0x01, 0x10, 0xBE, 0x64]);
//! assert_eq!(pfe_fuzz_harness::lms_decoder(&input), 1);
//! ```
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod lms_driver;
pub mod lms_driver_async;
pub mod seeds;

pub use lms_driver::lms_driver;
pub use lms_driver_async::lms_driver_async;

use std::io::Cursor;

use lms2xx::codec::frame::{encode_telegram, Telegram, MAX_TELEGRAM, STX};
use lms2xx::codec::frame::{Decoder, DecoderStats, Event};
use lms2xx::codec::reply::{parse_reply, Reply, ReplyOptions};
use lms2xx::codec::types::MeasuringMode;
use pfe_core::{Config, ExtractError, Extractor, Feature, Scan, ScanGeometry};
use pfe_formats::{scans, Format};
use pfe_frame::{write_report, write_scan, Feed, Frame, FrameDecoder, Header};

/// A deterministic chunking of a byte stream, chosen by the fuzzer's first two bytes.
#[derive(Clone, Copy, Debug)]
pub struct Chunker {
    mode: u8,
    state: u32,
}

impl Chunker {
    /// `a & 3`: 0 all at once, 1 byte by byte, 2 fixed size `(a >> 2) + 1`, 3 pseudo-random
    /// sizes 1..=`(a >> 2) + 1`·8 from an xorshift seeded by `a` and `b`.
    pub fn new(a: u8, b: u8) -> Self {
        Self {
            mode: a,
            state: (u32::from(a) << 8 | u32::from(b)) | 0x1_0000,
        }
    }

    /// Size of the next chunk (≥ 1).
    pub fn next_len(&mut self) -> usize {
        let size = usize::from(self.mode >> 2) + 1;
        match self.mode & 3 {
            0 => usize::MAX,
            1 => 1,
            2 => size,
            _ => {
                let mut x = self.state;
                x ^= x << 13;
                x ^= x >> 17;
                x ^= x << 5;
                self.state = x;
                (x as usize % (size * 8)) + 1
            }
        }
    }

    /// Splits `data` into chunks.
    pub fn chunks(mut self, data: &[u8]) -> Vec<&[u8]> {
        let mut out = Vec::new();
        let mut rest = data;
        while !rest.is_empty() {
            let (a, b) = rest.split_at(self.next_len().min(rest.len()));
            out.push(a);
            rest = b;
        }
        out
    }
}

/// What a decoder produced from a stream, in order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Seen {
    /// ACK event.
    Ack,
    /// NAK event.
    Nak,
    /// Telegram (raw bytes).
    Telegram(Vec<u8>),
}

/// Feeds `chunks` to `dec` the way a driver does (call again with the unconsumed rest until
/// the decoder returns no event), checking every event; returns the events.
pub fn drive<const CAP: usize>(dec: &mut Decoder<CAP>, chunks: &[&[u8]]) -> Vec<Seen> {
    let mut seen = Vec::new();
    for chunk in chunks {
        let mut rest: &[u8] = chunk;
        loop {
            let (used, ev) = dec.feed(rest);
            assert!(
                used <= rest.len(),
                "consumed {used} of {} bytes",
                rest.len()
            );
            rest = &rest[used..];
            match ev {
                None => {
                    assert!(
                        rest.is_empty(),
                        "no event but {} bytes unconsumed",
                        rest.len()
                    );
                    break;
                }
                Some(Event::Ack) => seen.push(Seen::Ack),
                Some(Event::Nak) => seen.push(Seen::Nak),
                Some(Event::Telegram(t)) => {
                    check_telegram(&t, CAP);
                    seen.push(Seen::Telegram(t.raw().to_vec()));
                }
            }
        }
    }
    // Nothing further may come out without new bytes.
    let (used, ev) = dec.feed(&[]);
    assert_eq!(used, 0);
    assert!(ev.is_none(), "an event without input: {ev:?}");
    seen
}

/// Every telegram a decoder delivers: CRC good, length within the protocol and the buffer,
/// and it is exactly the encoding of its own address and payload. Its reply parses without
/// panicking, and a B0 reply's values are consistent with its count word.
pub fn check_telegram(t: &Telegram<'_>, cap: usize) {
    let raw = t.raw();
    assert!(
        raw.len() <= MAX_TELEGRAM && raw.len() <= cap,
        "{} bytes",
        raw.len()
    );
    assert!(
        Telegram::parse(raw).is_ok(),
        "delivered a bad telegram {raw:02x?}"
    );
    assert_eq!(raw.first(), Some(&STX));
    let mut buf = [0u8; MAX_TELEGRAM];
    let n = encode_telegram(t.address(), t.payload(), &mut buf);
    assert_eq!(
        n.ok().and_then(|n| buf.get(..n)),
        Some(raw),
        "re-encoding differs"
    );
    for realtime_index in [false, true] {
        if let Ok(p) = parse_reply(
            t.payload(),
            ReplyOptions::default().with_realtime_index(realtime_index),
        ) {
            if let Reply::Values(v) = p.reply {
                assert_eq!(v.len(), usize::from(v.count_word() & 0x3FF));
                let mut codes = [0u16; 1024];
                assert_eq!(
                    v.range_codes(MeasuringMode::M8_FIELDS_AB_DAZZLE, &mut codes),
                    v.len()
                );
            }
        }
    }
}

/// Reference model of the telegram layer: the telegrams a correct resynchronising decoder must
/// deliver from `stream` (greedy left to right; a candidate whose header is plausible but which
/// is still incomplete at the end blocks everything after it), and how many bytes it holds
/// pending at the end.
pub fn reference_telegrams(stream: &[u8], address: u8) -> (Vec<Vec<u8>>, usize) {
    let mut out = Vec::new();
    let mut i = 0usize;
    let n = stream.len();
    while i < n {
        if stream[i] != STX {
            i += 1;
            continue;
        }
        let Some(&adr) = stream.get(i + 1) else {
            return (out, n - i);
        };
        if adr != address {
            i += 1;
            continue;
        }
        let (Some(&lo), Some(&hi)) = (stream.get(i + 2), stream.get(i + 3)) else {
            return (out, n - i);
        };
        let len = usize::from(u16::from_le_bytes([lo, hi]));
        if len == 0 || len + 6 > MAX_TELEGRAM {
            i += 1;
            continue;
        }
        let Some(cand) = stream.get(i..i + len + 6) else {
            return (out, n - i);
        };
        if Telegram::parse(cand).is_ok() {
            out.push(cand.to_vec());
            i += len + 6;
        } else {
            i += 1;
        }
    }
    (out, 0)
}

fn telegram_bytes(seen: &[Seen]) -> usize {
    seen.iter()
        .map(|s| match s {
            Seen::Telegram(t) => t.len(),
            _ => 1,
        })
        .sum()
}

fn check_conservation(stats: &DecoderStats, seen: &[Seen], pending: usize, total: usize) {
    let telegrams = seen
        .iter()
        .filter(|s| matches!(s, Seen::Telegram(_)))
        .count();
    let acks = seen.iter().filter(|s| **s == Seen::Ack).count();
    let naks = seen.iter().filter(|s| **s == Seen::Nak).count();
    assert_eq!(stats.telegrams as usize, telegrams, "{stats:?}");
    assert_eq!(stats.acks as usize, acks, "{stats:?}");
    assert_eq!(stats.naks as usize, naks, "{stats:?}");
    assert_eq!(
        stats.dropped(),
        stats.crc_errors + stats.bad_length + stats.overflows
    );
    // Every input byte is accounted for exactly once.
    assert_eq!(
        stats.bytes_skipped as usize + telegram_bytes(seen) + pending,
        total,
        "bytes not accounted for: {stats:?}, pending {pending}"
    );
}

/// Fuzz target `lms_decoder`. Input: two chunking bytes ([`Chunker`]) then the byte stream.
///
/// Checks: the decoder delivers exactly the reference model's telegrams
/// ([`reference_telegrams`]), each verified by [`check_telegram`]; the events and counters do
/// not depend on how the stream is chunked; every byte is counted once (skipped, in a
/// telegram, an ACK/NAK or pending); a decoder with a small buffer and one listening for the
/// host address obey the same accounting. Returns the number of telegrams.
pub fn lms_decoder(data: &[u8]) -> usize {
    let (a, b, stream) = match data {
        [a, b, rest @ ..] => (*a, *b, rest),
        _ => return 0,
    };
    let chunks = Chunker::new(a, b).chunks(stream);

    let mut whole = Decoder::<MAX_TELEGRAM>::new();
    let seen_whole = drive(&mut whole, &[stream]);
    let mut chunked = Decoder::<MAX_TELEGRAM>::new();
    let seen = drive(&mut chunked, &chunks);
    assert_eq!(seen, seen_whole, "events depend on chunking");
    assert_eq!(
        chunked.stats(),
        whole.stats(),
        "counters depend on chunking"
    );
    assert_eq!(chunked.pending(), whole.pending());

    let (reference, pending) = reference_telegrams(stream, 0x80);
    let telegrams: Vec<&Vec<u8>> = seen
        .iter()
        .filter_map(|s| match s {
            Seen::Telegram(t) => Some(t),
            _ => None,
        })
        .collect();
    assert_eq!(
        telegrams.len(),
        reference.len(),
        "telegram count differs from the model"
    );
    for (got, want) in telegrams.iter().zip(&reference) {
        assert_eq!(*got, want, "telegram differs from the model");
    }
    assert_eq!(
        chunked.pending(),
        pending,
        "pending bytes differ from the model"
    );
    assert_eq!(chunked.stats().overflows, 0);
    check_conservation(&chunked.stats(), &seen, chunked.pending(), stream.len());

    let mut small = Decoder::<64>::new();
    let seen_small = drive(&mut small, &chunks);
    check_conservation(&small.stats(), &seen_small, small.pending(), stream.len());

    let mut host = Decoder::<MAX_TELEGRAM>::with_address(0x00);
    let seen_host = drive(&mut host, &chunks);
    check_conservation(&host.stats(), &seen_host, host.pending(), stream.len());
    let (reference_host, _) = reference_telegrams(stream, 0x00);
    assert_eq!(
        seen_host
            .iter()
            .filter(|s| matches!(s, Seen::Telegram(_)))
            .count(),
        reference_host.len()
    );
    telegrams.len()
}

/// Readings the extractor target's extractor holds.
pub const EXTRACT_N: usize = 1024;
/// Features the extractor target's extractor holds (small, to exercise the capacity path).
pub const EXTRACT_M: usize = 16;

fn take<const K: usize>(rest: &mut &[u8]) -> [u8; K] {
    let mut out = [0u8; K];
    let n = K.min(rest.len());
    out[..n].copy_from_slice(&rest[..n]);
    *rest = &rest[n..];
    out
}

/// Layout of the `extractor` target's input (also used by [`seeds`] to encode real scans).
///
/// Byte 0 is a flag byte: bit 0 raw LMS codes (`u16`) instead of mm (`f32`); bit 1 geometry
/// and mm ranges as arbitrary `f32` bits instead of the "sane" integer encoding; bit 2 cm
/// units (10 mm per code); bit 3 also run two variants of the configurations. Then the
/// geometry: sane = start (i16, centidegrees), step (i16, millidegrees), r_max (u16, mm); raw =
/// three little-endian `f32` bits. Then the readings: `u16` LE (raw codes, or mm in sane mode),
/// or `f32` LE bits in raw-float mode.
#[derive(Clone, Debug)]
pub struct ExtractorInput {
    /// Flag byte.
    pub flags: u8,
    /// Scan geometry.
    pub geometry: ScanGeometry,
    /// Raw codes (flag bit 0).
    pub codes: Vec<u16>,
    /// Ranges in mm (otherwise).
    pub mm: Vec<f32>,
}

impl ExtractorInput {
    /// Flag: raw LMS codes.
    pub const RAW: u8 = 1;
    /// Flag: arbitrary f32 bits.
    pub const FLOAT_BITS: u8 = 2;
    /// Flag: cm units.
    pub const CM: u8 = 4;
    /// Flag: configuration variants too.
    pub const VARIANTS: u8 = 8;

    /// Decodes the fuzzer's bytes.
    pub fn parse(data: &[u8]) -> Option<Self> {
        let (&flags, mut rest) = data.split_first()?;
        let float_bits = flags & Self::FLOAT_BITS != 0;
        let geometry = if float_bits {
            let [s, a, r] = [0; 3].map(|_: u8| f32::from_le_bytes(take::<4>(&mut rest)));
            ScanGeometry::new(s, a, r)
        } else {
            let s = i16::from_le_bytes(take::<2>(&mut rest));
            let a = i16::from_le_bytes(take::<2>(&mut rest));
            let r = u16::from_le_bytes(take::<2>(&mut rest));
            ScanGeometry::new(
                f32::from(s) * 0.01f32.to_radians(),
                f32::from(a) * 0.001f32.to_radians(),
                f32::from(r),
            )
        };
        let (mut codes, mut mm) = (Vec::new(), Vec::new());
        if flags & Self::RAW != 0 {
            codes = rest
                .chunks_exact(2)
                .map(|w| u16::from_le_bytes([w[0], w[1]]))
                .collect();
        } else if float_bits {
            mm = rest
                .chunks_exact(4)
                .map(|w| f32::from_le_bytes([w[0], w[1], w[2], w[3]]))
                .collect();
        } else {
            mm = rest
                .chunks_exact(2)
                .map(|w| f32::from(u16::from_le_bytes([w[0], w[1]])))
                .collect();
        }
        Some(Self {
            flags,
            geometry,
            codes,
            mm,
        })
    }

    /// Encodes a scan in the sane layout: raw codes when `codes`, mm otherwise.
    pub fn encode_sane(
        start_cdeg: i16,
        step_mdeg: i16,
        r_max: u16,
        raw: bool,
        values: &[u16],
    ) -> Vec<u8> {
        let mut out = vec![if raw { Self::RAW } else { 0 }];
        out.extend(start_cdeg.to_le_bytes());
        out.extend(step_mdeg.to_le_bytes());
        out.extend(r_max.to_le_bytes());
        for v in values {
            out.extend(v.to_le_bytes());
        }
        out
    }

    /// The scan.
    pub fn scan(&self) -> Scan<'_> {
        if self.flags & Self::RAW != 0 {
            let unit = if self.flags & Self::CM != 0 {
                10.0
            } else {
                1.0
            };
            Scan::from_lms(self.geometry, &self.codes, unit)
        } else {
            Scan::from_mm(self.geometry, &self.mm)
        }
    }

    /// The configurations to run.
    pub fn configs(&self) -> Vec<Config> {
        let mut v = vec![Config::paper(), Config::default()];
        if self.flags & Self::VARIANTS != 0 {
            let mut p = Config::paper();
            p.check_step = false;
            p.min_points = 2;
            v.push(p);
            let mut d = Config::default().with_sigma_r(0.5);
            d.circle_refine = 0;
            d.min_points = 3;
            v.push(d);
        }
        v
    }
}

/// Checks one extraction's result and the extractor's state.
pub fn check_extraction<const N: usize, const M: usize>(
    ex: &Extractor<N, M>,
    scan: &Scan<'_>,
    result: Result<pfe_core::Stats, ExtractError>,
) {
    let n = scan.ranges.len();
    let feats = ex.features();
    match result {
        Ok(stats) => {
            assert_eq!(stats.dropped, 0);
            assert_eq!(stats.features, feats.len());
            assert_eq!(stats.readings, n);
        }
        Err(ExtractError::FeatureCapacity { dropped }) => {
            assert!(dropped > 0);
            // Full, but for a line the real-scan checks found unseeable only after the
            // capacity was reached (reaching over its neighbour beams made it so): the lines
            // they find unseeable when stored give their room up.
            assert!(feats.len() <= M);
        }
        Err(ExtractError::TooManyReadings { got, .. }) => {
            assert_eq!(got, n);
            assert!(n > N);
            assert!(feats.is_empty());
            return;
        }
        Err(ExtractError::InvalidGeometry) => {
            assert!(
                !scan.geometry.is_valid(),
                "valid geometry rejected: {:?}",
                scan.geometry
            );
            assert!(feats.is_empty());
            return;
        }
        Err(e) => panic!("unexpected error {e:?} for a valid configuration"),
    }
    assert!(scan.geometry.is_valid());
    assert!(feats.len() <= M);
    assert_eq!(ex.points().len(), n);
    let marks: Vec<usize> = ex.marks().collect();
    assert!(
        marks.windows(2).all(|w| w[0] < w[1]),
        "marks not increasing"
    );
    assert!(marks.iter().all(|&m| m < n), "mark beyond the scan");
    let mut prev_last: Option<usize> = None;
    for f in feats {
        assert!(f.is_well_formed(), "ill-formed feature {f:?}");
        let (first, last) = (f.first(), f.last());
        assert!(first <= last && last < n, "feature {first}..={last} of {n}");
        if let Some(p) = prev_last {
            assert!(
                first > p,
                "features overlap or are out of order: {p} then {first}"
            );
        }
        prev_last = Some(last);
        assert!(
            ex.is_mark(first) && ex.is_mark(last),
            "feature ends are not marks"
        );
        let points = match f {
            Feature::Line(l) => usize::from(l.points),
            Feature::Circle(c) => usize::from(c.points),
            Feature::Object(o) => usize::from(o.points),
            _ => unreachable!("a feature kind the harness does not check: {f:?}"),
        };
        let need = if f.is_line() { 2 } else { 3 };
        assert!(
            points >= need && points <= last - first + 1,
            "{points} points in {first}..={last}"
        );
        for i in first..=last {
            assert!(
                ex.points()[i].is_valid(),
                "invalid point {i} inside a feature"
            );
        }
    }
}

/// Fuzz target `extractor`: arbitrary ranges (raw `u16` codes or `f32` mm), arbitrary geometry,
/// both configurations (and variants). See [`ExtractorInput`] for the layout and
/// [`check_extraction`] for the invariants. Returns the number of features of the last run.
pub fn extractor(data: &[u8]) -> usize {
    let Some(input) = ExtractorInput::parse(data) else {
        return 0;
    };
    let scan = input.scan();
    let mut ex = Box::new(Extractor::<EXTRACT_N, EXTRACT_M>::new());
    let mut last = 0;
    for config in input.configs() {
        let result = ex.extract(&scan, &config);
        check_extraction(&ex, &scan, result);
        last = ex.features().len();
    }
    last
}

/// Fuzz target `readers`: the first byte picks the format (csv, carmen, hokuyo, lms200), the
/// rest is the file. Errors must be values (no panic), reading stops after the first error,
/// and every record obeys the readers' contract (1..=2048 beams, a usable geometry). Returns
/// the number of records.
pub fn readers(data: &[u8]) -> usize {
    let Some((&sel, text)) = data.split_first() else {
        return 0;
    };
    let format = match sel % 4 {
        0 => Format::Csv,
        1 => Format::Carmen,
        2 => Format::Hokuyo,
        _ => Format::Lms200,
    };
    let mut it = scans(format, Box::new(Cursor::new(text.to_vec())));
    let mut records = 0;
    // A record needs at least one byte of input, so this bound is never the limit.
    for _ in 0..=text.len() {
        match it.next() {
            None => return records,
            Some(Ok(r)) => {
                records += 1;
                assert!(!r.ranges_mm.is_empty() && r.ranges_mm.len() <= pfe_formats::MAX_BEAMS);
                assert!(
                    r.geometry.is_valid(),
                    "{format}: unusable geometry {:?}",
                    r.geometry
                );
            }
            Some(Err(e)) => {
                assert!(!e.message.is_empty());
                assert!(
                    it.next().is_none(),
                    "{format}: reading went on after an error"
                );
                return records;
            }
        }
    }
    panic!("{format}: more records than input bytes");
}

fn reencode(frame: &Frame) -> Vec<u8> {
    let mut out = Vec::new();
    let r = match &frame.header {
        Header::Scan(h) => {
            let feats: Vec<Feature> = frame.features.to_vec();
            write_scan(&mut out, h, &feats)
        }
        Header::Report(r) => write_report(&mut out, r),
    };
    assert!(r.is_ok(), "re-encoding a decoded frame failed: {r:?}");
    out
}

/// Fuzz target `frame_decoder`: two chunking bytes then arbitrary bytes into the output
/// [`FrameDecoder`]. No panic; frames and errors do not depend on chunking; every decoded
/// frame re-encodes to a frame that decodes to the same bytes again (encode ∘ decode is
/// idempotent). Returns the number of frames.
pub fn frame_decoder(data: &[u8]) -> usize {
    let (a, b, stream) = match data {
        [a, b, rest @ ..] => (*a, *b, rest),
        _ => return 0,
    };
    let run = |chunks: &[&[u8]]| {
        let mut dec = Box::new(FrameDecoder::<4096>::new());
        let mut out: Vec<Result<Vec<u8>, String>> = Vec::new();
        for chunk in chunks {
            let mut rest: &[u8] = chunk;
            loop {
                match dec.feed(rest) {
                    Feed::Consumed => break,
                    Feed::Frame { frame, remaining } => {
                        assert!(remaining.len() < rest.len());
                        out.push(Ok(reencode(&frame)));
                        rest = remaining;
                    }
                    Feed::Error { error, remaining } => {
                        assert!(remaining.len() < rest.len());
                        out.push(Err(format!("{error:?}")));
                        rest = remaining;
                    }
                }
            }
        }
        out
    };
    let whole = run(&[stream]);
    let chunked = run(&Chunker::new(a, b).chunks(stream));
    assert_eq!(whole, chunked, "frames depend on chunking");
    let mut frames = 0;
    for bytes in whole.iter().flatten() {
        frames += 1;
        assert_eq!(bytes.last(), Some(&0));
        let mut dec = Box::new(FrameDecoder::<4096>::new());
        match dec.feed(bytes) {
            Feed::Frame { frame, remaining } => {
                assert!(remaining.is_empty());
                assert_eq!(&reencode(&frame), bytes, "encode(decode(x)) is not stable");
            }
            other => panic!("a re-encoded frame does not decode: {other:?}"),
        }
    }
    frames
}
