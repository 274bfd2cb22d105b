//! The LMS200 range model: Gaussian noise (optionally growing with the incidence angle),
//! optional systematic bias, quantisation to the range mode's unit (1 mm or 10 mm), no-return
//! codes and optional mixed pixels, with the ground truth of the measured scan. A moving
//! scanner measures each beam from its pose at the beam's time.

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use std::f64::consts::PI;

use super::{
    bearing, cast_moving, crb, incidence_noise_factor, Scenario, Shape, SimScan, TruthFeature,
    TruthKind, MIN_RUN,
};
use pfe_core::LMS_MAX_VALID_8M;

/// The raw LMS code written for a beam without return (first reserved code in the 8 m / 80 m
/// modes).
pub const NO_RETURN_CODE: u16 = 8183;

/// Amplitude of the optional systematic range bias, mm (LMS200 data sheet, 8 m mode).
pub const BIAS_AMPLITUDE_MM: f64 = 15.0;

/// The optional systematic range error, mm: a smooth curve within ±[`BIAS_AMPLITUDE_MM`]
/// over 0–8 m (a stand-in for the LMS200's calibration curve).
pub fn systematic_bias_mm(r_mm: f64) -> f64 {
    let x = (r_mm / 8000.0).clamp(0.0, 1.5);
    BIAS_AMPLITUDE_MM * (0.7 * (2.0 * PI * 1.3 * x + 0.4).sin() + 0.3 * (2.0 * x - 1.0))
}
/// Measures `shapes` (in the scanner frame of beam 0) as `scenario` says, with ground truth.
/// Each beam is cast from the scanner's pose at its time ([`Scenario::pose`]); its range is
/// measured from there and reported at its nominal bearing.
pub fn render(shapes: &[Shape], scenario: &Scenario, rng: &mut ChaCha8Rng) -> SimScan {
    let geometry = scenario.geometry();
    let r_max = f64::from(geometry.r_max);
    let unit = f64::from(scenario.range_mode.mm_per_unit());
    let hits = cast_moving(shapes, &geometry, |i| scenario.pose(i));
    let n = hits.len();
    let mut true_r: Vec<f64> = hits
        .iter()
        .map(|h| h.map_or(f64::NAN, |h| h.range))
        .collect();
    let mut prim: Vec<Option<usize>> = hits.iter().map(|h| h.map(|h| h.primitive)).collect();
    // Noise factor per beam (1 unless the noise depends on the incidence angle).
    let factor: Vec<f64> = hits
        .iter()
        .map(|h| match h {
            Some(h) if scenario.incidence_noise => incidence_noise_factor(h.incidence),
            _ => 1.0,
        })
        .collect();
    // Ground truth comes from the clean hits; mixed pixels then remove beams from it.
    if scenario.mixed_pixels {
        let mut i = 0;
        while i + 1 < n {
            let (a, b) = (true_r[i], true_r[i + 1]);
            if a.is_finite() && b.is_finite() && (a - b).abs() > 300.0 && rng.gen_bool(0.5) {
                let j = if rng.gen_bool(0.5) { i } else { i + 1 };
                let w: f64 = rng.gen_range(0.2..0.8);
                true_r[j] = w * a + (1.0 - w) * b;
                prim[j] = None;
                i += 2;
            } else {
                i += 1;
            }
        }
    }
    let sigma = f64::from(scenario.sigma_r).max(0.0);
    let normal = Normal::new(0.0, sigma.max(1e-12)).ok();
    let mut ranges_mm = vec![f32::NAN; n];
    let mut raw = vec![NO_RETURN_CODE; n];
    for i in 0..n {
        let t = true_r[i];
        if !t.is_finite() {
            prim[i] = None;
            continue;
        }
        let mut r = t;
        if scenario.bias {
            r += systematic_bias_mm(t);
        }
        if sigma > 0.0 {
            if let Some(nd) = &normal {
                let f = factor.get(i).copied().unwrap_or(1.0);
                r += if f == 1.0 {
                    nd.sample(rng)
                } else {
                    f * nd.sample(rng)
                };
            }
        }
        let q = (r / unit).round();
        if q >= 1.0 && q * unit <= r_max && q <= f64::from(LMS_MAX_VALID_8M) {
            ranges_mm[i] = (q * unit) as f32;
            raw[i] = q as u16;
        } else {
            prim[i] = None;
        }
    }
    // Truth: maximal runs of ≥ MIN_RUN beams on one primitive. The CRB takes the RMS noise of
    // the run's beams, with the quantisation's.
    let quantum = unit * unit / 12.0;
    let mut truth = Vec::new();
    let mut i = 0;
    while i < n {
        let Some(id) = prim[i] else {
            i += 1;
            continue;
        };
        let mut j = i;
        while j + 1 < n && prim[j + 1] == Some(id) {
            j += 1;
        }
        if j + 1 - i >= MIN_RUN {
            if let Some(shape) = shapes.get(id) {
                let kind = TruthKind::of(shape);
                let bearings: Vec<f64> = (i..=j).map(|k| bearing(&geometry, k)).collect();
                let f2 = factor[i..=j].iter().map(|f| f * f).sum::<f64>() / bearings.len() as f64;
                let sigma_eff = (sigma * sigma * f2 + quantum).sqrt();
                truth.push(TruthFeature {
                    primitive: id,
                    first: i,
                    last: j,
                    kind,
                    crb: crb(&kind, &bearings, sigma_eff).unwrap_or_default(),
                });
            }
        }
        i = j + 1;
    }
    let mut true_marks: Vec<usize> = truth.iter().flat_map(|f| [f.first, f.last]).collect();
    true_marks.dedup();
    SimScan {
        geometry,
        ranges_mm,
        raw,
        beam_primitive: prim,
        truth,
        true_marks,
        shapes: shapes.to_vec(),
        true_ranges_mm: true_r,
        sigma_r: sigma,
        mm_per_unit: scenario.range_mode.mm_per_unit(),
        sweeps: scenario.sweeps(),
        odometry: scenario.odometry_given.then(|| scenario.motion()),
    }
}
