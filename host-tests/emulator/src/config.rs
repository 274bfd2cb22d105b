//! What the emulated device is at power-on and which faults it injects.

use lms2xx::codec::reply::ConfigBlock;
use lms2xx::codec::types::{Baud, Variant};

use super::SourceKind;

/// Fault injection on the device's output, deterministic from [`EmulatorConfig::seed`].
/// Probabilities are per B0 telegram; at most one damaging fault hits one telegram.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Faults {
    /// Flip one bit of one byte.
    pub bit_flip: f64,
    /// Drop one byte.
    pub drop_byte: f64,
    /// Send one byte twice.
    pub duplicate_byte: f64,
    /// Cut the telegram short.
    pub truncate: f64,
    /// Insert 1–40 random bytes before the telegram (does not damage it).
    pub garbage: f64,
    /// After this many B0 telegrams, stay silent for `silence_ms` (streaming resumes after).
    pub silence_after_scans: Option<u32>,
    /// Length of the silence, ms.
    pub silence_ms: u32,
    /// After this many B0 telegrams, reset spontaneously (back to 9600, request mode, 0x90).
    pub reset_after_scans: Option<u32>,
    /// Answer this many of the next commands with NAK instead of ACK + reply.
    pub nak_commands: u32,
    /// Apply the damaging faults (flip, drop, duplicate, truncate) to replies as well.
    pub damage_replies: bool,
}

/// Emulator settings.
#[derive(Clone, Debug)]
pub struct EmulatorConfig {
    /// Baud at power-on (9600 on a real device).
    pub initial_baud: Baud,
    /// Variant at power-on.
    pub variant: Variant,
    /// Configuration block at power-on (unit, measuring mode, availability).
    pub config: ConfigBlock,
    /// Type string (BA reply).
    pub type_string: String,
    /// Status byte of every reply.
    pub status: u8,
    /// Delay from the end of a command to the ACK, µs.
    pub ack_delay_us: u64,
    /// Delay from the ACK to the reply, µs.
    pub reply_delay_us: u64,
    /// Time from a reset to the power-on message, µs.
    pub reset_time_us: u64,
    /// Seed of the fault injection and garbling.
    pub seed: u64,
    /// Faults to inject.
    pub faults: Faults,
    /// Built-in scan source (used by [`serve_tcp`](super::serve_tcp) and `pfe emulate`).
    pub source: SourceKind,
    /// Command codes this device does not implement: answered `92` (incorrect command), as
    /// a variant or a simpler emulator might.
    pub unsupported: Vec<u8>,
    /// Baud rates this device cannot switch to: `20 4x` for them is answered `A0 01` and the
    /// device stays at its rate (an RS-232 LMS200 has no 500 000 Bd).
    pub refused_bauds: Vec<Baud>,
}

impl Default for EmulatorConfig {
    fn default() -> Self {
        Self {
            initial_baud: Baud::B9600,
            variant: Variant::A180_R050,
            config: ConfigBlock::default_mm(),
            type_string: "LMS200;30106".into(),
            status: 0x10,
            ack_delay_us: 1200,
            reply_delay_us: 2000,
            reset_time_us: 200_000,
            seed: 1,
            faults: Faults::default(),
            source: SourceKind::Room,
            unsupported: Vec::new(),
            refused_bauds: Vec::new(),
        }
    }
}
