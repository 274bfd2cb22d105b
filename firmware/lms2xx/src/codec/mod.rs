//! The LMS2xx telegram codec: bytes in, typed telegrams out, and back. Sans-IO (it never
//! touches a UART) and independent of pfe-core.
//!
//! - [`crc`]: the telegram checksum (CRC-16 of the LMS protocol).
//! - [`frame`]: framing, the resynchronising [`frame::Decoder`] and the telegram encoder.
//! - [`command`]: host → device commands ([`command::Command`]).
//! - [`reply`]: device → host replies ([`reply::parse_reply`]), measured values, status,
//!   configuration block.
//! - [`types`]: baud rates, scan variants, units, measuring modes.
//! - why bytes are not a telegram ([`frame::FrameError`]) or a payload not a reply
//!   ([`reply::ReplyError`]).

pub mod command;
pub mod crc;
mod error;
pub mod frame;
pub mod reply;
pub mod types;
