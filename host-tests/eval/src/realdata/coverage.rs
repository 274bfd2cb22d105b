//! How much of a scan the features cover, and how much of its smooth surfaces they leave as
//! bare mark points.
//!
//! - A beam is **valid** when it has a return (finite, > 0, ≤ r_max).
//! - A beam is **in a feature** when it lies in the beam span `first..=last` of a feature a
//!   consumer can use ([`usable`]): any circle or small object, and a line the scanner can have
//!   seen (at most 85° incidence at its midpoint, at least 10 mm long) whose direction and
//!   place are known well enough to match it again (σ_α ≤ [`MAX_SIGMA_ALPHA`], and the σ of
//!   its distance at its midpoint ≤ [`MAX_SIGMA_MID_MM`]).
//! - A **smooth run** is a maximal run of at least [`MIN_SMOOTH_RUN`] consecutive valid beams
//!   whose neighbours differ in range by less than [`SMOOTH_STEP_MM`]. Its beams that lie in
//!   no feature are **bare**: a surface the scanner saw continuously but the method described
//!   only by mark points (or not at all).

use std::ops::RangeInclusive;

use pfe_core::{Feature, ScanGeometry};

/// Shortest smooth run, beams.
pub const MIN_SMOOTH_RUN: usize = 10;
/// Largest range step between neighbours inside a smooth run, mm.
pub const SMOOTH_STEP_MM: f32 = 300.0;

/// Largest σ_α of a usable line, rad: beyond it (±17° at 3σ) a line's direction no longer
/// tells one wall from the next, and a localiser's gate (the benchmark's own: 0.1 rad) cannot
/// hold it.
pub const MAX_SIGMA_ALPHA: f32 = 0.1;
/// Largest σ of a usable line's distance at its midpoint, mm: beyond it (±0.3 m at 3σ) a line
/// no longer tells itself from a wall a door's depth behind it (the benchmark's gate: 0.3 m).
/// Not σ_ρ itself: ρ is measured at the foot of the normal from the scanner, which can lie
/// metres from the segment, so σ_ρ grows with that distance times σ_α for a well placed wall.
pub const MAX_SIGMA_MID_MM: f32 = 100.0;

/// True when a consumer can use `f`: every circle and small object, and a line the scanner can
/// have seen as a surface whose σ_α and σ at its midpoint are within [`MAX_SIGMA_ALPHA`] and
/// [`MAX_SIGMA_MID_MM`].
///
/// ```
/// use pfe_core::{Feature, LineFeature, Point};
/// use pfe_eval::realdata::coverage::usable;
/// let wall = |var_alpha| Feature::Line(LineFeature::new(
///     0, 9, 10, 0.0, 1000.0, var_alpha, 4.0, 0.0,
///     Point::new(1000.0, -100.0), Point::new(1000.0, 100.0),
/// ));
/// assert!(usable(&wall(1e-4)));
/// assert!(!usable(&wall(0.02))); // σ_α 0.14 rad
/// ```
pub fn usable(f: &Feature) -> bool {
    match f {
        Feature::Line(l) => {
            let (s, e) = ([l.start.x, l.start.y], [l.end.x, l.end.y]);
            let len = (e[0] - s[0]).hypot(e[1] - s[1]);
            super::visible::incidence_deg(l.alpha, s, e) <= super::visible::MAX_INCIDENCE_DEG
                && len >= super::visible::MIN_LINE_MM
                && l.var_alpha <= MAX_SIGMA_ALPHA * MAX_SIGMA_ALPHA
                && var_at_midpoint(l) <= MAX_SIGMA_MID_MM * MAX_SIGMA_MID_MM
        }
        _ => true,
    }
}

/// The variance of `l`'s distance at its segment's midpoint, mm²: with t the midpoint's
/// coordinate along the line, δd = t·δα − δρ.
fn var_at_midpoint(l: &pfe_core::LineFeature) -> f32 {
    let (mx, my) = (0.5 * (l.start.x + l.end.x), 0.5 * (l.start.y + l.end.y));
    let t = -l.alpha.sin() * mx + l.alpha.cos() * my;
    t * t * l.var_alpha - 2.0 * t * l.cov_alpha_rho + l.var_rho
}

/// Beam counts of one scan (or a sum of scans).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Coverage {
    /// Valid beams.
    pub valid: usize,
    /// Valid beams in a feature.
    pub in_features: usize,
    /// Beams of smooth runs in no feature.
    pub bare: usize,
    /// Of those, the beams of bare stretches that reach an end of their smooth run (the beams
    /// between a feature's end and a jump or a no-return, such as mixed pixels at an edge).
    pub bare_at_ends: usize,
}

impl Coverage {
    /// Counts one scan's beams (the features a consumer cannot use, [`usable`], hold none).
    pub fn of(geometry: &ScanGeometry, ranges_mm: &[f32], features: &[Feature]) -> Self {
        let n = ranges_mm.len();
        let mut covered = vec![false; n];
        for f in features.iter().filter(|f| usable(f)) {
            for c in covered.iter_mut().take(f.last() + 1).skip(f.first()) {
                *c = true;
            }
        }
        let valid: Vec<bool> = ranges_mm
            .iter()
            .map(|&r| r.is_finite() && r > 0.0 && r <= geometry.r_max)
            .collect();
        let mut out = Coverage {
            valid: valid.iter().filter(|v| **v).count(),
            in_features: valid
                .iter()
                .zip(&covered)
                .filter(|(v, c)| **v && **c)
                .count(),
            bare: 0,
            bare_at_ends: 0,
        };
        for run in smooth_runs(geometry, ranges_mm) {
            out.bare += run.clone().filter(|&k| !covered[k]).count();
            // The bare stretches that start or end the run.
            let head = run.clone().take_while(|&k| !covered[k]).count();
            let tail = run.clone().rev().take_while(|&k| !covered[k]).count();
            out.bare_at_ends += (head + tail).min(run.count());
        }
        out
    }

    /// Adds `other`'s counts.
    pub fn add(&mut self, other: &Coverage) {
        self.valid += other.valid;
        self.in_features += other.in_features;
        self.bare += other.bare;
        self.bare_at_ends += other.bare_at_ends;
    }
}

/// The smooth runs of one scan, as ranges of beam indices: maximal runs of at least
/// [`MIN_SMOOTH_RUN`] consecutive valid beams (finite, > 0, ≤ r_max) whose neighbours differ in
/// range by less than [`SMOOTH_STEP_MM`].
///
/// ```
/// use pfe_eval::realdata::coverage::smooth_runs;
/// use pfe_core::ScanGeometry;
/// let mut r = vec![2000.0f32; 40];
/// r[20] = 5000.0; // a jump on both sides: 0..=19 and 21..=39 remain
/// r[35] = f32::NAN; // 21..=34 and a run of 4 beams, too short
/// assert_eq!(smooth_runs(&ScanGeometry::LMS200_180_050, &r), vec![0..=19, 21..=34]);
/// ```
pub fn smooth_runs(geometry: &ScanGeometry, ranges_mm: &[f32]) -> Vec<RangeInclusive<usize>> {
    let valid = |r: f32| r.is_finite() && r > 0.0 && r <= geometry.r_max;
    let mut runs = Vec::new();
    let mut i = 0;
    while let Some(&r) = ranges_mm.get(i) {
        if !valid(r) {
            i += 1;
            continue;
        }
        let mut j = i;
        while let (Some(&a), Some(&b)) = (ranges_mm.get(j), ranges_mm.get(j + 1)) {
            if !(valid(b) && (b - a).abs() < SMOOTH_STEP_MM) {
                break;
            }
            j += 1;
        }
        if j + 1 - i >= MIN_SMOOTH_RUN {
            runs.push(i..=j);
        }
        i = j + 1;
    }
    runs
}

#[cfg(test)]
mod tests {
    use super::*;
    use pfe_core::{LineFeature, Point};

    fn line(first: u16, last: u16) -> Feature {
        Feature::Line(LineFeature::new(
            first,
            last,
            last - first + 1,
            0.0,
            1000.0,
            1e-6,
            1.0,
            0.0,
            Point::new(1000.0, -100.0),
            Point::new(1000.0, 100.0),
        ))
    }

    #[test]
    fn counts_valid_covered_and_bare_beams() {
        let g = ScanGeometry::LMS200_180_050;
        // Beams 0..30 smooth, 30 no return, 31..36 smooth but short, 36 a jump, 37..60 smooth.
        let mut r = vec![2000.0f32; 60];
        r[30] = f32::NAN;
        r[36] = 5000.0;
        let cov = Coverage::of(&g, &r, &[line(5, 24), line(40, 59)]);
        assert_eq!(cov.valid, 59);
        assert_eq!(cov.in_features, 40);
        // Run 0..=29: beams 0..5 and 25..30 bare (10); 31..=35 too short; 36 alone (jump on
        // both sides); 37..=59: beams 37, 38, 39 bare.
        assert_eq!(cov.bare, 13);
        // All of them reach an end of their run.
        assert_eq!(cov.bare_at_ends, 13);
    }

    #[test]
    fn bare_stretches_between_features_are_not_at_the_ends() {
        let g = ScanGeometry::LMS200_180_050;
        let r = vec![2000.0f32; 40];
        // Bare: 0..=2 (at the run's start), 13..=15 (between two lines), 30..=39 (at its end).
        let cov = Coverage::of(&g, &r, &[line(3, 12), line(16, 29)]);
        assert_eq!((cov.bare, cov.bare_at_ends), (16, 13));
        // A run with no feature is bare from end to end, counted once.
        let cov = Coverage::of(&g, &r, &[]);
        assert_eq!((cov.bare, cov.bare_at_ends), (40, 40));
        let mut sum = Coverage::default();
        sum.add(&cov);
        sum.add(&Coverage::of(&g, &r, &[line(3, 12), line(16, 29)]));
        assert_eq!((sum.valid, sum.bare, sum.bare_at_ends), (80, 56, 53));
    }
}
