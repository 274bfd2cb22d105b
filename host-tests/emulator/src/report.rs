//! What an emulator run sent and counted.

use lms2xx::codec::types::{MeasuringMode, Unit};

/// A scan the emulator sent.
#[derive(Clone, Debug, PartialEq)]
pub struct SentScan {
    /// Sequence number (0-based) of B0 telegrams sent.
    pub seq: u32,
    /// The value words sent.
    pub words: Vec<u16>,
    /// The ranges (mm) the source produced.
    pub ranges_mm: Vec<f32>,
    /// Unit and measuring mode in force.
    pub unit: Unit,
    /// Measuring mode in force.
    pub mode: MeasuringMode,
    /// True when a fault or a baud mismatch damaged it on the way.
    pub damaged: bool,
}

/// Counters and logs of one emulator run.
#[derive(Clone, Debug, Default)]
pub struct EmulatorReport {
    /// Commands received with a good CRC (code bytes, in order).
    pub commands: Vec<u8>,
    /// B0 telegrams sent.
    pub scans: Vec<SentScan>,
    /// Host bytes dropped because the host's baud differed from the device's.
    pub garbled_in: u64,
    /// Device bytes garbled because the host's baud differed.
    pub garbled_out: u64,
    /// Host telegrams with a bad CRC (answered with NAK).
    pub bad_commands: u32,
    /// Device bytes sent.
    pub bytes_out: u64,
    /// Resets (commanded or injected).
    pub resets: u32,
    /// Replies damaged by [`Faults::damage_replies`](super::Faults::damage_replies).
    pub damaged_replies: u32,
}
