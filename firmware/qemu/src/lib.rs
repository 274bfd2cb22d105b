//! Board support for QEMU's `mps2-an386` (Cortex-M4F) used by the pfe firmware binaries:
//! CMSDK APB UARTs as polled `embedded-io` ports, UART0 to the scanner through its receive
//! interrupt and the firmware's receive ring ([`scanner_uart`]), a SysTick time base, semihosting exit and
//! arguments, the stack high-water mark, and the runtime glue the binaries share (exception
//! and panic handlers, the statics in [`rt`]), and with feature `async` the async UART, delay
//! and executor of the `pfe-qemu-async` binary ([`asynch`]).
//!
//! Everything here only exists for `target_os = "none"`; on the host the crate is empty so
//! `cargo test --workspace` and clippy still build it.
#![cfg_attr(target_os = "none", no_std)]
#![deny(missing_docs)]
#![deny(unsafe_code)]
#![deny(clippy::indexing_slicing)]

#[cfg(target_os = "none")]
pub mod uart;

#[cfg(target_os = "none")]
pub mod scanner_uart;

#[cfg(target_os = "none")]
pub mod time;

#[cfg(target_os = "none")]
pub mod sys;

#[cfg(target_os = "none")]
pub mod rt;

#[cfg(all(target_os = "none", feature = "async"))]
pub mod asynch;
