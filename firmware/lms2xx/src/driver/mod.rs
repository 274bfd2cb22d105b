//! LMS200 driver over `embedded-io` UART halves, a delay and a millisecond clock.
//!
//! Initialises like the reference clients (sicktoolbox order): probe the baud rate with `20 25`,
//! switch baud (`20 4x`, the reply comes at the old rate, then wait ≥ 250 ms; a refused rate
//! keeps the one found), type `3A`, status `31`, configuration `74`, variant `3B` when it
//! differs (a refusal keeps the device's, known from the status or the scans' value count),
//! unit / measuring mode through installation mode + `77` when they differ (a refusal
//! keeps the device's: scans carry their unit), then continuous output `20 24`. Every wait has
//! a timeout; commands are tried [`Config::tries`] times; silence or a device reset triggers a
//! re-initialisation. No allocation, no panic.
//!
//! The protocol is one sans-IO state machine, [`machine::Machine`] (its receive pump and
//! command transactions in `machine`, initialisation in `init`, streaming and
//! re-initialisation in `stream`); the drivers are thin loops that carry out its actions:
//! [`Driver`] (blocking, `embedded-io` + `DelayNs` busy-polling) and, with the `async`
//! feature, `AsyncDriver` (`embedded-io-async` + `embedded-hal-async`). Both therefore share
//! the configuration, timeouts, errors and counters. The other files: `traits` (what the
//! platform provides: [`Clock`], [`SetBaud`]), `config` ([`Config`]), `state`
//! ([`DeviceState`], [`Counters`]), `scan` (the delivered [`ScanData`]), `error` ([`Error`]).
//! Every item is public here, at `lms2xx::driver::`.

#[cfg(feature = "async")]
mod asynch;
mod blocking;
mod config;
mod error;
mod init;
pub mod machine;
mod scan;
mod state;
mod stream;
mod traits;

#[cfg(feature = "async")]
pub use asynch::{read_with_timeout, AsyncDriver, AsyncSetBaud};
pub use blocking::Driver;
pub use config::Config;
pub use error::Error;
pub use scan::{ScanData, MAX_VALUES};
pub use state::{Counters, DeviceState};
pub use traits::{Clock, SetBaud};
