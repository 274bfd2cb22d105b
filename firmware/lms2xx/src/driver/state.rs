//! What the driver knows about the device, and its counters.

use crate::codec::types::{Baud, MeasuringMode, Unit, Variant};

/// What the driver knows about the device after initialisation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub struct DeviceState {
    /// Baud rate the device runs at (None before the probe).
    pub baud: Option<Baud>,
    /// Current variant.
    pub variant: Variant,
    /// Current unit.
    pub unit: Option<Unit>,
    /// Current measuring mode.
    pub measuring_mode: MeasuringMode,
    /// B0 telegrams carry a real-time scan index.
    pub realtime_index: bool,
    /// Type string (`LMS200;30106`), ASCII, zero padded.
    pub type_string: [u8; 20],
}

/// Driver counters. All saturate.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub struct Counters {
    /// Telegrams with a good CRC.
    pub telegrams_ok: u32,
    /// Candidate telegrams dropped for a bad CRC.
    pub crc_errors: u32,
    /// Candidates dropped for a bad length or buffer overflow.
    pub bad_length: u32,
    /// Bytes skipped while resynchronising.
    pub bytes_skipped: u32,
    /// NAK bytes received.
    pub naks: u32,
    /// Command tries that timed out.
    pub timeouts: u32,
    /// Command retries (second and later tries).
    pub retries: u32,
    /// Re-initialisations (after the first initialisation).
    pub reinits: u32,
    /// Scans delivered.
    pub scans: u32,
    /// Telegrams with a good CRC but an unusable layout (e.g. B0 length ≠ count).
    pub bad_replies: u32,
    /// Device resets seen (0x90 / 0x91, unexpected A0, restart status).
    pub device_resets: u32,
    /// Initialisations that kept the device's baud rate because it refused
    /// [`Config::baud`](super::Config::baud).
    pub baud_refused: u32,
    /// Initialisations that kept the device's variant because it refused
    /// [`Config::variant`](super::Config::variant).
    pub variant_refused: u32,
    /// Initialisations that kept the device's unit and measuring mode because it refused
    /// [`Config::unit`](super::Config::unit) /
    /// [`Config::measuring_mode`](super::Config::measuring_mode) or did not report its
    /// configuration.
    pub config_refused: u32,
}
