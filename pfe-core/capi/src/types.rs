//! The C types: what `include/pfe.h` declares, laid out as C lays it out (`#[repr(C)]`).
//!
//! Inputs from C (configuration, geometry, scan options) hold only integers and floats, so any
//! bit pattern C writes is a value; the conversions in `crate::convert` reject the ones that
//! mean nothing. Outputs to C (features, statistics) are written by Rust only.

#![forbid(unsafe_code)]

/// Readings the extractor holds (`N` of `Extractor<N, M>`): 1081 is the longest scan of the
/// common 2D scanners (270° at 0.25°); an LMS200 scan has at most 721.
pub const PFE_MAX_READINGS: usize = 1081;

/// Features the extractor keeps per scan (`M` of `Extractor<N, M>`); more are dropped and
/// counted (`PFE_ERR_FEATURE_CAPACITY`, `pfe_stats.dropped`).
pub const PFE_MAX_FEATURES: usize = 64;

/// Bytes of a `pfe_extractor`: enough for the extractor of `PFE_MAX_READINGS` readings and
/// `PFE_MAX_FEATURES` features on 32- and 64-bit targets (checked at compile time;
/// `pfe_extractor_size()` gives the bytes it uses on this target).
pub const PFE_EXTRACTOR_SIZE: usize = 31_552;

/// Alignment of a `pfe_extractor`, bytes.
pub const PFE_EXTRACTOR_ALIGN: usize = 8;

/// What a call did: `PFE_OK` (0) or a negative error.
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum pfe_status {
    /// Success.
    PFE_OK = 0,
    /// A pointer that must not be NULL is NULL.
    PFE_ERR_NULL = -1,
    /// The memory or array given is shorter than needed (for `pfe_marks`: the marks that fit
    /// are written, the count says how many there are).
    PFE_ERR_BUFFER_TOO_SMALL = -2,
    /// A pointer is not aligned for its type (`PFE_EXTRACTOR_ALIGN` for the extractor).
    PFE_ERR_MISALIGNED = -3,
    /// The extractor was not set up with `pfe_extractor_init`.
    PFE_ERR_NOT_INITIALIZED = -4,
    /// An argument is unusable: a unit or quantum that is NaN, infinite or negative, a motion
    /// that is not finite, an option outside its range.
    PFE_ERR_INVALID_ARGUMENT = -5,
    /// The scan has more than `PFE_MAX_READINGS` readings; nothing was extracted.
    PFE_ERR_TOO_MANY_READINGS = -6,
    /// The scan geometry is unusable (non-finite or zero step, r_max ≤ 0).
    PFE_ERR_INVALID_GEOMETRY = -7,
    /// The configuration is unusable (a non-finite or out-of-range parameter, an unknown
    /// kind, or scrutiny on in a library built without it).
    PFE_ERR_INVALID_CONFIG = -8,
    /// More than `PFE_MAX_FEATURES` features: the first ones are readable, `pfe_stats.dropped`
    /// says how many were not stored.
    PFE_ERR_FEATURE_CAPACITY = -9,
    /// A feature index at or past `pfe_feature_count`.
    PFE_ERR_INDEX = -10,
    /// An error this version of the C API does not know (a newer pfe-core).
    PFE_ERR_OTHER = -11,
}

/// Memory for one extractor: declare it `static` (it goes to .bss) and set it up with
/// `pfe_extractor_init`. Its contents are private.
#[repr(C, align(8))]
pub struct pfe_extractor {
    /// Private.
    pub(crate) opaque: [u8; PFE_EXTRACTOR_SIZE],
}

/// Where the beams point and how far the scanner sees.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct pfe_geometry {
    /// Bearing of beam 0, rad (x forward, y left, counter-clockwise positive).
    pub start_angle: f32,
    /// Bearing increment from one beam to the next, rad (may be negative).
    pub angle_step: f32,
    /// Maximum range, mm: readings beyond it are no return.
    pub r_max: f32,
}

/// `pfe_config.threshold`: how the mark-point threshold is computed.
#[repr(u8)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum pfe_threshold {
    /// The paper's (§3.6): `paper_d0`, `paper_lambda`.
    PFE_THRESHOLD_PAPER = 0,
    /// From the range noise (the default mode): `noise`.
    PFE_THRESHOLD_NOISE = 1,
}

/// `pfe_config.typing`: how a segment's type is decided.
#[repr(u8)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum pfe_typing {
    /// The paper's (§3.5): a line when the mean distance to it is ≤ `mean_distance_d_f`.
    PFE_TYPING_MEAN_DISTANCE = 0,
    /// Compare the line and circle fits: `compare_chi2`, `compare_ratio`, `compare_max_radius`.
    PFE_TYPING_COMPARE_FITS = 1,
}

/// `pfe_config.circle_method`: the algebraic circle fit.
#[repr(u8)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum pfe_circle_method {
    /// Kåsa.
    PFE_CIRCLE_KASA = 0,
    /// Taubin.
    PFE_CIRCLE_TAUBIN = 1,
    /// Hyper (Al-Sharadqah & Chernov).
    PFE_CIRCLE_HYPER = 2,
}

/// The default mode's mark-point test (`PFE_THRESHOLD_NOISE`); pfe-core's `NoiseModel`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct pfe_noise_model {
    /// Detection level, in standard deviations of the prediction error.
    pub k: f32,
    /// Boundary localisation level, standard deviations.
    pub k_locate: f32,
    /// Constant allowance, mm.
    pub floor: f32,
    /// Points in the prediction window (≥ 2).
    pub window: u32,
    /// The window grows up to this many points until it spans `min_span · σ_r`.
    pub max_window: u32,
    /// Smallest span of the prediction window, in units of σ_r.
    pub min_span: f32,
    /// Points of the arc continuation test (0: off).
    pub arc_window: u32,
    /// Required drop of the squared residual sum for the arc test, units of σ_r².
    pub arc_chi2: f32,
    /// Largest radius for the arc test, mm.
    pub arc_max_radius: f32,
}

/// Extractor configuration (pfe-core's `Config`). Fill one with `pfe_config_default` or
/// `pfe_config_paper`, then adjust fields. Fields of a kind not selected are ignored.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct pfe_config {
    /// A `pfe_threshold`.
    pub threshold: u8,
    /// A `pfe_typing`.
    pub typing: u8,
    /// A `pfe_circle_method`.
    pub circle_method: u8,
    /// 1: apply the paper's check step (§3.3); 0: not.
    pub check_step: u8,
    /// 1: the default mode's checks for real scans; 0: not.
    pub scrutiny: u8,
    /// 1: apply `correction` to every reading; 0: not.
    pub has_correction: u8,
    /// d_0, mm (`PFE_THRESHOLD_PAPER`).
    pub paper_d0: f32,
    /// λ (`PFE_THRESHOLD_PAPER`).
    pub paper_lambda: f32,
    /// `PFE_THRESHOLD_NOISE`'s parameters.
    pub noise: pfe_noise_model,
    /// d_f, mm (`PFE_TYPING_MEAN_DISTANCE`).
    pub mean_distance_d_f: f32,
    /// Required drop of the residual sum, units of σ_r² (`PFE_TYPING_COMPARE_FITS`).
    pub compare_chi2: f32,
    /// Circle residual sum must be below this × the line's (`PFE_TYPING_COMPARE_FITS`).
    pub compare_ratio: f32,
    /// Largest circle radius, mm (`PFE_TYPING_COMPARE_FITS`).
    pub compare_max_radius: f32,
    /// Minimum points of a segment (≥ 2).
    pub min_points: u32,
    /// Geometric refinement steps after the algebraic circle fit.
    pub circle_refine: u32,
    /// Range noise σ_r, mm.
    pub sigma_r: f32,
    /// Beam-to-beam systematic range error σ_sys, mm.
    pub sigma_sys: f32,
    /// Range correction polynomial coefficients, constant term first, mm (`has_correction`).
    pub correction_coeffs: [f32; 7],
    /// Normalising range of the correction, mm.
    pub correction_scale: f32,
}

/// The scanner's constant-velocity motion during a scan, for de-skewing.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct pfe_motion {
    /// Forward speed, mm/s.
    pub v: f32,
    /// Turn rate, rad/s (counter-clockwise positive).
    pub omega: f32,
    /// Time between consecutive beams of one sweep, s.
    pub beam_dt: f32,
    /// Time between the starts of consecutive interleaved sweeps, s.
    pub sweep_dt: f32,
    /// Interleaved sweeps of the timing (0 or 1: one).
    pub sweeps: u8,
}

/// How a scan was taken, beyond its readings. `pfe_scan_options_default` gives: one sweep, the
/// input's own quantum, no motion (what passing NULL means).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct pfe_scan_options {
    /// Interleaved sweeps the scan is made of (0 or 1: one); beam i is in sweep i mod sweeps.
    pub sweeps: u8,
    /// 1: `motion` is the scanner's motion during the scan; 0: unknown.
    pub has_motion: u8,
    /// Resolution of the readings, mm (≥ 0). 0: the input's own (the unit for raw codes,
    /// unknown for mm).
    pub quantum: f32,
    /// The motion (`has_motion`).
    pub motion: pfe_motion,
}

/// A point in the scanner frame, mm: x forward, y left.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct pfe_point {
    /// Forward, mm.
    pub x: f32,
    /// Left, mm.
    pub y: f32,
}

/// A line `x cos α + y sin α = ρ`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct pfe_line {
    /// Normal angle α, rad, in (−π, π].
    pub alpha: f32,
    /// Distance ρ from the scanner, mm, ≥ 0.
    pub rho: f32,
    /// σ_α², rad².
    pub var_alpha: f32,
    /// σ_ρ², mm².
    pub var_rho: f32,
    /// cov(α, ρ), rad·mm.
    pub cov_alpha_rho: f32,
    /// Projection of the first point on the line.
    pub start: pfe_point,
    /// Projection of the last point on the line.
    pub end: pfe_point,
}

/// A circle or arc.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct pfe_circle {
    /// Centre, mm.
    pub center: pfe_point,
    /// Radius, mm.
    pub radius: f32,
    /// Covariance of (centre x, centre y, radius), mm².
    pub cov: [[f32; 3]; 3],
    /// Bearing from the centre to the first point, rad.
    pub start_angle: f32,
    /// Bearing from the centre to the last point, rad.
    pub end_angle: f32,
}

/// `pfe_feature.kind`.
#[repr(u8)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum pfe_feature_kind {
    /// `shape.line` holds it.
    PFE_FEATURE_LINE = 1,
    /// `shape.circle` holds it.
    PFE_FEATURE_CIRCLE = 2,
    /// `shape.object` holds it.
    PFE_FEATURE_OBJECT = 3,
}

/// A small object (a leg, a post): a short run of returns apart from its neighbours.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct pfe_object {
    /// Centre (the mean of its points), mm.
    pub center: pfe_point,
    /// Covariance of the centre, mm².
    pub cov: [[f32; 2]; 2],
    /// Extent across, mm.
    pub extent: f32,
}

/// A feature's geometry: the member `pfe_feature.kind` names.
#[repr(C)]
#[derive(Clone, Copy)]
pub union pfe_feature_shape {
    /// For `PFE_FEATURE_LINE`.
    pub line: pfe_line,
    /// For `PFE_FEATURE_CIRCLE`.
    pub circle: pfe_circle,
    /// For `PFE_FEATURE_OBJECT`.
    pub object: pfe_object,
}

/// One extracted feature.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct pfe_feature {
    /// Which member of `shape` holds it.
    pub kind: pfe_feature_kind,
    /// Index of the first beam of its segment (counting every beam, valid or not).
    pub first: u16,
    /// Index of the last beam of its segment.
    pub last: u16,
    /// Valid points fitted.
    pub points: u16,
    /// Its geometry.
    pub shape: pfe_feature_shape,
}

/// What the last extraction did (pfe-core's `Stats`; counts saturate at `UINT32_MAX`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct pfe_stats {
    /// Readings in the scan.
    pub readings: u32,
    /// Valid points.
    pub valid: u32,
    /// Segments (of any length).
    pub segments: u32,
    /// Segments shorter than `min_points`, ignored.
    pub short_segments: u32,
    /// Segments whose fit failed (degenerate), ignored.
    pub degenerate: u32,
    /// Features stored.
    pub features: u32,
    /// Features that did not fit (`PFE_ERR_FEATURE_CAPACITY`).
    pub dropped: u32,
    /// Predictions made.
    pub predictions: u32,
    /// Interleaved sweeps moved onto sweep 0.
    pub sweeps_aligned: u32,
    /// The scan's own σ_r in µm when the extraction used it; else 0.
    pub scan_sigma_um: u32,
}
