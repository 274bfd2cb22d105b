//! The host-side frame reader: sans-IO, byte chunks in, frames out.

use heapless::Vec;

use super::cobs::cobs_decode_in_place;
use super::crc::crc32;
use super::wire::{Header, ScanHeader, WireFeature, MAX_FEATURES};

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
