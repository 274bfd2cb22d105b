//! Firmware library: LMS200 telegram codec, driver and the application loop around pfe-core.
#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
