//! Features on the wire: postcard + COBS frames with a CRC-32.
//!
//! # Frame format (version [`WIRE_VERSION`])
//!
//! ```text
//! COBS( postcard(Header) ‖ postcard(WireFeature) × n ‖ CRC-32 (4 bytes, little-endian) ) ‖ 0x00
//! ```
//!
//! - Every frame ends with a single `0x00`; COBS guarantees there is no other zero in it, so a
//!   receiver that joins mid-stream or loses bytes resynchronises at the next `0x00`.
//! - The payload is [postcard](https://docs.rs/postcard) (integers as LEB128 varints, `f32` as
//!   4 little-endian bytes — bit-exact, enums as a varint variant index).
//! - The CRC is CRC-32/ISO-HDLC (the zlib / Ethernet CRC: reflected polynomial `0xEDB88320`,
//!   init and final XOR `0xFFFFFFFF`; `crc32(b"123456789") = 0xCBF43926`) over the postcard
//!   bytes, appended little-endian before COBS encoding.
//! - The [`Header`] says what follows: [`Header::Scan`] is followed by exactly `n_features`
//!   [`WireFeature`]s; [`Header::Report`] (stack high-water mark, timing) by nothing.
//!
//! The encoder ([`write_scan`], [`write_report`]) streams to any [`embedded_io::Write`] with a
//! fixed 255-byte COBS block, a 96-byte scratch buffer for the header and a 420-byte chunk of
//! features (written by hand, byte for byte what postcard writes): the frame size does not
//! need RAM.
//! The decoder ([`FrameDecoder`]) is sans-IO: feed it byte chunks, get frames out.
//!
//! ```
//! use firmware::output::{write_scan, Counters, FrameDecoder, Header, ScanHeader, Feed};
//! use pfe_core::{Feature, LineFeature, Point};
//! let f = Feature::Line(LineFeature {
//!     first: 10, last: 40, points: 31, alpha: 0.1, rho: 2000.0, var_alpha: 1e-6,
//!     var_rho: 4.0, cov_alpha_rho: 1e-4, start: Point::new(1.0, 2.0), end: Point::new(3.0, 4.0),
//! });
//! let header = ScanHeader { seq: 7, counters: Counters::default(), valid: 300, segments: 5,
//!     dropped: 0, n_features: 1, status: Default::default() };
//! let mut buf = [0u8; 512];
//! let mut w = &mut buf[..];
//! write_scan(&mut w, &header, &[f])?;
//! let n = 512 - w.len();
//! let mut dec = FrameDecoder::<4096>::new();
//! let Feed::Frame { frame, remaining } = dec.feed(&buf[..n]) else {
//!     return Err("no frame".into());
//! };
//! assert!(remaining.is_empty());
//! assert_eq!(frame.header, Header::Scan(header));
//! assert_eq!(frame.features[0].to_feature(), f);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use heapless::Vec;
use pfe_core::{CircleFeature, Feature, LineFeature, Point};
use serde::{Deserialize, Serialize};

/// Version of the frame layout described here; bump it when a wire struct changes.
pub const WIRE_VERSION: u8 = 1;

/// Most features one decoded frame can hold.
pub const MAX_FEATURES: usize = 64;

/// Largest postcard encoding of one [`WireFeature`] (a circle: tag + 3 u16 varints + 15 f32).
pub const MAX_FEATURE_LEN: usize = 1 + 3 * 3 + 15 * 4;

/// Bytes of features [`write_scan`] encodes at a time.
const FEATURE_CHUNK: usize = 6 * MAX_FEATURE_LEN;

/// Largest frame on the wire for `features` features (header, features, CRC, COBS overhead
/// and the terminating zero): size a receive buffer with it.
pub const fn max_frame_len(features: usize) -> usize {
    let raw = 64 + features * MAX_FEATURE_LEN + 4;
    raw + raw / 254 + 2
}

/// Link counters of the scanner driver, cumulative since start.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Counters {
    /// Telegrams received with a good CRC.
    pub telegrams_ok: u32,
    /// Telegrams dropped for a bad CRC.
    pub crc_dropped: u32,
    /// Bytes skipped while searching for a telegram start.
    pub bytes_skipped: u32,
    /// Times the driver re-initialised the scanner.
    pub reinits: u32,
}

/// Header of a scan frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ScanHeader {
    /// Scan sequence number (0 for the first scan after start).
    pub seq: u32,
    /// Link counters after this scan.
    pub counters: Counters,
    /// Valid readings in the scan.
    pub valid: u16,
    /// Segments found.
    pub segments: u16,
    /// Features that did not fit in the extractor's buffer (not sent).
    pub dropped: u16,
    /// Number of [`WireFeature`]s that follow.
    pub n_features: u16,
    /// How the extraction went.
    pub status: ScanStatus,
}

/// Outcome of one scan's extraction.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ScanStatus {
    /// All features were extracted and sent.
    #[default]
    Ok,
    /// The feature buffer was full: the first features are sent, `dropped` were lost.
    FeatureCapacity,
    /// The scan had more readings than the extractor's capacity: nothing extracted.
    TooManyReadings,
    /// The geometry or configuration was rejected: nothing extracted.
    InvalidInput,
}

/// What a timing report measured (see [`Report::Timing`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Stage {
    /// Decoding one B0 telegram (CRC and values).
    Decode,
    /// pfe-core with `Config::paper()`.
    ExtractPaper,
    /// pfe-core with `Config::default()`.
    ExtractDefault,
    /// Telegram bytes to encoded output frame, everything.
    Pipeline,
}

/// Out-of-band reports of the firmware.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Report {
    /// Stack high-water mark, bytes, out of the stack's size.
    Stack {
        /// Bytes of stack ever used.
        used: u32,
        /// Bytes reserved for the stack.
        size: u32,
    },
    /// Timer ticks spent on one stage of one scan.
    Timing {
        /// Scan sequence number.
        seq: u32,
        /// What was measured.
        stage: Stage,
        /// Timer ticks (SysTick under QEMU `-icount shift=10`: instructions = ticks × 10 / 256).
        ticks: u32,
        /// Readings in the scan.
        points: u16,
    },
    /// The firmware finished after `scans` scans.
    Done {
        /// Scans processed.
        scans: u32,
    },
}

/// First item of every frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Header {
    /// One scan's features follow.
    Scan(ScanHeader),
    /// A report; nothing follows.
    Report(Report),
}

/// A feature as sent: pfe-core's [`Feature`] with points as `[x, y]`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum WireFeature {
    /// A line `x cos α + y sin α = ρ` (see [`LineFeature`]).
    Line {
        /// First beam.
        first: u16,
        /// Last beam.
        last: u16,
        /// Valid points fitted.
        points: u16,
        /// α, rad.
        alpha: f32,
        /// ρ, mm.
        rho: f32,
        /// σ_α², rad².
        var_alpha: f32,
        /// σ_ρ², mm².
        var_rho: f32,
        /// cov(α, ρ), rad·mm.
        cov_alpha_rho: f32,
        /// Start point, mm.
        start: [f32; 2],
        /// End point, mm.
        end: [f32; 2],
    },
    /// A circle (see [`CircleFeature`]).
    Circle {
        /// First beam.
        first: u16,
        /// Last beam.
        last: u16,
        /// Valid points fitted.
        points: u16,
        /// Centre, mm.
        center: [f32; 2],
        /// Radius, mm.
        radius: f32,
        /// Covariance of (x, y, r), mm².
        cov: [[f32; 3]; 3],
        /// Bearing from the centre to the first point, rad.
        start_angle: f32,
        /// Bearing from the centre to the last point, rad.
        end_angle: f32,
    },
}

impl From<&Feature> for WireFeature {
    fn from(f: &Feature) -> Self {
        match *f {
            Feature::Line(l) => WireFeature::Line {
                first: l.first,
                last: l.last,
                points: l.points,
                alpha: l.alpha,
                rho: l.rho,
                var_alpha: l.var_alpha,
                var_rho: l.var_rho,
                cov_alpha_rho: l.cov_alpha_rho,
                start: [l.start.x, l.start.y],
                end: [l.end.x, l.end.y],
            },
            Feature::Circle(c) => WireFeature::Circle {
                first: c.first,
                last: c.last,
                points: c.points,
                center: [c.center.x, c.center.y],
                radius: c.radius,
                cov: c.cov,
                start_angle: c.start_angle,
                end_angle: c.end_angle,
            },
        }
    }
}

impl WireFeature {
    /// Back to pfe-core's type (bit-exact).
    pub fn to_feature(&self) -> Feature {
        match *self {
            WireFeature::Line {
                first,
                last,
                points,
                alpha,
                rho,
                var_alpha,
                var_rho,
                cov_alpha_rho,
                start,
                end,
            } => Feature::Line(LineFeature {
                first,
                last,
                points,
                alpha,
                rho,
                var_alpha,
                var_rho,
                cov_alpha_rho,
                start: Point::new(start[0], start[1]),
                end: Point::new(end[0], end[1]),
            }),
            WireFeature::Circle {
                first,
                last,
                points,
                center,
                radius,
                cov,
                start_angle,
                end_angle,
            } => Feature::Circle(CircleFeature {
                first,
                last,
                points,
                center: Point::new(center[0], center[1]),
                radius,
                cov,
                start_angle,
                end_angle,
            }),
        }
    }

    /// True for a line.
    pub fn is_line(&self) -> bool {
        matches!(self, WireFeature::Line { .. })
    }
}

/// The postcard bytes of `WireFeature::from(f)` in `out`, written directly (variant index and
/// beam indices as varints, the `f32`s as 4 little-endian bytes each, fields in declaration
/// order): the same bytes as `postcard::to_slice`, for a tenth of its instructions. Returns
/// their length.
fn feature_bytes(f: &Feature, out: &mut [u8]) -> usize {
    let mut w = Cursor { out, at: 0 };
    match f {
        Feature::Line(l) => {
            w.head(0, [l.first, l.last, l.points]);
            w.floats(l.values());
        }
        Feature::Circle(c) => {
            w.head(1, [c.first, c.last, c.points]);
            w.floats(c.values());
        }
    }
    w.at
}

/// Writes into a buffer (given at least [`MAX_FEATURE_LEN`] bytes, which every feature fits;
/// a write past its end is dropped, never a panic).
struct Cursor<'a> {
    out: &'a mut [u8],
    at: usize,
}

impl Cursor<'_> {
    /// The variant index and the beam indices (first, last, number of points).
    #[inline(always)]
    fn head(&mut self, tag: u16, beams: [u16; 3]) {
        let [first, last, points] = beams;
        self.varint(tag);
        self.varint(first);
        self.varint(last);
        self.varint(points);
    }

    /// LEB128, as postcard writes integers.
    fn varint(&mut self, mut v: u16) {
        while v >= 0x80 {
            self.byte(v as u8 | 0x80);
            v >>= 7;
        }
        self.byte(v as u8);
    }

    fn byte(&mut self, b: u8) {
        if let Some(slot) = self.out.get_mut(self.at) {
            *slot = b;
            self.at += 1;
        }
    }

    /// The values as 4 little-endian bytes each (one bounds check for all of them).
    fn floats<const K: usize>(&mut self, values: [f32; K]) {
        if let Some(out) = self.out.get_mut(self.at..self.at + 4 * K) {
            for (slot, v) in out.chunks_exact_mut(4).zip(values) {
                slot.copy_from_slice(&v.to_le_bytes());
            }
            self.at += 4 * K;
        }
    }
}

/// CRC-32/ISO-HDLC of `data`, continuing from `crc` (start with `0`).
///
/// ```
/// assert_eq!(firmware::output::crc32(0, b"123456789"), 0xCBF4_3926);
/// ```
pub fn crc32(crc: u32, data: &[u8]) -> u32 {
    !data.iter().fold(!crc, |c, &b| crc32_byte(c, b))
}

/// CRC-32 byte table (1 KiB of flash, built at compile time: an index out of range would be a
/// build error, not a panic).
#[allow(clippy::indexing_slicing)]
const CRC32_TABLE: [u32; 256] = {
    let mut t = [0u32; 256];
    let mut i = 0;
    while i < 256 {
        let mut c = i as u32;
        let mut k = 0;
        while k < 8 {
            c = if c & 1 != 0 {
                (c >> 1) ^ 0xEDB8_8320
            } else {
                c >> 1
            };
            k += 1;
        }
        t[i] = c;
        i += 1;
    }
    t
};

/// Shifts one byte out of the (complemented) CRC-32 register: one table lookup.
#[inline(always)]
fn crc32_shift(c: u32) -> u32 {
    // The index is < 256: `get` never fails.
    (c >> 8) ^ CRC32_TABLE.get((c & 0xFF) as usize).copied().unwrap_or(0)
}

/// One byte of CRC-32 (on the complemented register).
#[inline(always)]
fn crc32_byte(c: u32, b: u8) -> u32 {
    crc32_shift(c ^ u32::from(b))
}

/// Four bytes of CRC-32, `w` their little-endian word (on the complemented register).
#[inline(always)]
fn crc32_word(c: u32, w: u32) -> u32 {
    crc32_shift(crc32_shift(crc32_shift(crc32_shift(c ^ w))))
}

/// Why a frame could not be written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum EncodeError<E> {
    /// The writer failed.
    Write(E),
    /// postcard could not serialise an item (cannot happen with the wire types).
    Serialize,
}

impl<E: core::fmt::Debug> core::fmt::Display for EncodeError<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            EncodeError::Write(e) => write!(f, "output write failed: {e:?}"),
            EncodeError::Serialize => f.write_str("serialisation failed"),
        }
    }
}

impl<E: core::fmt::Debug> core::error::Error for EncodeError<E> {}

/// Streaming COBS encoder with a CRC-32 over what it is given.
struct CobsWriter<'w, W> {
    w: &'w mut W,
    /// `block[0]` is the code byte slot, data from 1.
    block: [u8; 255],
    len: usize,
    crc: u32,
}

impl<'w, W: embedded_io::Write> CobsWriter<'w, W> {
    fn new(w: &'w mut W) -> Self {
        Self {
            w,
            block: [0; 255],
            len: 1,
            crc: 0,
        }
    }

    fn flush_block(&mut self) -> Result<(), W::Error> {
        if let Some(code) = self.block.first_mut() {
            *code = self.len as u8; // len ≤ 255
        }
        let out = self.block.get(..self.len).unwrap_or(&[]);
        self.w.write_all(out)?;
        self.len = 1;
        Ok(())
    }

    /// COBS-encodes `data` (with `CRC` its CRC-32 is also taken: one loop for both), four
    /// bytes at a time where they hold no zero and fit the block.
    fn encode<const CRC: bool>(&mut self, data: &[u8]) -> Result<(), W::Error> {
        let mut c = !self.crc;
        // Kept below 255 between bytes: a full block is flushed at once.
        let mut len = self.len;
        let mut words = data.chunks_exact(4);
        for word in words.by_ref() {
            let Ok(bytes) = <[u8; 4]>::try_from(word) else {
                continue;
            };
            let w = u32::from_le_bytes(bytes);
            if CRC {
                c = crc32_word(c, w);
            }
            // No zero byte in `w` (the classic bit trick: exact for "has none").
            let no_zero = w.wrapping_sub(0x0101_0101) & !w & 0x8080_8080 == 0;
            let slot = self
                .block
                .get_mut(len..len + 4)
                .and_then(|s| <&mut [u8; 4]>::try_from(s).ok());
            match slot {
                // len + 4 < 255: the block is not full after them.
                Some(slot) if no_zero && len + 4 < 255 => {
                    *slot = bytes;
                    len += 4;
                }
                _ => len = self.bytes(&bytes, len)?,
            }
        }
        self.len = self.bytes(words.remainder(), len)?;
        if CRC {
            self.crc = !words.remainder().iter().fold(c, |c, &b| crc32_byte(c, b));
        }
        Ok(())
    }

    /// COBS-encodes `data` byte by byte into the block at `len`; returns the new length.
    fn bytes(&mut self, data: &[u8], mut len: usize) -> Result<usize, W::Error> {
        for &b in data {
            if b != 0 {
                if let Some(slot) = self.block.get_mut(len) {
                    *slot = b;
                }
                len += 1;
                if len < 255 {
                    continue;
                }
            }
            self.len = len;
            self.flush_block()?;
            len = 1;
        }
        Ok(len)
    }

    fn raw(&mut self, data: &[u8]) -> Result<(), W::Error> {
        self.encode::<false>(data)
    }

    fn put(&mut self, data: &[u8]) -> Result<(), W::Error> {
        self.encode::<true>(data)
    }

    fn put_item<T: Serialize>(&mut self, item: &T) -> Result<(), EncodeError<W::Error>> {
        let mut scratch = [0u8; 96];
        let bytes = postcard::to_slice(item, &mut scratch).map_err(|_| EncodeError::Serialize)?;
        self.put(bytes).map_err(EncodeError::Write)
    }

    fn finish(mut self) -> Result<(), W::Error> {
        let crc = self.crc.to_le_bytes();
        self.raw(&crc)?;
        // The last block ends at the frame end, not at a zero byte: its code says so by
        // being one more than its data length, which is what flush_block writes.
        self.flush_block()?;
        self.w.write_all(&[0])
    }
}

/// Writes one scan frame: `header` (its `n_features` is overwritten with `features.len()`)
/// then every feature.
pub fn write_scan<W: embedded_io::Write>(
    w: &mut W,
    header: &ScanHeader,
    features: &[Feature],
) -> Result<(), EncodeError<W::Error>> {
    let mut h = *header;
    h.n_features = u16::try_from(features.len()).unwrap_or(u16::MAX);
    let mut enc = CobsWriter::new(w);
    enc.put_item(&Header::Scan(h))?;
    // Features gathered into a chunk, encoded a chunk at a time (fewer calls, and fewer
    // bytes left over from the encoder's words).
    let mut chunk = [0u8; FEATURE_CHUNK];
    let mut len = 0usize;
    for f in features.iter().take(usize::from(h.n_features)) {
        if len + MAX_FEATURE_LEN > FEATURE_CHUNK {
            enc.put(chunk.get(..len).unwrap_or(&[]))
                .map_err(EncodeError::Write)?;
            len = 0;
        }
        len += chunk
            .get_mut(len..)
            .map_or(0, |rest| feature_bytes(f, rest));
    }
    enc.put(chunk.get(..len).unwrap_or(&[]))
        .map_err(EncodeError::Write)?;
    enc.finish().map_err(EncodeError::Write)
}

/// Writes one report frame.
pub fn write_report<W: embedded_io::Write>(
    w: &mut W,
    report: &Report,
) -> Result<(), EncodeError<W::Error>> {
    let mut enc = CobsWriter::new(w);
    enc.put_item(&Header::Report(*report))?;
    enc.finish().map_err(EncodeError::Write)
}

/// A decoded frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// What the frame is.
    pub header: Header,
    /// The features of a scan frame (empty for reports).
    pub features: Vec<WireFeature, MAX_FEATURES>,
}

impl Frame {
    /// The scan header, if this is a scan frame.
    pub fn scan(&self) -> Option<&ScanHeader> {
        match &self.header {
            Header::Scan(h) => Some(h),
            Header::Report(_) => None,
        }
    }
}

/// Why a frame was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum DecodeError {
    /// The frame was longer than the decoder's buffer; bytes up to the next zero were dropped.
    Overflow,
    /// The COBS encoding is broken (a code byte points past the end of the frame).
    Cobs,
    /// Fewer than 5 bytes (a header and a CRC) between two zeros.
    TooShort,
    /// Checksum mismatch.
    Crc {
        /// CRC computed over the payload.
        expected: u32,
        /// CRC found in the frame.
        got: u32,
    },
    /// The payload is not a valid header followed by features.
    Payload,
    /// More features than [`MAX_FEATURES`].
    TooManyFeatures {
        /// Features announced.
        n: u16,
    },
    /// Bytes left over after the announced features.
    TrailingBytes,
}

impl core::fmt::Display for DecodeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            DecodeError::Overflow => f.write_str("frame longer than the receive buffer"),
            DecodeError::Cobs => f.write_str("broken COBS encoding"),
            DecodeError::TooShort => f.write_str("frame too short"),
            DecodeError::Crc { expected, got } => {
                write!(
                    f,
                    "CRC mismatch: computed {expected:#010x}, frame has {got:#010x}"
                )
            }
            DecodeError::Payload => f.write_str("payload is not a valid header and features"),
            DecodeError::TooManyFeatures { n } => write!(f, "{n} features announced, too many"),
            DecodeError::TrailingBytes => f.write_str("bytes after the last feature"),
        }
    }
}

impl core::error::Error for DecodeError {}

/// What [`FrameDecoder::feed`] found.
// The frame is returned by value (no allocator); the decoder is meant for the host side.
#[allow(clippy::large_enum_variant)]
#[derive(Debug)]
pub enum Feed<'a> {
    /// Every byte was consumed, no frame ended yet.
    Consumed,
    /// A frame ended; `remaining` are the bytes after its terminating zero (feed them next).
    Frame {
        /// The frame.
        frame: Frame,
        /// Unconsumed input.
        remaining: &'a [u8],
    },
    /// A frame ended but was rejected; `remaining` as above.
    Error {
        /// Why.
        error: DecodeError,
        /// Unconsumed input.
        remaining: &'a [u8],
    },
}

/// Sans-IO frame receiver with a `B`-byte buffer (see [`max_frame_len`]).
pub struct FrameDecoder<const B: usize> {
    buf: [u8; B],
    len: usize,
    overflow: bool,
}

impl<const B: usize> Default for FrameDecoder<B> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const B: usize> FrameDecoder<B> {
    /// An empty decoder.
    pub const fn new() -> Self {
        Self {
            buf: [0; B],
            len: 0,
            overflow: false,
        }
    }

    /// Consumes `data` up to and including the end of the next frame.
    pub fn feed<'a>(&mut self, data: &'a [u8]) -> Feed<'a> {
        for (i, &b) in data.iter().enumerate() {
            if b != 0 {
                match self.buf.get_mut(self.len) {
                    Some(slot) if !self.overflow => {
                        *slot = b;
                        self.len += 1;
                    }
                    _ => self.overflow = true,
                }
                continue;
            }
            let remaining = data.get(i + 1..).unwrap_or(&[]);
            let (len, overflow) = (self.len, self.overflow);
            self.len = 0;
            self.overflow = false;
            if len == 0 && !overflow {
                continue; // an empty frame (e.g. a leading zero used as a resync marker)
            }
            let result = if overflow {
                Err(DecodeError::Overflow)
            } else {
                decode_frame(self.buf.get_mut(..len).unwrap_or(&mut []))
            };
            return match result {
                Ok(frame) => Feed::Frame { frame, remaining },
                Err(error) => Feed::Error { error, remaining },
            };
        }
        Feed::Consumed
    }
}

/// COBS-decodes `buf` in place, returning the decoded length.
fn cobs_decode_in_place(buf: &mut [u8]) -> Result<usize, DecodeError> {
    let (mut r, mut w) = (0usize, 0usize);
    let n = buf.len();
    while r < n {
        let code = usize::from(*buf.get(r).ok_or(DecodeError::Cobs)?);
        if code == 0 || r + code > n {
            return Err(DecodeError::Cobs);
        }
        r += 1;
        for _ in 1..code {
            let b = *buf.get(r).ok_or(DecodeError::Cobs)?;
            *buf.get_mut(w).ok_or(DecodeError::Cobs)? = b;
            r += 1;
            w += 1;
        }
        if code < 0xFF && r < n {
            *buf.get_mut(w).ok_or(DecodeError::Cobs)? = 0;
            w += 1;
        }
    }
    Ok(w)
}

/// Decodes one frame (COBS-encoded, without its terminating zero) in place.
pub fn decode_frame(buf: &mut [u8]) -> Result<Frame, DecodeError> {
    let n = cobs_decode_in_place(buf)?;
    if n < 5 {
        return Err(DecodeError::TooShort);
    }
    let data = buf.get(..n).ok_or(DecodeError::Cobs)?;
    let (payload, tail) = data.split_at(n - 4);
    let got = u32::from_le_bytes([
        *tail.first().ok_or(DecodeError::TooShort)?,
        *tail.get(1).ok_or(DecodeError::TooShort)?,
        *tail.get(2).ok_or(DecodeError::TooShort)?,
        *tail.get(3).ok_or(DecodeError::TooShort)?,
    ]);
    let expected = crc32(0, payload);
    if expected != got {
        return Err(DecodeError::Crc { expected, got });
    }
    let (header, mut rest): (Header, &[u8]) =
        postcard::take_from_bytes(payload).map_err(|_| DecodeError::Payload)?;
    let mut features = Vec::new();
    if let Header::Scan(h) = header {
        if usize::from(h.n_features) > MAX_FEATURES {
            return Err(DecodeError::TooManyFeatures { n: h.n_features });
        }
        for _ in 0..h.n_features {
            let (f, r): (WireFeature, &[u8]) =
                postcard::take_from_bytes(rest).map_err(|_| DecodeError::Payload)?;
            features
                .push(f)
                .map_err(|_| DecodeError::TooManyFeatures { n: h.n_features })?;
            rest = r;
        }
    }
    if !rest.is_empty() {
        return Err(DecodeError::TrailingBytes);
    }
    Ok(Frame { header, features })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::indexing_slicing)]
    use super::*;

    extern crate std;

    /// The hand-written feature bytes are postcard's, for lines and circles with fields of
    /// every bit pattern and beam indices at every varint length.
    #[test]
    fn feature_bytes_are_postcards() -> Result<(), postcard::Error> {
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        let edges = [0u16, 1, 127, 128, 300, 16383, 16384, 65535];
        for k in 0..20_000usize {
            let mut f32s = [0.0f32; 15];
            for v in &mut f32s {
                *v = f32::from_bits(next() as u32);
            }
            let [a, b, c, d, e, g, h, i, j, l, m, n, o, p, q] = f32s;
            let idx = |r: u64| edges[(r % 8) as usize].wrapping_add((r >> 8) as u16 % 3);
            let (first, last, points) = (idx(next()), idx(next()), idx(next()));
            let f = if k % 2 == 0 {
                Feature::Line(LineFeature {
                    first,
                    last,
                    points,
                    alpha: a,
                    rho: b,
                    var_alpha: c,
                    var_rho: d,
                    cov_alpha_rho: e,
                    start: Point::new(g, h),
                    end: Point::new(i, j),
                })
            } else {
                Feature::Circle(CircleFeature {
                    first,
                    last,
                    points,
                    center: Point::new(a, b),
                    radius: c,
                    cov: [[d, e, g], [h, i, j], [l, m, n]],
                    start_angle: o,
                    end_angle: p + q,
                })
            };
            let mut want = [0u8; MAX_FEATURE_LEN];
            let want = postcard::to_slice(&WireFeature::from(&f), &mut want)?;
            let mut got = [0u8; MAX_FEATURE_LEN];
            let n = feature_bytes(&f, &mut got);
            assert_eq!(&got[..n], &want[..], "{f:?}");
        }
        Ok(())
    }

    /// The word-at-a-time encoder gives the `cobs` crate's bytes and `crc32fast`'s CRC for
    /// zero bytes at every position relative to a block's end and to the words, fed in pieces
    /// of every size.
    #[test]
    fn encoder_matches_cobs_and_crc32_at_every_alignment(
    ) -> Result<(), embedded_io::SliceWriteError> {
        for before in 0..300usize {
            for piece in [1usize, 3, 4, 7, 64] {
                let mut data: std::vec::Vec<u8> =
                    (0..before).map(|i| (i % 251 + 1) as u8).collect();
                data.push(0);
                data.extend((0..520).map(|i| (i % 13 + 1) as u8));
                data.push(0);
                data.extend([5, 0, 0, 6]);
                let mut buf = [0u8; 1024];
                let mut out = &mut buf[..];
                let mut enc = CobsWriter::new(&mut out);
                for chunk in data.chunks(piece) {
                    enc.put(chunk)?;
                }
                enc.finish()?;
                let written = 1024 - out.len();
                let mut raw = data.clone();
                raw.extend(crc32fast::hash(&data).to_le_bytes());
                let mut want = cobs::encode_vec(&raw);
                want.push(0);
                assert_eq!(&buf[..written], &want[..], "before {before} piece {piece}");
            }
        }
        Ok(())
    }
}
