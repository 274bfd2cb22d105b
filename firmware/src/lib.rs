//! Firmware library: the LMS200 telegram codec and driver, the application loop around
//! pfe-core, and the framed feature output. Host-testable (`no_std`, generic over
//! `embedded-io` / `embedded-hal` traits); the binaries (`firmware/qemu`, `firmware/board`)
//! add the hardware glue.
//!
//! # Layers (the data path, in folder order)
//!
//! ```text
//! UART bytes
//!   → rx_ring       the receive interrupt's lock-free ring (counts what it loses)
//!   → lms::codec    sans-IO telegram codec: framing, CRC-16, resync, commands, replies
//!   → lms::driver   the device over a UART: init, retries, re-init; delivers ScanData
//!   → app           the only bridge to pfe-core: ScanData → RawScan → pfe_core::Scan,
//!                   Extractor<401, 48>, counters → output header
//!   → output        wire types → encoder (postcard) → CRC-32 → COBS → UART bytes
//!                   (and the host-side decoder)
//! ```
//!
//! Imports go down the list only: [`lms::codec`] imports nothing else of the crate and no
//! pfe-core; [`lms::driver`] imports the codec; [`app`] imports the driver, the output and
//! pfe-core; [`output`] imports pfe-core's feature types only.
#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

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
pub mod lms;
pub mod output;
pub mod rx_ring;
