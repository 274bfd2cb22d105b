//! The LMS2xx serial protocol: [`codec`] (bytes ↔ telegrams, sans-IO) and [`driver`]
//! (the device over a UART: initialisation, retries, re-initialisation, scans).
//!
//! Data path: bytes → [`frame::Decoder`] (framing, CRC, resync) → [`reply::parse_reply`] →
//! [`driver::Driver`] → [`driver::ScanData`].

pub mod codec;
pub mod driver;

pub use codec::{command, crc, frame, reply, types};

pub use codec::command::Command;
pub use codec::frame::{Decoder, DecoderStats, Event, Telegram, MAX_TELEGRAM};
pub use codec::reply::{parse_reply, MeasuredValues, ParsedReply, Reply, ReplyOptions, Status};
pub use codec::types::{Baud, MeasuringMode, Unit, Variant};
pub use driver::error::{self, Error};
pub use driver::{Clock, Config, Counters, DeviceState, Driver, ScanData, SetBaud};
