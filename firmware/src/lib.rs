//! pfe's firmware application, host-testable (`no_std`, generic over `embedded-io` /
//! `embedded-hal` traits): the loop from the LMS2xx driver's scans through pfe-core's
//! extractor to feature frames, and the UART receive ring. The binaries (`firmware/qemu`,
//! `firmware/board`) add the hardware glue.
//!
//! # The data path
//!
//! ```text
//! UART bytes
//!   → rx_ring              the receive interrupt's lock-free ring (counts what it loses)
//!   → lms2xx::codec        sans-IO telegram codec: framing, CRC-16, resync, commands, replies
//!   → lms2xx::driver       the device over a UART: init, retries, re-init; delivers ScanData
//!   → app                  the only bridge to pfe-core: ScanData → RawScan → pfe_core::Scan,
//!                          Extractor<401, 48>, counters → frame header
//!   → pfe_frame            wire types → encoder (postcard) → CRC-32 → COBS → UART bytes
//! ```
//!
//! This crate imports `lms2xx`, `pfe-frame` and pfe-core; none of them imports it, and
//! `lms2xx` imports neither pfe-core nor `pfe-frame`.
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

pub mod app;
pub mod rx_ring;
