//! The device side: an emulated SICK LMS200 ([`emulator`]) and a real one recorded through the
//! firmware driver ([`record`], over the std adapters of [`tty`]).

pub mod emulator;
pub mod record;
pub mod tty;
