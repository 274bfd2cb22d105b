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
//! One file per job: `traits` (what the platform provides: [`Clock`], [`SetBaud`]), `config`
//! ([`Config`]), `state` ([`DeviceState`], [`Counters`]), `scan` (the delivered [`ScanData`]),
//! `pump` (bytes and command transactions), `init` (initialisation), `stream` (scans and
//! re-initialisation), `error` ([`Error`]). Every item is public here, at `lms2xx::driver::`.

use embedded_hal::delay::DelayNs;
use embedded_io::{Read, ReadReady, Write};

use crate::codec::frame::{Decoder, MAX_TELEGRAM};
use crate::codec::types::Baud;

mod config;
mod error;
mod init;
mod pump;
mod scan;
mod state;
mod stream;
mod traits;

use config::poll_interval;
pub use config::Config;
pub use error::Error;
use pump::{REPLY_CAP, RX_CHUNK};
pub use scan::{ScanData, MAX_VALUES};
pub use state::{Counters, DeviceState};
pub use traits::{Clock, SetBaud};

/// The LMS200 driver. See the module docs for the sequence.
///
/// ```no_run
/// # fn demo<U, D, C>(uart: U, delay: D, clock: C) -> Result<(), lms2xx::driver::Error<U::Error>>
/// # where U: embedded_io::Read + embedded_io::Write + embedded_io::ReadReady + lms2xx::driver::SetBaud,
/// #       D: embedded_hal::delay::DelayNs, C: lms2xx::driver::Clock {
/// use lms2xx::driver::{Config, Driver};
/// let mut lms = Driver::new(uart, delay, clock, Config::default());
/// lms.init()?;
/// loop {
///     let scan = lms.next_scan()?;
///     let _ranges = scan.codes(); // 361 range codes in mm
/// #   break;
/// }
/// let (_uart, _delay, _clock) = lms.release();
/// # Ok(()) }
/// ```
pub struct Driver<U, D, C> {
    uart: U,
    delay: D,
    clock: C,
    config: Config,
    decoder: Decoder<MAX_TELEGRAM>,
    rx: [u8; RX_CHUNK],
    rx_pos: usize,
    rx_len: usize,
    /// Current poll interval, µs (see [`Config::poll_interval_us`]).
    idle_us: u32,
    reply: [u8; REPLY_CAP],
    reply_len: usize,
    scan: ScanData,
    scan_ok: bool,
    device: DeviceState,
    streaming: bool,
    initialised_once: bool,
    reset_seen: bool,
    /// A scan that looks like a device reset re-initialises only while this is set; cleared
    /// by that re-initialisation, set again by a scan that looks normal.
    reset_check_armed: bool,
    last_scan_ms: u32,
    last_cmd_ms: u32,
    counters: Counters,
}

impl<U, D, C> Driver<U, D, C>
where
    U: Read + Write + ReadReady + SetBaud,
    D: DelayNs,
    C: Clock,
{
    /// A driver owning the UART, a delay and a clock. Nothing is sent until [`Driver::init`] or
    /// [`Driver::next_scan`].
    pub fn new(uart: U, delay: D, clock: C, config: Config) -> Self {
        Self {
            uart,
            delay,
            clock,
            config,
            decoder: Decoder::new(),
            rx: [0; RX_CHUNK],
            rx_pos: 0,
            rx_len: 0,
            idle_us: poll_interval(config.poll_interval_us, Baud::B9600),
            reply: [0; REPLY_CAP],
            reply_len: 0,
            scan: ScanData::default(),
            scan_ok: false,
            device: DeviceState::default(),
            streaming: false,
            initialised_once: false,
            reset_seen: false,
            reset_check_armed: true,
            last_scan_ms: 0,
            last_cmd_ms: 0,
            counters: Counters::default(),
        }
    }

    /// Gives back the UART, delay and clock.
    pub fn release(self) -> (U, D, C) {
        (self.uart, self.delay, self.clock)
    }

    /// Counters so far (decoder counters included).
    pub fn counters(&self) -> Counters {
        let s = self.decoder.stats();
        Counters {
            telegrams_ok: s.telegrams,
            crc_errors: s.crc_errors,
            bad_length: s.bad_length.saturating_add(s.overflows),
            bytes_skipped: s.bytes_skipped,
            naks: s.naks,
            ..self.counters
        }
    }

    /// What the driver knows about the device.
    pub fn device(&self) -> &DeviceState {
        &self.device
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// The last scan delivered (empty before the first).
    pub fn last_scan(&self) -> &ScanData {
        &self.scan
    }

    /// True while the device is in continuous output.
    pub fn is_streaming(&self) -> bool {
        self.streaming
    }
}
