//! A real SICK LMS200 recorded through the firmware driver ([`record`], over the std adapters
//! of [`tty`]). The emulated one is the `lms200-emulator` crate.

pub mod record;
pub mod tty;
