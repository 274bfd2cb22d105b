//! The host-side frame reader: sans-IO, byte chunks in, frames out.

use heapless::Vec;
use pfe_core::{CircleFeature, Feature, LineFeature, ObjectFeature, Point};

use super::cobs::cobs_decode_in_place;
use super::crc::crc32;
use super::wire::{Header, PoseBlock, ScanHeader, MAX_FEATURES, OLDER_VERSIONS, WIRE_VERSION};

/// A decoded frame. `#[non_exhaustive]`: later wire versions may carry more.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct Frame {
    /// What the frame is.
    pub header: Header,
    /// The features of a scan frame (empty for reports), bit for bit as the firmware had them.
    pub features: Vec<Feature, MAX_FEATURES>,
    /// The pose block of a scan frame: the firmware's odometry for this scan, bit for bit
    /// (`None` for reports, for a frame sent without one, and for versions 2 and 3).
    pub pose: Option<PoseBlock>,
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
    /// The frame is intact (its CRC matches) but of another [`WIRE_VERSION`]: not decoded.
    UnknownVersion {
        /// The version byte found.
        version: u8,
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
            DecodeError::UnknownVersion { version } => write!(
                f,
                "frame version {version}, this decoder reads versions {OLDER_VERSIONS:?} and {WIRE_VERSION}"
            ),
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

/// Sans-IO frame receiver with a `B`-byte buffer (see [`max_frame_len`](super::max_frame_len)).
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
    let (&version, payload) = payload.split_first().ok_or(DecodeError::TooShort)?;
    if version != WIRE_VERSION && !OLDER_VERSIONS.contains(&version) {
        return Err(DecodeError::UnknownVersion { version });
    }
    // Version 2 had no small objects (tag 2).
    let max_tag = if version == 2 { 1 } else { 2 };
    let (header, mut rest): (Header, &[u8]) =
        postcard::take_from_bytes(payload).map_err(|_| DecodeError::Payload)?;
    // Version 3 had no stages from 4 on in its timing reports (the per-step stages and the
    // pose stages came with version 4).
    if let Header::Report(crate::Report::Timing { stage, .. }) = header {
        if version < 4 && stage as u8 >= crate::Stage::Load as u8 {
            return Err(DecodeError::Payload);
        }
    }
    let mut features = Vec::new();
    let mut pose = None;
    if let Header::Scan(h) = header {
        if usize::from(h.n_features) > MAX_FEATURES {
            return Err(DecodeError::TooManyFeatures { n: h.n_features });
        }
        for _ in 0..h.n_features {
            let (f, r) = take_feature(rest, max_tag).ok_or(DecodeError::Payload)?;
            features
                .push(f)
                .map_err(|_| DecodeError::TooManyFeatures { n: h.n_features })?;
            rest = r;
        }
        // Version 4: the pose block follows the features.
        if version >= 4 {
            let (p, r): (Option<PoseBlock>, &[u8]) =
                postcard::take_from_bytes(rest).map_err(|_| DecodeError::Payload)?;
            pose = p;
            rest = r;
        }
    }
    if !rest.is_empty() {
        return Err(DecodeError::TrailingBytes);
    }
    Ok(Frame {
        header,
        features,
        pose,
    })
}

/// One feature off the front of `data` (the layout the encoder writes: variant index, first,
/// last, points as varints, then the `f32`s little-endian), and the bytes after it.
fn take_feature(data: &[u8], max_tag: u16) -> Option<(Feature, &[u8])> {
    let mut r = Reader(data);
    let tag = r.varint()?;
    if tag > max_tag {
        return None;
    }
    let (first, last, points) = (r.varint()?, r.varint()?, r.varint()?);
    let f = match tag {
        0 => {
            let [alpha, rho, var_alpha, var_rho, cov_alpha_rho, sx, sy, ex, ey] = r.floats()?;
            Feature::Line(LineFeature::new(
                first,
                last,
                points,
                alpha,
                rho,
                var_alpha,
                var_rho,
                cov_alpha_rho,
                Point::new(sx, sy),
                Point::new(ex, ey),
            ))
        }
        1 => {
            let [cx, cy, radius, a, b, c, d, e, g, h, i, j, start_angle, end_angle] = r.floats()?;
            Feature::Circle(CircleFeature::new(
                first,
                last,
                points,
                Point::new(cx, cy),
                radius,
                [[a, b, c], [d, e, g], [h, i, j]],
                start_angle,
                end_angle,
            ))
        }
        2 => {
            let [cx, cy, a, b, c, d, extent] = r.floats()?;
            Feature::Object(ObjectFeature::new(
                first,
                last,
                points,
                Point::new(cx, cy),
                [[a, b], [c, d]],
                extent,
            ))
        }
        _ => return None,
    };
    Some((f, r.0))
}

/// Reads postcard's encodings off the front of a slice.
struct Reader<'a>(&'a [u8]);

impl Reader<'_> {
    fn byte(&mut self) -> Option<u8> {
        let (&b, rest) = self.0.split_first()?;
        self.0 = rest;
        Some(b)
    }

    /// A `u16` as an LEB128 varint (at most 3 bytes, no bits above 16, as postcard accepts).
    fn varint(&mut self) -> Option<u16> {
        let mut v = 0u32;
        for shift in [0u32, 7, 14] {
            let b = self.byte()?;
            v |= u32::from(b & 0x7F) << shift;
            if b & 0x80 == 0 {
                return u16::try_from(v).ok();
            }
        }
        None
    }

    /// `K` little-endian `f32`s.
    fn floats<const K: usize>(&mut self) -> Option<[f32; K]> {
        let mut out = [0.0f32; K];
        for v in &mut out {
            let (b, rest) = self.0.split_first_chunk::<4>()?;
            *v = f32::from_le_bytes(*b);
            self.0 = rest;
        }
        Some(out)
    }
}
