//! The centre NIS of small objects that stay where they are.
//!
//! The plain object NIS ([`super::compare`]) matches each object of scan k to the nearest of
//! k+1 within [`GATE_CENTER_MM`]; on the shared logs that also pairs what its covariance cannot
//! speak for: people walking beside the robot (fhw: a crowd follows it) and the posts of a
//! railing spaced closer than the gate (csail, where the logged scans are a metre apart). Here
//! a match counts only when it is
//!
//! - **unambiguous**: the object has one candidate in k+1 within the gate, and that candidate
//!   one in k;
//! - **static**: an object lies within [`STATIC_MM`] of the same place in the world in another
//!   scan, at most [`STATIC_SPAN`] scans away, taken from at least [`STATIC_MOVE_MM`] or
//!   [`STATIC_TURN_RAD`] away from both scans of the pair (so a person keeping pace with the
//!   robot is not re-found there).
//!
//! The other scan's sighting decides which matches count, not their error: it is within
//! 150 mm, several times the objects' stated σ, so the selection hardly narrows the NIS.
//!
//! The NIS through the corrected poses charges their error to the objects. Two columns remove
//! it: [`Statics::nis_reference`] adds the reference's own scatter between two scans
//! ([`REFERENCE_SIGMA_MM`] per axis, [`REFERENCE_SIGMA_RAD`], as the pose benchmark does) to
//! the pair's covariance; [`Statics::nis_refit`] first corrects the pair's motion from its lines.
//!
//! ```
//! use pfe_eval::realdata::compare::Seen;
//! use pfe_eval::realdata::statics::Statics;
//! use pfe_eval::realdata::CircleObs;
//! let post = |x: f64| CircleObs { center: [x, 0.0], cov: [[100.0, 0.0], [0.0, 100.0]], radius: 20.0 };
//! let mut s = Statics::default();
//! // The scanner drives along x in 0.3 m steps past a post at x = 3 m, y = 0 in the world.
//! for k in 0..6 {
//!     let x = 300.0 * k as f64;
//!     let seen = Seen { pose: [x, 0.0, 0.0], objects: vec![post(3000.0 - x)], ..Seen::default() };
//!     s.scan(&seen);
//! }
//! assert_eq!(s.nis().len(), 5); // every pair, the post seen from ≥ 0.5 m away in another scan
//! assert!(s.nis().iter().all(|&v| v < 1e-9));
//! ```

use super::compare::{matched_lines, refit_centre, Seen, GATE_CENTER_MM};
use super::frame::{add, nis, FrameChange, Pose, REFERENCE_SIGMA_MM, REFERENCE_SIGMA_RAD};
use super::refit::{correction, correction_covariance};
use super::CircleObs;

/// Farthest an object's other sighting lies from the same place, mm.
pub const STATIC_MM: f64 = 150.0;
/// Most scans between a pair and the other sighting.
pub const STATIC_SPAN: usize = 50;
/// Least distance of the other sighting's scanner from both scans of the pair, mm…
pub const STATIC_MOVE_MM: f64 = 500.0;
/// …or least turn, rad.
pub const STATIC_TURN_RAD: f64 = 0.5;

/// The scans of one log, in order, and the unambiguous object matches of their pairs.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Statics {
    /// Scanner pose and its objects' centres in the world, per scan.
    scans: Vec<(Pose, Vec<[f64; 2]>)>,
    /// The unambiguous matches.
    matches: Vec<Match>,
    /// The scan before, in its own frame.
    last: Option<Seen>,
}

impl Statics {
    /// Adds the next scan of the log (its pair with the scan before, if any).
    pub fn scan(&mut self, s: &Seen) {
        if let Some(a) = self.last.take() {
            self.pair(&a, s);
        }
        let world = s
            .objects
            .iter()
            .map(|o| to_world(s.pose, o.center))
            .collect();
        self.scans.push((s.pose, world));
        self.last = Some(s.clone());
    }

    /// Breaks the chain of pairs (a scan without a pose).
    pub fn gap(&mut self) {
        self.last = None;
    }

    /// The unambiguous matches of `a` (the last scan added) in `b`.
    fn pair(&mut self, a: &Seen, b: &Seen) {
        let Some(k) = self.scans.len().checked_sub(1) else {
            return;
        };
        let change = FrameChange::between(a.pose, b.pose);
        let lines: Vec<_> = matched_lines(a, b, &change)
            .into_iter()
            .map(|m| m.1)
            .collect();
        let delta = correction(&lines).zip(correction_covariance(&lines));
        let moved: Vec<CircleObs> = a.objects.iter().map(|o| change.circle(o)).collect();
        for (m, o) in moved.iter().zip(&a.objects) {
            let Some(j) = only_candidate(m.center, &b.objects) else {
                continue;
            };
            let Some(c) = b.objects.get(j) else { continue };
            if only_candidate(c.center, &moved).is_none() {
                continue;
            }
            let d = [m.center[0] - c.center[0], m.center[1] - c.center[1]];
            let both = add(&m.cov, &c.cov);
            if let Some(v) = nis(d, &both) {
                let refit = delta.as_ref().and_then(|delta| {
                    let (r, s) = refit_centre(m, c, delta);
                    nis(r, &s)
                });
                let reference = nis(d, &add(&both, &reference_scatter(&change, m.center)));
                self.matches.push(Match {
                    k,
                    at: to_world(a.pose, o.center),
                    nis: v,
                    reference,
                    refit,
                });
            }
        }
    }

    /// The NIS of the matches whose object is static (module docs).
    pub fn nis(&self) -> Vec<f64> {
        self.statics().map(|m| m.nis).collect()
    }

    /// [`Self::nis`] with the reference's own scatter between the two scans added.
    pub fn nis_reference(&self) -> Vec<f64> {
        self.statics().filter_map(|m| m.reference).collect()
    }

    /// [`Self::nis`] after each pair's pose refit from its lines (pairs with a refit only).
    pub fn nis_refit(&self) -> Vec<f64> {
        self.statics().filter_map(|m| m.refit).collect()
    }

    /// The matches whose object is static.
    fn statics(&self) -> impl Iterator<Item = &Match> {
        self.matches
            .iter()
            .filter(|m| self.seen_elsewhere(m.k, m.at))
    }

    /// True when a scan other than `k` and `k + 1`, within [`STATIC_SPAN`] and taken from
    /// elsewhere, has an object within [`STATIC_MM`] of `at`.
    fn seen_elsewhere(&self, k: usize, at: [f64; 2]) -> bool {
        let (Some(pa), Some(pb)) = (self.scans.get(k), self.scans.get(k + 1)) else {
            return false;
        };
        let lo = k.saturating_sub(STATIC_SPAN);
        let hi = (k + 1 + STATIC_SPAN).min(self.scans.len().saturating_sub(1));
        (lo..=hi)
            .filter(|&m| m != k && m != k + 1)
            .filter_map(|m| self.scans.get(m))
            .filter(|(p, _)| elsewhere(*p, pa.0) && elsewhere(*p, pb.0))
            .any(|(_, objects)| {
                objects
                    .iter()
                    .any(|o| (o[0] - at[0]).hypot(o[1] - at[1]) <= STATIC_MM)
            })
    }
}

/// One unambiguous match of a pair.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Match {
    /// The pair's first scan.
    k: usize,
    /// The object's centre in the world, mm.
    at: [f64; 2],
    /// Its NIS through the reference poses.
    nis: f64,
    /// The same with the reference's scatter added.
    reference: Option<f64>,
    /// After the pair's pose refit from its lines (when there is one).
    refit: Option<f64>,
}

/// The covariance, in frame k+1, that the reference's scatter between the two scans gives a
/// point `p` of frame k moved there by `change`: σ² per axis, and the turn's σ² along the
/// perpendicular of the point's offset from scanner k.
fn reference_scatter(change: &FrameChange, p: [f64; 2]) -> [[f64; 2]; 2] {
    let r = [p[0] - change.shift[0], p[1] - change.shift[1]];
    let (t, s) = (
        REFERENCE_SIGMA_MM * REFERENCE_SIGMA_MM,
        REFERENCE_SIGMA_RAD * REFERENCE_SIGMA_RAD,
    );
    [
        [t + s * r[1] * r[1], -s * r[0] * r[1]],
        [-s * r[0] * r[1], t + s * r[0] * r[0]],
    ]
}

/// The index of the only one of `objects` within [`GATE_CENTER_MM`] of `p`.
fn only_candidate(p: [f64; 2], objects: &[CircleObs]) -> Option<usize> {
    let mut near = objects
        .iter()
        .enumerate()
        .filter(|(_, o)| (o.center[0] - p[0]).hypot(o.center[1] - p[1]) < GATE_CENTER_MM)
        .map(|(i, _)| i);
    let first = near.next()?;
    near.next().is_none().then_some(first)
}

/// True when the scanner at `p` is at least [`STATIC_MOVE_MM`] or [`STATIC_TURN_RAD`] away
/// from `q`.
fn elsewhere(p: Pose, q: Pose) -> bool {
    let turn = super::frame::wrap(p[2] - q[2]).abs();
    (p[0] - q[0]).hypot(p[1] - q[1]) >= STATIC_MOVE_MM || turn >= STATIC_TURN_RAD
}

/// A point of the frame of the scanner at `pose` in the world.
fn to_world(pose: Pose, p: [f64; 2]) -> [f64; 2] {
    let (s, c) = pose[2].sin_cos();
    [c * p[0] - s * p[1] + pose[0], s * p[0] + c * p[1] + pose[1]]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A point 1 m ahead of scanner k, which moved 1 m back and turned: the reference's turn
    /// error moves it across its offset from scanner k, by 1 m × σ_θ.
    #[test]
    fn reference_scatter_grows_across_the_offset_from_the_first_scanner() {
        let change = FrameChange::between([0.0, 0.0, 0.0], [-1000.0, 0.0, 0.0]);
        let p = change.point([1000.0, 0.0]);
        assert!((p[0] - 2000.0).abs() < 1e-9);
        let c = reference_scatter(&change, p);
        let t = REFERENCE_SIGMA_MM * REFERENCE_SIGMA_MM;
        let across = 1000.0 * REFERENCE_SIGMA_RAD;
        assert!((c[0][0] - t).abs() < 1e-9, "{c:?}");
        assert!((c[1][1] - (t + across * across)).abs() < 1e-6, "{c:?}");
        assert!(c[0][1].abs() < 1e-9 && c[1][0].abs() < 1e-9, "{c:?}");
    }
}
