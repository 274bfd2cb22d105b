//! The wire types: what a frame carries, serialised by postcard (see the [module
//! docs](super) for the frame layout).

use pfe_core::{CircleFeature, Feature, LineFeature, Point};
use serde::{Deserialize, Serialize};

/// Version of the frame layout described here; bump it when a wire struct changes.
pub const WIRE_VERSION: u8 = 1;

/// Most features one decoded frame can hold.
pub const MAX_FEATURES: usize = 64;

/// Largest postcard encoding of one [`WireFeature`] (a circle: tag + 3 u16 varints + 15 f32).
pub const MAX_FEATURE_LEN: usize = 1 + 3 * 3 + 15 * 4;

/// Largest frame on the wire for `features` features (header, features, CRC, COBS overhead
/// and the terminating zero): size a receive buffer with it.
pub const fn max_frame_len(features: usize) -> usize {
    let raw = 64 + features * MAX_FEATURE_LEN + 4;
    raw + raw / 254 + 2
}

/// Link counters of the scanner driver, cumulative since start.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Counters {
    /// Telegrams received with a good CRC.
    pub telegrams_ok: u32,
    /// Telegrams dropped for a bad CRC.
    pub crc_dropped: u32,
    /// Bytes skipped while searching for a telegram start.
    pub bytes_skipped: u32,
    /// Times the driver re-initialised the scanner.
    pub reinits: u32,
}

/// Header of a scan frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ScanHeader {
    /// Scan sequence number (0 for the first scan after start).
    pub seq: u32,
    /// Link counters after this scan.
    pub counters: Counters,
    /// Valid readings in the scan.
    pub valid: u16,
    /// Segments found.
    pub segments: u16,
    /// Features that did not fit in the extractor's buffer (not sent).
    pub dropped: u16,
    /// Number of [`WireFeature`]s that follow.
    pub n_features: u16,
    /// How the extraction went.
    pub status: ScanStatus,
}

/// Outcome of one scan's extraction.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ScanStatus {
    /// All features were extracted and sent.
    #[default]
    Ok,
    /// The feature buffer was full: the first features are sent, `dropped` were lost.
    FeatureCapacity,
    /// The scan had more readings than the extractor's capacity: nothing extracted.
    TooManyReadings,
    /// The geometry or configuration was rejected: nothing extracted.
    InvalidInput,
}

/// What a timing report measured (see [`Report::Timing`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Stage {
    /// Decoding one B0 telegram (CRC and values).
    Decode,
    /// pfe-core with `Config::paper()`.
    ExtractPaper,
    /// pfe-core with `Config::default()`.
    ExtractDefault,
    /// Telegram bytes to encoded output frame, everything.
    Pipeline,
}

/// Out-of-band reports of the firmware.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Report {
    /// Stack high-water mark, bytes, out of the stack's size.
    Stack {
        /// Bytes of stack ever used.
        used: u32,
        /// Bytes reserved for the stack.
        size: u32,
    },
    /// Timer ticks spent on one stage of one scan.
    Timing {
        /// Scan sequence number.
        seq: u32,
        /// What was measured.
        stage: Stage,
        /// Timer ticks (SysTick under QEMU `-icount shift=10`: instructions = ticks × 10 / 256).
        ticks: u32,
        /// Readings in the scan.
        points: u16,
    },
    /// The firmware finished after `scans` scans.
    Done {
        /// Scans processed.
        scans: u32,
    },
}

/// First item of every frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Header {
    /// One scan's features follow.
    Scan(ScanHeader),
    /// A report; nothing follows.
    Report(Report),
}

/// A feature as sent: pfe-core's [`Feature`] with points as `[x, y]`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum WireFeature {
    /// A line `x cos α + y sin α = ρ` (see [`LineFeature`]).
    Line {
        /// First beam.
        first: u16,
        /// Last beam.
        last: u16,
        /// Valid points fitted.
        points: u16,
        /// α, rad.
        alpha: f32,
        /// ρ, mm.
        rho: f32,
        /// σ_α², rad².
        var_alpha: f32,
        /// σ_ρ², mm².
        var_rho: f32,
        /// cov(α, ρ), rad·mm.
        cov_alpha_rho: f32,
        /// Start point, mm.
        start: [f32; 2],
        /// End point, mm.
        end: [f32; 2],
    },
    /// A circle (see [`CircleFeature`]).
    Circle {
        /// First beam.
        first: u16,
        /// Last beam.
        last: u16,
        /// Valid points fitted.
        points: u16,
        /// Centre, mm.
        center: [f32; 2],
        /// Radius, mm.
        radius: f32,
        /// Covariance of (x, y, r), mm².
        cov: [[f32; 3]; 3],
        /// Bearing from the centre to the first point, rad.
        start_angle: f32,
        /// Bearing from the centre to the last point, rad.
        end_angle: f32,
    },
}

impl From<&Feature> for WireFeature {
    fn from(f: &Feature) -> Self {
        match *f {
            Feature::Line(l) => WireFeature::Line {
                first: l.first,
                last: l.last,
                points: l.points,
                alpha: l.alpha,
                rho: l.rho,
                var_alpha: l.var_alpha,
                var_rho: l.var_rho,
                cov_alpha_rho: l.cov_alpha_rho,
                start: [l.start.x, l.start.y],
                end: [l.end.x, l.end.y],
            },
            Feature::Circle(c) => WireFeature::Circle {
                first: c.first,
                last: c.last,
                points: c.points,
                center: [c.center.x, c.center.y],
                radius: c.radius,
                cov: c.cov,
                start_angle: c.start_angle,
                end_angle: c.end_angle,
            },
        }
    }
}

impl WireFeature {
    /// Back to pfe-core's type (bit-exact).
    pub fn to_feature(&self) -> Feature {
        match *self {
            WireFeature::Line {
                first,
                last,
                points,
                alpha,
                rho,
                var_alpha,
                var_rho,
                cov_alpha_rho,
                start,
                end,
            } => Feature::Line(LineFeature {
                first,
                last,
                points,
                alpha,
                rho,
                var_alpha,
                var_rho,
                cov_alpha_rho,
                start: Point::new(start[0], start[1]),
                end: Point::new(end[0], end[1]),
            }),
            WireFeature::Circle {
                first,
                last,
                points,
                center,
                radius,
                cov,
                start_angle,
                end_angle,
            } => Feature::Circle(CircleFeature {
                first,
                last,
                points,
                center: Point::new(center[0], center[1]),
                radius,
                cov,
                start_angle,
                end_angle,
            }),
        }
    }

    /// True for a line.
    pub fn is_line(&self) -> bool {
        matches!(self, WireFeature::Line { .. })
    }
}
