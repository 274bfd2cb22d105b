//! pfe's feature frame on the wire: postcard + COBS frames with a CRC-32, written by the
//! firmware and read by the host. `no_std`, no allocation, no panic on any input.
//!
//! # Frame format (version [`WIRE_VERSION`]; the specification is `docs/FRAME.md`)
//!
//! ```text
//! COBS( WIRE_VERSION ‖ postcard(Header) ‖ feature × n ‖ [postcard(Option<PoseBlock>)]
//!       ‖ CRC-32 (4 bytes, little-endian) ) ‖ 0x00
//! ```
//!
//! - Every frame ends with a single `0x00`; COBS guarantees there is no other zero in it, so a
//!   receiver that joins mid-stream or loses bytes resynchronises at the next `0x00`.
//! - The payload starts with the version byte; a receiver drops a frame of another version.
//! - The rest is [postcard](https://docs.rs/postcard) (integers as LEB128 varints, `f32` as
//!   4 little-endian bytes — bit-exact, enums as a varint variant index).
//! - The CRC is CRC-32/ISO-HDLC (the zlib / Ethernet CRC: reflected polynomial `0xEDB88320`,
//!   init and final XOR `0xFFFFFFFF`; `crc32(b"123456789") = 0xCBF43926`) over the payload
//!   bytes (version included), appended little-endian before COBS encoding.
//! - The [`Header`] says what follows: [`Header::Scan`] is followed by exactly `n_features`
//!   pfe-core [`Feature`](pfe_core::Feature)s (points as `[x, y]`) and the pose block, an
//!   `Option<`[`PoseBlock`]`>` (the scan's pose from the firmware's feature odometry: relative
//!   and accumulated pose with covariances, status); [`Header::Report`] (stack high-water mark,
//!   timing) by nothing. Versions 3 and 2 (still decoded) have no pose block.
//!
//! The encoder ([`write_scan`], [`write_report`]) streams to any [`embedded_io::Write`] with a
//! fixed 255-byte COBS block and a 210-byte chunk for a scan's header and features (written
//! by hand, byte for byte what postcard writes; a report goes through a 96-byte scratch
//! buffer): the frame size does not need RAM.
//! The decoder ([`FrameDecoder`]) is sans-IO: feed it byte chunks, get frames out.
//!
//! ```
//! use pfe_frame::{write_scan, Counters, FrameDecoder, Header, ScanHeader, Feed};
//! use pfe_core::{Feature, LineFeature, Point};
//! // first, last, points, α, ρ, σ_α², σ_ρ², cov(α, ρ), start, end
//! let f = Feature::Line(LineFeature::new(
//!     10, 40, 31, 0.1, 2000.0, 1e-6, 4.0, 1e-4, Point::new(1.0, 2.0), Point::new(3.0, 4.0),
//! ));
//! let header = ScanHeader { seq: 7, time_ms: 1234, counters: Counters::default(), valid: 300, segments: 5,
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
//! assert_eq!(frame.features[0], f);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
#![deny(clippy::indexing_slicing)]

mod cobs;
mod crc;
mod decoder;
mod encoder;
mod wire;

pub use crc::crc32;
pub use decoder::{decode_frame, DecodeError, Feed, Frame, FrameDecoder};
pub use encoder::{write_report, write_scan, write_scan_with_pose, EncodeError};
pub use wire::{
    max_frame_len, Counters, Header, PoseBlock, PoseCov, PoseFailure, PoseStatus, Report,
    ScanHeader, ScanStatus, Stage, MAX_FEATURES, MAX_FEATURE_LEN, MAX_POSE_LEN, OLDER_VERSIONS,
    WIRE_VERSION,
};
