//! The robot's side of the firmware's output link: frames in, JSON lines out.
//!
//! - `clock`: [`clock::FirmwareClock`], a frame's firmware time as a Unix timestamp.
//! - `listen`: [`listen::Listener`] (sans-IO: byte chunks in, decoded scans and counts out),
//!   [`listen::ListenJson`] (one output line per scan), the byte sources of `pfe listen`.

pub mod clock;
pub mod listen;
