//! LMS200 serial protocol: telegram codec (sans-IO), commands, replies, driver.
//!
//! Data path: bytes → [`frame::Decoder`] (framing, CRC, resync) → [`reply::parse_reply`] →
//! [`driver::Driver`] (initialisation, retries, re-initialisation, scans).

pub mod command;
pub mod crc;
pub mod frame;
pub mod reply;
pub mod types;

pub use command::Command;
pub use frame::{Decoder, DecoderStats, Event, Telegram, MAX_TELEGRAM};
pub use reply::{parse_reply, MeasuredValues, ParsedReply, Reply, ReplyOptions, Status};
pub use types::{Baud, MeasuringMode, Unit, Variant};
pub mod driver;
pub mod error;

pub use driver::{Clock, Config, Counters, DeviceState, Driver, ScanData, SetBaud};
pub use error::Error;
