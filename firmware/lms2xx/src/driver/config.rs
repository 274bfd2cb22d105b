//! Driver settings.

use crate::codec::types::{Baud, MeasuringMode, Unit, Variant};

/// Driver settings. `#[non_exhaustive]`: start from [`Config::default`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub struct Config {
    /// Baud rate to run at.
    pub baud: Baud,
    /// Scan variant to set (default 180° at 0.5°).
    pub variant: Variant,
    /// Range unit to set (default mm).
    pub unit: Unit,
    /// Measuring mode to set; `None` keeps the device's.
    pub measuring_mode: Option<MeasuringMode>,
    /// Reply timeout for ordinary commands, ms.
    pub reply_timeout_ms: u32,
    /// Reply timeout for the configuration write `77`, ms.
    pub config_timeout_ms: u32,
    /// Tries per command.
    pub tries: u8,
    /// Wait after a baud change, ms (sicktoolbox 250, MRPT 500).
    pub baud_switch_wait_ms: u32,
    /// Re-initialise when no scan arrived for this long, ms (at least two telegrams' time at
    /// the current baud rate).
    pub silence_timeout_ms: u32,
    /// Re-initialisations [`Driver::next_scan`](super::Driver::next_scan) attempts before returning [`Error::Silence`](super::Error::Silence).
    pub max_reinits_per_call: u8,
    /// Longest poll interval while waiting for bytes, µs; the driver never waits longer
    /// than half a character time at the current baud (a 1-byte receive register cannot
    /// overrun while the driver waits).
    pub poll_interval_us: u32,
}

/// The poll interval at `baud`: `max_us`, but at most half a 10-bit character time, ≥ 1 µs.
pub(super) fn poll_interval(max_us: u32, baud: Baud) -> u32 {
    max_us.min(5_000_000 / baud.bps()).max(1)
}

impl Default for Config {
    fn default() -> Self {
        Self {
            baud: Baud::B38400,
            variant: Variant::A180_R050,
            unit: Unit::Mm,
            measuring_mode: None,
            reply_timeout_ms: 1000,
            config_timeout_ms: 15_000,
            tries: 3,
            baud_switch_wait_ms: 250,
            silence_timeout_ms: 1000,
            max_reinits_per_call: 2,
            poll_interval_us: 500,
        }
    }
}

impl Config {
    /// Default settings with another baud rate.
    pub fn with_baud(mut self, baud: Baud) -> Self {
        self.baud = baud;
        self
    }
    /// Default settings with another variant.
    pub fn with_variant(mut self, variant: Variant) -> Self {
        self.variant = variant;
        self
    }
    /// Default settings with another unit.
    pub fn with_unit(mut self, unit: Unit) -> Self {
        self.unit = unit;
        self
    }
    /// Sets the measuring mode to select.
    pub fn with_measuring_mode(mut self, mode: MeasuringMode) -> Self {
        self.measuring_mode = Some(mode);
        self
    }
    /// Sets the silence timeout.
    pub fn with_silence_timeout_ms(mut self, ms: u32) -> Self {
        self.silence_timeout_ms = ms;
        self
    }
}
