//! Firmware library: the LMS200 telegram codec and driver, the application loop around
//! pfe-core, and the framed feature output. Host-testable (`no_std`, generic over
//! `embedded-io` / `embedded-hal` traits); the binaries in `src/bin` add the hardware glue.
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
