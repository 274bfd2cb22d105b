//! The wire types: what a frame carries, serialised by postcard (see the [module
//! docs](super) for the frame layout).

use serde::{Deserialize, Serialize};

/// Version of the frame layout described here, the first byte of every frame's payload; bump it
/// when a wire struct or the feature layout changes. A receiver drops a frame of another version
/// ([`DecodeError::UnknownVersion`](super::DecodeError::UnknownVersion)).
pub const WIRE_VERSION: u8 = 4;

/// The older versions the decoder still reads: version 3, the same layout without the pose
/// block after the features (and without the stages from [`Stage::Load`] on), and version 2,
/// version 3 without small objects (feature tag 2).
pub const OLDER_VERSIONS: [u8; 2] = [2, 3];

/// Most features one decoded frame can hold.
pub const MAX_FEATURES: usize = 64;

/// Bound on the encoding of one [`Feature`](pfe_core::Feature): a circle, the largest, takes
/// its tag, 3 u16 varints and 14 f32 (66 bytes at most); the bound counts 15 f32 (70 bytes).
pub const MAX_FEATURE_LEN: usize = 1 + 3 * 3 + 15 * 4;

/// Bound on the encoding of a scan frame's pose block (`Option<PoseBlock>`): its tag, two
/// poses of 12 f32, the status's variant index and 3 f32 (110 bytes at most).
pub const MAX_POSE_LEN: usize = 1 + 2 * 12 * 4 + 1 + 3 * 4;

/// Largest frame on the wire for `features` features (header, features, pose block, CRC, COBS
/// overhead and the terminating zero): size a receive buffer with it.
pub const fn max_frame_len(features: usize) -> usize {
    let raw = 64 + features * MAX_FEATURE_LEN + MAX_POSE_LEN + 4;
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
    /// Firmware time when the scan's telegram was complete, ms (the driver's clock; wraps).
    pub time_ms: u32,
    /// Link counters after this scan.
    pub counters: Counters,
    /// Valid readings in the scan.
    pub valid: u16,
    /// Segments found.
    pub segments: u16,
    /// Features that did not fit in the extractor's buffer (not sent).
    pub dropped: u16,
    /// Number of features that follow.
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
    /// pfe-core's default extraction, step by step (`cargo xtask bench-mcu`, pfe-core's
    /// `probe`): readings to points.
    Load,
    /// The scan's own σ.
    Scatter,
    /// Mark points (the walk).
    Mark,
    /// Interleaved sweeps aligned (estimate, move, mark again).
    Sweeps,
    /// The check step.
    Check,
    /// Segments, their type and fits.
    Segments,
    /// Line ends over the beams beside them.
    Reach,
    /// No unseeable lines, small objects.
    Sift,
    /// Encoding the output frame of the features.
    Encode,
    /// The pfe-core scan built from the codes (`RawScan::to_pfe`: sweeps, grid).
    Scan,
    /// The pose step alone: registration against the local map and its update (version 4).
    Pose,
    /// Telegram bytes to encoded output frame with the pose step, everything (version 4).
    PipelinePose,
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

/// What a frame is: the item after the version byte.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Header {
    /// One scan's features follow.
    Scan(ScanHeader),
    /// A report; nothing follows.
    Report(Report),
}

/// A pose (x, y, θ) with its 3×3 covariance: the pose of a scan's frame in another frame
/// (x forward, y left, θ counter-clockwise; see `docs/FRAME.md`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PoseCov {
    /// mm.
    pub x: f32,
    /// mm.
    pub y: f32,
    /// rad.
    pub theta: f32,
    /// Covariance of (x mm, y mm, θ rad), row by row (mm², mm·rad, rad²), as computed (the
    /// off-diagonal pairs may differ in their last bits).
    pub cov: [[f32; 3]; 3],
}

/// Why a scan was not registered (pfe-pose's `Failure`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PoseFailure {
    /// Fewer than two usable features in a scan.
    TooFewFeatures,
    /// No hypothesis could be formed.
    NoHypothesis,
    /// The best hypothesis was agreed on by too few features.
    NoConsensus,
    /// Two distinct solutions agreed nearly as well.
    Ambiguous,
    /// The motion prior was not usable.
    InvalidPrior,
    /// A reason this version of the frame has no name for.
    Other,
}

/// How a scan's registration went.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PoseStatus {
    /// Registered; the scene determined every direction.
    Ok,
    /// Registered, but the scene cannot tell the pose along `direction` (a corridor).
    Degenerate {
        /// Unit vector (x mm, y mm, θ × 1000 mm): the least determined direction.
        direction: [f32; 3],
    },
    /// Not registered: the relative pose is the prediction and the local map restarts.
    None(PoseFailure),
}

/// The pose block of a version-4 scan frame: the firmware's feature odometry (pfe-pose) for
/// this scan.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PoseBlock {
    /// This scan's pose in the previous scan's frame (identity, zero covariance, for the
    /// first scan).
    pub rel: PoseCov,
    /// This scan's pose in the first scan's frame.
    pub pose: PoseCov,
    /// How the registration went.
    pub status: PoseStatus,
}
