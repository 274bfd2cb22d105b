//! The application loop, and the only place where LMS scans meet pfe-core: scans from the
//! driver → pfe-core → framed output.
//!
//! [`App`] owns a statically sized [`Extractor`] and the pose step ([`PoseStep`]: pfe-pose's
//! odometry with its local map) (put the `App` in a `static`, all zero bytes: `.bss`; about
//! `25·N + 68·M` bytes + 7.7 KiB for the pose step, 20.9 KiB for `App<401, 48>`) and turns each
//! [`RawScan`] into one output frame with the scan's pose ([`pfe_frame::write_scan_with_pose`]).
//! Where the scans come from is a [`ScanSource`]: the LMS200 driver on a board, a test double
//! on the host.
//!
//! - `scan`: [`RawScan`] and [`ScanDataExt`], the driver's scan as pfe-core input (the one
//!   adapter).
//! - `source`: [`ScanSource`], implemented by the driver; its counters as the output's
//!   ([`link_counters`]).
//! - `pose`: [`PoseStep`], the features' odometry as the frame's pose block.
//!
//! ```
//! use firmware::app::{App, ConfigChoice, RawScan};
//! use pfe_frame::{Counters, Feed, FrameDecoder};
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
//! assert_eq!(frame.scan().map(|h| h.time_ms), Some(0)); // lms_8m: time unknown
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use embedded_io::Write;
use pfe_core::{Config, ExtractError, Extractor};

use lms2xx::codec::types::Variant;
use pfe_frame::{Counters, EncodeError, ScanHeader, ScanStatus};

mod pose;
mod scan;
mod source;

pub use pose::{pose_block, PoseStep};
pub use scan::{RawScan, ScanDataExt};
pub use source::{link_counters, ScanSource};

/// The named pfe-core configurations, each for a SICK LMS2xx as `pfe extract --format lms200
/// [--config paper]` runs it on the host ([`Config::for_lms2xx`]: σ_r 5 mm, σ_sys 5 mm); with
/// the scans as [`RawScan::to_pfe`] builds them the board's features are the host's, bit for
/// bit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigChoice {
    /// `Config::paper()`: the method as published.
    Paper,
    /// `Config::default()`, everything on: noise-model threshold, boundary localisation, fit
    /// comparison, the checks for real scans (`Config::scrutiny`: the scan's own σ, joined
    /// short segments, corner splits, reach, no unseeable lines, small objects) and the
    /// interleaved sweeps aligned.
    Default,
}

impl ConfigChoice {
    /// The configuration.
    pub const fn config(self) -> Config {
        match self {
            ConfigChoice::Paper => Config::paper().for_lms2xx(),
            ConfigChoice::Default => Config::default_config().for_lms2xx(),
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

/// Readings the firmware's extractor has room for: every LMS2xx scan (100° at 0.25°: 401).
pub const LMS_READINGS: usize = Variant::MAX_VALUES;
/// Features the firmware's extractor has room for.
pub const LMS_FEATURES: usize = 48;
/// The firmware's extractor: room for every LMS2xx scan and [`LMS_FEATURES`] features.
pub type LmsExtractor = Extractor<LMS_READINGS, LMS_FEATURES>;
/// The application the firmware runs (its extractor an [`LmsExtractor`]).
pub type LmsApp = App<LMS_READINGS, LMS_FEATURES>;

/// The application: extractor with room for `N` readings and `M` features, a configuration
/// and the scan sequence number.
pub struct App<const N: usize, const M: usize> {
    extractor: Extractor<N, M>,
    config: ConfigSlot,
    seq: u32,
    pose: PoseStep,
    /// The pose step is off (false, all zero, by default).
    pose_off: bool,
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
static DEFAULT: Config = ConfigChoice::Default.config();
static PAPER: Config = ConfigChoice::Paper.config();

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
            pose: PoseStep::new(),
            pose_off: false,
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

    /// The pose step (its odometry: map and latest pose).
    pub fn pose(&self) -> &PoseStep {
        &self.pose
    }

    /// Scans processed so far (the next scan's sequence number).
    pub fn seq(&self) -> u32 {
        self.seq
    }

    /// Extracts the features of `scan`, registers them ([`PoseStep::update`]) and writes its
    /// frame with the pose block to `out`; returns the header sent.
    pub fn process<W: Write>(
        &mut self,
        scan: &RawScan<'_>,
        counters: Counters,
        out: &mut W,
    ) -> Result<ScanHeader, EncodeError<W::Error>> {
        let header = self.extract(scan, counters);
        let pose = self.update_pose();
        self.write_frame(out, &header, pose.as_ref())?;
        Ok(header)
    }

    /// The first step of [`App::process`], alone (to measure each): extracts the features of
    /// `scan` and returns the frame's header (the sequence number advances).
    pub fn extract(&mut self, scan: &RawScan<'_>, counters: Counters) -> ScanHeader {
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
            time_ms: scan.time_ms,
            counters,
            valid: sat(stats.valid),
            segments: sat(stats.segments),
            dropped: sat(stats.dropped),
            n_features: sat(features.len()),
            status,
        };
        self.seq = self.seq.wrapping_add(1);
        header
    }

    /// The second step of [`App::process`]: the pose of the features last extracted
    /// ([`PoseStep::update`]); `None` with the pose step off ([`App::set_pose_step`]).
    pub fn update_pose(&mut self) -> Option<pfe_frame::PoseBlock> {
        if self.pose_off {
            return None;
        }
        Some(self.pose.update(self.extractor.features()))
    }

    /// The last step of [`App::process`]: the frame of the features last extracted, with
    /// `header` and the pose block `pose`.
    pub fn write_frame<W: Write>(
        &self,
        out: &mut W,
        header: &ScanHeader,
        pose: Option<&pfe_frame::PoseBlock>,
    ) -> Result<(), EncodeError<W::Error>> {
        pfe_frame::write_scan_with_pose(out, header, self.extractor.features(), pose)
    }

    /// Switches the pose step on (the default) or off (frames then carry no pose block, and
    /// the odometry restarts when it is switched on again).
    pub fn set_pose_step(&mut self, on: bool) {
        if on && self.pose_off {
            self.pose.reset();
        }
        self.pose_off = !on;
    }

    /// [`App::process`] without the pose step: the frame carries no pose block. A binary that
    /// calls only this (the board's: the pose step costs far more than a scan period on the
    /// M4F, docs/POSE.md) links none of the pose code.
    pub fn process_features<W: Write>(
        &mut self,
        scan: &RawScan<'_>,
        counters: Counters,
        out: &mut W,
    ) -> Result<ScanHeader, EncodeError<W::Error>> {
        let header = self.extract(scan, counters);
        self.write_frame(out, &header, None)?;
        Ok(header)
    }

    /// [`App::step`] without the pose step ([`App::process_features`]).
    pub fn step_features<S: ScanSource, W: Write>(
        &mut self,
        source: &mut S,
        out: &mut W,
    ) -> Result<ScanHeader, AppError<S::Error, W::Error>> {
        let (scan, counters) = source.next_scan().map_err(AppError::Source)?;
        self.process_features(&scan, counters, out)
            .map_err(AppError::Output)
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
