//! The SICK LMS2xx serial protocol (LMS200 / LMS291 family) for `no_std`, without allocation
//! and without panics: [`codec`] turns bytes into telegrams and back (sans-IO), [`driver`]
//! runs the device over a UART (initialisation, retries, re-initialisation, scans): one
//! sans-IO state machine ([`driver::machine`]) behind a blocking [`driver::Driver`] and, with
//! the `async` feature, an `AsyncDriver` for embassy (`embedded-io-async`,
//! `embedded-hal-async`).
//!
//! Data path: UART bytes → [`codec::frame::Decoder`] (framing, CRC-16, resync) →
//! [`codec::reply::parse_reply`] → [`driver::machine::Machine`] → [`driver::Driver`] →
//! [`driver::ScanData`].
//!
//! Imports go one way: [`codec`] imports nothing else of the crate; [`driver`] imports the
//! codec. Each item has one public path (`lms2xx::codec::frame::Decoder`,
//! `lms2xx::driver::Driver`); there are no re-exports at the crate root.
//!
//! A device's acknowledgement of "switch baud rate" (reply `0xA0`, status `0x10`) as bytes,
//! decoded back into a telegram and parsed as a reply:
//!
//! ```
//! use lms2xx::codec::frame::{encode_telegram, Decoder, Event, DEVICE_ADDRESS, MAX_TELEGRAM};
//! use lms2xx::codec::reply::{parse_reply, Reply, ReplyOptions};
//!
//! let mut raw = [0u8; 16];
//! let n = encode_telegram(DEVICE_ADDRESS, &[0xA0, 0x00, 0x10], &mut raw)?;
//! let mut decoder = Decoder::<MAX_TELEGRAM>::new();
//! match decoder.feed(raw.get(..n).unwrap_or(&[])) {
//!     (_, Some(Event::Telegram(t))) => {
//!         let reply = parse_reply(t.payload(), ReplyOptions::default())?;
//!         assert_eq!(reply.reply, Reply::Mode(0));
//!     }
//!     _ => return Err("no telegram".into()),
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
#![deny(clippy::indexing_slicing)]

/// `defmt::$level!(...)` with the `defmt` feature, nothing without it.
macro_rules! log {
    ($level:ident, $($arg:tt)*) => {
        #[cfg(feature = "defmt")]
        {
            defmt::$level!($($arg)*);
        }
    };
}

pub mod codec;
pub mod driver;
