//! Between the C types and pfe-core's, and the extractor state behind a `pfe_extractor`: all
//! safe code. Values from C that mean nothing are errors here, before pfe-core sees them.

#![forbid(unsafe_code)]

use pfe_core::{
    BeamTiming, CircleMethod, Config, ExtractError, Extractor, Feature, Motion, RangeCorrection,
    Scan, ScanGeometry, Stats, Threshold, Typing,
};

use crate::types::pfe_status::{self, *};
use crate::types::*;

/// The extractor of the C API's capacities.
pub(crate) type CExtractor = Extractor<PFE_MAX_READINGS, PFE_MAX_FEATURES>;

/// What `pfe_extractor_init` writes in the caller's memory: zero bytes (an extractor as
/// `Extractor::new()` makes it, no output) and the mark.
#[repr(C)]
pub(crate) struct State {
    /// [`MAGIC`] once initialised (the caller's memory is zero or garbage before).
    pub(crate) magic: u32,
    /// 1 when the extractor's output is that of the last `pfe_extract_*` call (0 after a call
    /// refused before pfe-core ran, so that no stale features are read as its result).
    pub(crate) current: u32,
    /// The extractor.
    pub(crate) ex: CExtractor,
}

/// Marks a set-up extractor ("pfe1").
pub(crate) const MAGIC: u32 = u32::from_le_bytes(*b"pfe1");

const _: () = assert!(core::mem::size_of::<State>() <= PFE_EXTRACTOR_SIZE);
const _: () = assert!(core::mem::align_of::<State>() <= PFE_EXTRACTOR_ALIGN);
const _: () = assert!(core::mem::align_of::<pfe_extractor>() == PFE_EXTRACTOR_ALIGN);
// The constant is the 64-bit size (the largest): no more than a cache line wasted there.
const _: () = assert!(
    core::mem::size_of::<usize>() != 8 || core::mem::size_of::<State>() + 64 > PFE_EXTRACTOR_SIZE
);

impl State {
    /// Extracts `scan` with `config` (already converted).
    pub(crate) fn extract(&mut self, scan: &Scan<'_>, config: &Config) -> pfe_status {
        let r = self.ex.extract(scan, config);
        self.current = 1;
        match r {
            Ok(_) => PFE_OK,
            Err(e) => status_of(e),
        }
    }

    /// The features of the last extraction (none after a refused call).
    pub(crate) fn features(&self) -> &[Feature] {
        match self.current {
            0 => &[],
            _ => self.ex.features(),
        }
    }

    /// The statistics of the last extraction (zero after a refused call).
    pub(crate) fn stats(&self) -> pfe_stats {
        match self.current {
            0 => pfe_stats::default(),
            _ => stats_to_c(&self.ex.stats()),
        }
    }

    /// Writes the mark points of the last extraction into `out` (as many as fit); returns how
    /// many there are.
    pub(crate) fn marks(&self, out: &mut [u16]) -> usize {
        if self.current == 0 {
            return 0;
        }
        let mut n = 0;
        for i in self.ex.marks() {
            if let Some(slot) = out.get_mut(n) {
                // Indices are below PFE_MAX_READINGS < 2^16.
                *slot = u16::try_from(i).unwrap_or(u16::MAX);
            }
            n += 1;
        }
        n
    }
}

/// The C status of an extraction error.
pub(crate) fn status_of(e: ExtractError) -> pfe_status {
    match e {
        ExtractError::TooManyReadings { .. } => PFE_ERR_TOO_MANY_READINGS,
        ExtractError::InvalidGeometry => PFE_ERR_INVALID_GEOMETRY,
        ExtractError::InvalidConfig => PFE_ERR_INVALID_CONFIG,
        ExtractError::FeatureCapacity { .. } => PFE_ERR_FEATURE_CAPACITY,
        _ => PFE_ERR_OTHER,
    }
}

/// 0 → false, 1 → true, anything else → `None`.
fn flag(v: u8) -> Option<bool> {
    match v {
        0 => Some(false),
        1 => Some(true),
        _ => None,
    }
}

/// A C count as `usize` (lossless on the 32- and 64-bit targets; saturating elsewhere).
fn count(v: u32) -> usize {
    usize::try_from(v).unwrap_or(usize::MAX)
}

/// A `usize` as a C count, saturating.
fn count_c(v: usize) -> u32 {
    u32::try_from(v).unwrap_or(u32::MAX)
}

/// The C form of `c`. The fields of the kinds `c` does not select hold the named
/// configurations' values (so that a C program switching kind starts from usable numbers).
pub(crate) fn config_to_c(c: &Config) -> pfe_config {
    let correction = c.correction.unwrap_or(RangeCorrection::IDENTITY);
    let mut out = pfe_config {
        threshold: 0,
        typing: 0,
        circle_method: match c.circle_method {
            CircleMethod::Kasa => pfe_circle_method::PFE_CIRCLE_KASA,
            CircleMethod::Taubin => pfe_circle_method::PFE_CIRCLE_TAUBIN,
            CircleMethod::Hyper => pfe_circle_method::PFE_CIRCLE_HYPER,
        } as u8,
        check_step: u8::from(c.check_step),
        scrutiny: u8::from(c.scrutiny),
        has_correction: u8::from(c.correction.is_some()),
        paper_d0: 0.0,
        paper_lambda: 0.0,
        noise: pfe_noise_model {
            k: 0.0,
            k_locate: 0.0,
            floor: 0.0,
            window: 0,
            max_window: 0,
            min_span: 0.0,
            arc_window: 0,
            arc_chi2: 0.0,
            arc_max_radius: 0.0,
        },
        mean_distance_d_f: 0.0,
        compare_chi2: 0.0,
        compare_ratio: 0.0,
        compare_max_radius: 0.0,
        min_points: count_c(c.min_points),
        circle_refine: count_c(c.circle_refine),
        sigma_r: c.sigma_r,
        sigma_sys: c.sigma_sys,
        correction_coeffs: correction.coeffs,
        correction_scale: correction.scale,
    };
    // `c` last: its kinds are the ones selected.
    for source in [Config::paper(), Config::default_config(), *c] {
        set_kinds(&mut out, &source);
    }
    out
}

/// Selects `c`'s threshold and typing kinds in `out`, with their parameters.
fn set_kinds(out: &mut pfe_config, c: &Config) {
    match c.threshold {
        Threshold::Paper { d0, lambda } => {
            out.threshold = pfe_threshold::PFE_THRESHOLD_PAPER as u8;
            out.paper_d0 = d0;
            out.paper_lambda = lambda;
        }
        Threshold::Noise(m) => {
            out.threshold = pfe_threshold::PFE_THRESHOLD_NOISE as u8;
            out.noise = pfe_noise_model {
                k: m.k,
                k_locate: m.k_locate,
                floor: m.floor,
                window: count_c(m.window),
                max_window: count_c(m.max_window),
                min_span: m.min_span,
                arc_window: count_c(m.arc_window),
                arc_chi2: m.arc_chi2,
                arc_max_radius: m.arc_max_radius,
            };
        }
    }
    match c.typing {
        Typing::MeanDistance { d_f } => {
            out.typing = pfe_typing::PFE_TYPING_MEAN_DISTANCE as u8;
            out.mean_distance_d_f = d_f;
        }
        Typing::CompareFits {
            chi2,
            ratio,
            max_radius,
        } => {
            out.typing = pfe_typing::PFE_TYPING_COMPARE_FITS as u8;
            out.compare_chi2 = chi2;
            out.compare_ratio = ratio;
            out.compare_max_radius = max_radius;
        }
    }
}

/// pfe-core's configuration of `c`, when it is one (`PFE_ERR_INVALID_CONFIG` otherwise).
pub(crate) fn config_from_c(c: &pfe_config) -> Result<Config, pfe_status> {
    const BAD: pfe_status = PFE_ERR_INVALID_CONFIG;
    let m = &c.noise;
    let threshold = match c.threshold {
        t if t == pfe_threshold::PFE_THRESHOLD_PAPER as u8 => Threshold::Paper {
            d0: c.paper_d0,
            lambda: c.paper_lambda,
        },
        t if t == pfe_threshold::PFE_THRESHOLD_NOISE as u8 => {
            // Field by field over pfe's own (pfe-core's types may become `#[non_exhaustive]`).
            let Threshold::Noise(mut n) = Config::default_config().threshold else {
                return Err(PFE_ERR_OTHER);
            };
            n.k = m.k;
            n.k_locate = m.k_locate;
            n.floor = m.floor;
            n.window = count(m.window);
            n.max_window = count(m.max_window);
            n.min_span = m.min_span;
            n.arc_window = count(m.arc_window);
            n.arc_chi2 = m.arc_chi2;
            n.arc_max_radius = m.arc_max_radius;
            Threshold::Noise(n)
        }
        _ => return Err(BAD),
    };
    let typing = match c.typing {
        t if t == pfe_typing::PFE_TYPING_MEAN_DISTANCE as u8 => Typing::MeanDistance {
            d_f: c.mean_distance_d_f,
        },
        t if t == pfe_typing::PFE_TYPING_COMPARE_FITS as u8 => Typing::CompareFits {
            chi2: c.compare_chi2,
            ratio: c.compare_ratio,
            max_radius: c.compare_max_radius,
        },
        _ => return Err(BAD),
    };
    let circle_method = match c.circle_method {
        v if v == pfe_circle_method::PFE_CIRCLE_KASA as u8 => CircleMethod::Kasa,
        v if v == pfe_circle_method::PFE_CIRCLE_TAUBIN as u8 => CircleMethod::Taubin,
        v if v == pfe_circle_method::PFE_CIRCLE_HYPER as u8 => CircleMethod::Hyper,
        _ => return Err(BAD),
    };
    let correction = match flag(c.has_correction).ok_or(BAD)? {
        false => None,
        true => {
            let ok = c.correction_coeffs.iter().all(|v| v.is_finite())
                && c.correction_scale.is_finite()
                && c.correction_scale > 0.0;
            if !ok {
                return Err(BAD);
            }
            let mut r = RangeCorrection::IDENTITY;
            r.coeffs = c.correction_coeffs;
            r.scale = c.correction_scale;
            Some(r)
        }
    };
    // `Config` grows (it is `#[non_exhaustive]`): start from a value and set every field.
    let mut out = Config::default_config();
    out.threshold = threshold;
    out.check_step = flag(c.check_step).ok_or(BAD)?;
    out.typing = typing;
    out.min_points = count(c.min_points);
    out.circle_method = circle_method;
    out.circle_refine = count(c.circle_refine);
    out.sigma_r = c.sigma_r;
    out.sigma_sys = c.sigma_sys;
    out.correction = correction;
    out.scrutiny = flag(c.scrutiny).ok_or(BAD)?;
    match out.is_valid() {
        true => Ok(out),
        false => Err(BAD),
    }
}

/// pfe-core's geometry of `g` (pfe-core checks it).
pub(crate) fn geometry_from_c(g: &pfe_geometry) -> ScanGeometry {
    let mut out = ScanGeometry::LMS200_180_050;
    out.start_angle = g.start_angle;
    out.angle_step = g.angle_step;
    out.r_max = g.r_max;
    out
}

/// The C form of `g`.
pub(crate) fn geometry_to_c(g: &ScanGeometry) -> pfe_geometry {
    pfe_geometry {
        start_angle: g.start_angle,
        angle_step: g.angle_step,
        r_max: g.r_max,
    }
}

/// The options `pfe_scan_options_default` gives.
pub(crate) const DEFAULT_OPTIONS: pfe_scan_options = pfe_scan_options {
    sweeps: 1,
    has_motion: 0,
    quantum: 0.0,
    motion: pfe_motion {
        v: 0.0,
        omega: 0.0,
        beam_dt: 0.0,
        sweep_dt: 0.0,
        sweeps: 1,
    },
};

/// `scan` with the options `o` applied (`PFE_ERR_INVALID_ARGUMENT` for a quantum or motion
/// that is not finite, or a flag that is not 0 or 1).
pub(crate) fn with_options<'a>(
    mut scan: Scan<'a>,
    o: &pfe_scan_options,
) -> Result<Scan<'a>, pfe_status> {
    const BAD: pfe_status = PFE_ERR_INVALID_ARGUMENT;
    if !(o.quantum.is_finite() && o.quantum >= 0.0) {
        return Err(BAD);
    }
    scan = scan.with_sweeps(o.sweeps);
    if o.quantum > 0.0 {
        scan = scan.with_quantum(o.quantum);
    }
    if flag(o.has_motion).ok_or(BAD)? {
        let m = &o.motion;
        let mut motion = Motion::uniform(m.v, m.omega, m.beam_dt);
        motion.timing = BeamTiming::interleaved(m.sweeps, m.sweep_dt, m.beam_dt);
        if !motion.is_valid() {
            return Err(BAD);
        }
        scan = scan.with_motion(motion);
    }
    Ok(scan)
}

/// A raw-code unit that can be used: finite and positive.
pub(crate) fn unit_ok(unit_mm: f32) -> bool {
    unit_mm.is_finite() && unit_mm > 0.0
}

/// The C form of `f` (`None` for a kind the C API does not know).
pub(crate) fn feature_to_c(f: &Feature) -> Option<pfe_feature> {
    Some(match f {
        Feature::Line(l) => pfe_feature {
            kind: pfe_feature_kind::PFE_FEATURE_LINE,
            first: l.first,
            last: l.last,
            points: l.points,
            shape: pfe_feature_shape {
                line: pfe_line {
                    alpha: l.alpha,
                    rho: l.rho,
                    var_alpha: l.var_alpha,
                    var_rho: l.var_rho,
                    cov_alpha_rho: l.cov_alpha_rho,
                    start: pfe_point {
                        x: l.start.x,
                        y: l.start.y,
                    },
                    end: pfe_point {
                        x: l.end.x,
                        y: l.end.y,
                    },
                },
            },
        },
        Feature::Circle(c) => pfe_feature {
            kind: pfe_feature_kind::PFE_FEATURE_CIRCLE,
            first: c.first,
            last: c.last,
            points: c.points,
            shape: pfe_feature_shape {
                circle: pfe_circle {
                    center: pfe_point {
                        x: c.center.x,
                        y: c.center.y,
                    },
                    radius: c.radius,
                    cov: c.cov,
                    start_angle: c.start_angle,
                    end_angle: c.end_angle,
                },
            },
        },
        Feature::Object(o) => pfe_feature {
            kind: pfe_feature_kind::PFE_FEATURE_OBJECT,
            first: o.first,
            last: o.last,
            points: o.points,
            shape: pfe_feature_shape {
                object: pfe_object {
                    center: pfe_point {
                        x: o.center.x,
                        y: o.center.y,
                    },
                    cov: o.cov,
                    extent: o.extent,
                },
            },
        },
        _ => return None,
    })
}

/// The C form of `s`.
pub(crate) fn stats_to_c(s: &Stats) -> pfe_stats {
    pfe_stats {
        readings: count_c(s.readings),
        valid: count_c(s.valid),
        segments: count_c(s.segments),
        short_segments: count_c(s.short_segments),
        degenerate: count_c(s.degenerate),
        features: count_c(s.features),
        dropped: count_c(s.dropped),
        predictions: count_c(s.predictions),
        sweeps_aligned: count_c(s.sweeps_aligned),
        scan_sigma_um: s.scan_sigma_um,
    }
}

/// The static text of a status code.
pub(crate) fn status_text(status: i32) -> &'static core::ffi::CStr {
    match status {
        0 => c"ok",
        -1 => c"a required pointer is NULL",
        -2 => c"buffer too small",
        -3 => c"pointer misaligned",
        -4 => c"extractor not initialised (pfe_extractor_init)",
        -5 => c"invalid argument (NaN, infinite or negative unit, quantum or motion; bad flag)",
        -6 => c"scan has more readings than PFE_MAX_READINGS",
        -7 => c"invalid scan geometry",
        -8 => c"invalid configuration",
        -9 => c"feature buffer full: features dropped (see pfe_stats.dropped)",
        -10 => c"feature index out of range",
        -11 => c"unknown extraction error",
        _ => c"not a pfe status",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_named_configurations_survive_the_round_trip() {
        for c in [
            Config::paper(),
            Config::default_config(),
            Config::paper().with_sigma_r(2.0).with_sigma_sys(15.0),
        ] {
            assert_eq!(config_from_c(&config_to_c(&c)), Ok(c));
        }
    }

    #[test]
    fn switching_kind_in_c_starts_from_the_named_configurations_values() {
        let mut c = config_to_c(&Config::paper());
        c.threshold = pfe_threshold::PFE_THRESHOLD_NOISE as u8;
        c.typing = pfe_typing::PFE_TYPING_COMPARE_FITS as u8;
        let d = Config::default_config();
        let got = config_from_c(&c);
        assert_eq!(
            got.map(|g| (g.threshold, g.typing)),
            Ok((d.threshold, d.typing))
        );
    }

    #[test]
    fn unknown_kinds_flags_and_nan_parameters_are_refused() {
        let good = config_to_c(&Config::default_config());
        let cases: [fn(&mut pfe_config); 9] = [
            |c| c.threshold = 2,
            |c| c.typing = 7,
            |c| c.circle_method = 3,
            |c| c.check_step = 2,
            |c| c.scrutiny = 255,
            |c| c.sigma_r = f32::NAN,
            |c| c.noise.k = f32::INFINITY,
            |c| c.min_points = 1,
            |c| {
                c.has_correction = 1;
                c.correction_coeffs[3] = f32::NAN;
            },
        ];
        for (i, edit) in cases.iter().enumerate() {
            let mut c = good;
            edit(&mut c);
            assert_eq!(config_from_c(&c), Err(PFE_ERR_INVALID_CONFIG), "case {i}");
        }
    }

    #[test]
    fn options_reject_nan_quantum_and_motion_and_set_the_scan() {
        let r = [1000.0_f32; 3];
        let scan = Scan::from_mm(ScanGeometry::LMS200_180_050, &r);
        let mut o = DEFAULT_OPTIONS;
        o.sweeps = 2;
        o.quantum = 10.0;
        let s = with_options(scan, &o).map_err(|_| ()).unwrap();
        assert_eq!((s.sweeps, s.quantum, s.motion), (2, 10.0, None));
        o.quantum = f32::NAN;
        assert_eq!(with_options(scan, &o).err(), Some(PFE_ERR_INVALID_ARGUMENT));
        o.quantum = 0.0;
        o.has_motion = 1;
        o.motion.v = f32::NAN;
        assert_eq!(with_options(scan, &o).err(), Some(PFE_ERR_INVALID_ARGUMENT));
        o.motion.v = 100.0;
        o.motion.beam_dt = 1e-4;
        let s = with_options(scan, &o).map_err(|_| ()).unwrap();
        assert_eq!(s.motion.map(|m| m.v), Some(100.0));
    }
}
