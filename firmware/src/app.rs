//! The application loop: scans from the driver → pfe-core → framed output.
//!
//! [`App`] owns a statically sized [`Extractor`] (put the `App` in a `static`: about
//! `9·N + 64·M` bytes) and turns each [`RawScan`] into one output frame
//! ([`crate::output::write_scan`]). Where the scans come from is a [`ScanSource`]: the LMS200
//! driver on a board, a test double on the host.
//!
//! ```
//! use firmware::app::{App, ConfigChoice, RawScan};
//! use firmware::output::{Counters, Feed, FrameDecoder};
//! use pfe_core::ScanGeometry;
//! // A wall 2 m ahead, as raw LMS200 codes in mm.
//! let g = ScanGeometry::LMS200_180_050;
//! let values: Vec<u16> = (0..361)
//!     .map(|i| {
//!         let b = g.bearing(i);
//!         if b.abs() < 1.0 { (2000.0 / b.cos()).round() as u16 } else { 8183 }
//!     })
//!     .collect();
//! let mut app = App::<361, 48>::new(ConfigChoice::Default);
//! let mut buf = [0u8; 1024];
//! let mut out = &mut buf[..];
//! let scan = RawScan::lms_8m(g, &values, 1.0);
//! let header = app.process(&scan, Counters::default(), &mut out)?;
//! assert_eq!(header.n_features, 1);
//! let n = 1024 - out.len();
//! let Feed::Frame { frame, .. } = FrameDecoder::<1024>::new().feed(&buf[..n]) else {
//!     return Err("no frame".into());
//! };
//! assert!(frame.features[0].is_line());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use embedded_hal::delay::DelayNs;
use embedded_io::Write;
use embedded_io::{Read, ReadReady};
use pfe_core::{Config, ExtractError, Extractor, Ranges, Scan, ScanGeometry};

use crate::lms::driver::{Clock, Driver, SetBaud};

use crate::output::{self, Counters, EncodeError, ScanHeader, ScanStatus};

/// One scan as the driver delivers it: raw range codes (measuring-mode flag bits removed).
#[derive(Clone, Copy, Debug)]
pub struct RawScan<'a> {
    /// Beam geometry of the scanner's variant.
    pub geometry: ScanGeometry,
    /// Range codes; 0 and codes above 8182 are no return.
    pub values: &'a [u16],
    /// mm per code: 1.0 in mm mode, 10.0 in cm mode.
    pub mm_per_unit: f32,
    /// Largest valid code ([`pfe_core::LMS_MAX_VALID_8M`] in the 8 m / 80 m modes).
    pub max_valid: u16,
}

impl<'a> RawScan<'a> {
    /// A scan in the 8 m / 80 m measuring modes (largest valid code 8182).
    pub fn lms_8m(geometry: ScanGeometry, values: &'a [u16], mm_per_unit: f32) -> Self {
        Self {
            geometry,
            values,
            mm_per_unit,
            max_valid: pfe_core::LMS_MAX_VALID_8M,
        }
    }

    /// The pfe-core input for this scan.
    pub fn to_pfe(&self) -> Scan<'a> {
        Scan {
            geometry: self.geometry,
            ranges: Ranges::Raw {
                values: self.values,
                mm_per_unit: self.mm_per_unit,
                max_valid: self.max_valid,
            },
            motion: None,
        }
    }
}

/// Where scans come from (the LMS200 driver through a small adapter, or a test double).
pub trait ScanSource {
    /// Why no scan could be delivered.
    type Error: core::fmt::Debug;
    /// Blocks (with a timeout) until the next complete scan; returns it with the link
    /// counters after it.
    fn next_scan(&mut self) -> Result<(RawScan<'_>, Counters), Self::Error>;
}

/// The named pfe-core configurations.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigChoice {
    /// `Config::paper()`: the method as published.
    Paper,
    /// `Config::default()`: noise-model threshold, boundary localisation, fit comparison.
    Default,
}

impl ConfigChoice {
    /// The configuration.
    pub const fn config(self) -> Config {
        match self {
            ConfigChoice::Paper => Config::paper(),
            ConfigChoice::Default => Config::default_config(),
        }
    }
}

/// Why a step of the loop failed.
#[derive(Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum AppError<S, W> {
    /// The scan source (driver) failed.
    Source(S),
    /// Writing the output frame failed.
    Output(EncodeError<W>),
}

impl<S: core::fmt::Debug, W: core::fmt::Debug> core::fmt::Display for AppError<S, W> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            AppError::Source(e) => write!(f, "scan source: {e:?}"),
            AppError::Output(e) => write!(f, "output: {e}"),
        }
    }
}

impl<S: core::fmt::Debug, W: core::fmt::Debug> core::error::Error for AppError<S, W> {}

/// Most features of one scan the firmware keeps.
pub const MAX_FEATURES: usize = 48;

/// The application the firmware runs: room for every LMS2xx scan
/// ([`crate::lms::driver::MAX_VALUES`]) and [`MAX_FEATURES`] features.
pub type LmsApp = App<{ crate::lms::driver::MAX_VALUES }, MAX_FEATURES>;

/// The application: extractor with room for `N` readings and `M` features, a configuration
/// and the scan sequence number.
pub struct App<const N: usize, const M: usize> {
    extractor: Extractor<N, M>,
    config: ConfigSlot,
    seq: u32,
}

/// The configuration an [`App`] uses. The named ones are tags only, so that a new `App` with
/// the default configuration is all zero bytes: a `static` of it goes to `.bss` instead of
/// being copied from flash (8 KiB of flash for a 401-value extractor).
#[derive(Clone, Copy, Debug)]
#[repr(u8)]
enum ConfigSlot {
    Default = 0,
    Paper = 1,
    Custom(Config) = 2,
}

impl ConfigSlot {
    const fn named(choice: ConfigChoice) -> Self {
        match choice {
            ConfigChoice::Default => ConfigSlot::Default,
            ConfigChoice::Paper => ConfigSlot::Paper,
        }
    }

    fn get(&self) -> &Config {
        match self {
            ConfigSlot::Default => &DEFAULT,
            ConfigSlot::Paper => &PAPER,
            ConfigSlot::Custom(c) => c,
        }
    }
}

/// What [`ConfigSlot::Default`] and [`ConfigSlot::Paper`] stand for.
static DEFAULT: Config = Config::default_config();
static PAPER: Config = Config::paper();

impl<const N: usize, const M: usize> App<N, M> {
    /// A new application (`const`: it can live in a `static`).
    pub const fn new(choice: ConfigChoice) -> Self {
        Self::with_slot(ConfigSlot::named(choice))
    }

    /// A new application with any configuration.
    pub const fn with_config(config: Config) -> Self {
        Self::with_slot(ConfigSlot::Custom(config))
    }

    const fn with_slot(config: ConfigSlot) -> Self {
        Self {
            extractor: Extractor::new(),
            config,
            seq: 0,
        }
    }

    /// Changes the configuration (in place: no copy of the extractor on the stack).
    pub fn set_config(&mut self, config: Config) {
        self.config = ConfigSlot::Custom(config);
    }

    /// Switches to a named configuration.
    pub fn set_choice(&mut self, choice: ConfigChoice) {
        self.config = ConfigSlot::named(choice);
    }

    /// The configuration in use.
    pub fn config(&self) -> &Config {
        self.config.get()
    }

    /// The extractor (features, marks and stats of the last scan).
    pub fn extractor(&self) -> &Extractor<N, M> {
        &self.extractor
    }

    /// Scans processed so far (the next scan's sequence number).
    pub fn seq(&self) -> u32 {
        self.seq
    }

    /// Extracts the features of `scan` and writes its frame to `out`; returns the header sent.
    pub fn process<W: Write>(
        &mut self,
        scan: &RawScan<'_>,
        counters: Counters,
        out: &mut W,
    ) -> Result<ScanHeader, EncodeError<W::Error>> {
        let s = scan.to_pfe();
        let result = self.extractor.extract(&s, self.config.get());
        let stats = self.extractor.stats();
        let status = match result {
            Ok(_) => ScanStatus::Ok,
            Err(ExtractError::FeatureCapacity { .. }) => ScanStatus::FeatureCapacity,
            Err(ExtractError::TooManyReadings { .. }) => ScanStatus::TooManyReadings,
            Err(_) => ScanStatus::InvalidInput,
        };
        let sat = |v: usize| u16::try_from(v).unwrap_or(u16::MAX);
        let features = self.extractor.features();
        let header = ScanHeader {
            seq: self.seq,
            counters,
            valid: sat(stats.valid),
            segments: sat(stats.segments),
            dropped: sat(stats.dropped),
            n_features: sat(features.len()),
            status,
        };
        self.seq = self.seq.wrapping_add(1);
        output::write_scan(out, &header, features)?;
        Ok(header)
    }

    /// Waits for the next scan from `source` and processes it.
    pub fn step<S: ScanSource, W: Write>(
        &mut self,
        source: &mut S,
        out: &mut W,
    ) -> Result<ScanHeader, AppError<S::Error, W::Error>> {
        let (scan, counters) = source.next_scan().map_err(AppError::Source)?;
        self.process(&scan, counters, out).map_err(AppError::Output)
    }
}

/// The LMS200 driver as a scan source: geometry, unit and measuring mode from the driver,
/// counters mapped to the output's (`crc_dropped` = CRC errors + bad lengths/overflows).
impl<U, D, C> ScanSource for Driver<U, D, C>
where
    U: Read + Write + ReadReady + SetBaud,
    U::Error: core::fmt::Debug,
    D: DelayNs,
    C: Clock,
{
    type Error = crate::lms::Error<U::Error>;

    fn next_scan(&mut self) -> Result<(RawScan<'_>, Counters), Self::Error> {
        Driver::next_scan(self)?;
        let c = self.counters();
        let counters = Counters {
            telegrams_ok: c.telegrams_ok,
            crc_dropped: c.crc_errors.saturating_add(c.bad_length),
            bytes_skipped: c.bytes_skipped,
            reinits: c.reinits,
        };
        let scan = self.last_scan();
        let raw = RawScan {
            geometry: scan.geometry(),
            values: scan.codes(),
            mm_per_unit: scan.mm_per_unit(),
            max_valid: scan.max_valid(),
        };
        Ok((raw, counters))
    }
}
