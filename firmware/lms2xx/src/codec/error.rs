//! The codec's errors: framing ([`FrameError`]) and reply layout ([`ReplyError`]).

use super::frame::MAX_LEN;

/// Why a byte slice is not a telegram ([`Telegram::parse`](super::frame::Telegram::parse)) or
/// a telegram cannot be encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum FrameError {
    /// Fewer bytes than the header and `LEN` announce.
    Truncated,
    /// More bytes than `LEN` announces.
    TrailingBytes,
    /// First byte is not STX.
    NoStx,
    /// `LEN` is 0 or above [`MAX_LEN`].
    BadLength(usize),
    /// Checksum mismatch.
    Crc {
        /// Checksum computed over the received bytes.
        expected: u16,
        /// Checksum carried by the telegram.
        got: u16,
    },
    /// The output buffer is too small.
    BufferTooSmall,
}

impl core::fmt::Display for FrameError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Truncated => f.write_str("telegram truncated"),
            Self::TrailingBytes => f.write_str("bytes after the telegram's CRC"),
            Self::NoStx => f.write_str("telegram does not start with STX"),
            Self::BadLength(l) => write!(f, "telegram LEN {l} out of range 1..={MAX_LEN}"),
            Self::Crc { expected, got } => {
                write!(
                    f,
                    "CRC mismatch: computed {expected:#06x}, received {got:#06x}"
                )
            }
            Self::BufferTooSmall => f.write_str("output buffer too small"),
        }
    }
}

impl core::error::Error for FrameError {}

/// Why a payload is not a well-formed reply.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ReplyError {
    /// Payload shorter than reply code + status.
    Empty,
    /// The payload length does not fit the reply's layout.
    Length {
        /// Reply code.
        code: u8,
        /// Payload bytes expected (0 when unknown).
        expected: usize,
        /// Payload bytes received.
        got: usize,
    },
}

impl core::fmt::Display for ReplyError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Empty => f.write_str("empty reply"),
            Self::Length {
                code,
                expected,
                got,
            } => write!(
                f,
                "reply {code:#04x}: {got} payload bytes, layout needs {expected}"
            ),
        }
    }
}

impl core::error::Error for ReplyError {}
