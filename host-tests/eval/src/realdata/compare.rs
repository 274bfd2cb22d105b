//! One pair of consecutive scans: scan k's features moved into scan k+1's frame
//! ([`super::frame`]) and matched there.
//!
//! - **Lines** of at least [`MIN_LINE_POINTS`] points are matched to the nearest line of k+1
//!   (by `(Δα/0.1)² + (Δρ/300 mm)²`) within the gate |Δα| < [`GATE_ALPHA`],
//!   |Δρ| < [`GATE_RHO_MM`] whose extent overlaps theirs along its direction.
//! - **Circles** are matched to the k+1 circle whose centre is nearest, within
//!   [`GATE_CENTER_MM`]; **small objects** to the nearest small object of k+1 alike.

use pfe_core::Feature;

use super::frame::{nis, Cov2, FrameChange, LineObs, Pose};
use rand::SeedableRng;

use super::refit::{
    consistent_refit_nis, correction, correction_covariance, refit_nis, Innovation,
};
use super::CircleObs;

/// Shortest line counted, points.
pub const MIN_LINE_POINTS: usize = 10;
/// Line gate on the normal angle, rad.
pub const GATE_ALPHA: f64 = 0.1;
/// Line gate on the distance, mm.
pub const GATE_RHO_MM: f64 = 300.0;
/// Draws per refitted pair of the consistent reference of the line NIS after the refit.
pub const CONSISTENT_DRAWS: usize = 8;
/// Circle gate on the centre, mm.
pub const GATE_CENTER_MM: f64 = 300.0;

/// One scan's features as the comparison needs them, with the scanner's pose.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Seen {
    /// Pose of the scanner, mm and rad.
    pub pose: Pose,
    /// Lines.
    pub lines: Vec<LineObs>,
    /// Circles.
    pub circles: Vec<CircleObs>,
    /// Small objects (their centre and its covariance; `radius`: half their extent).
    pub objects: Vec<CircleObs>,
}

impl Seen {
    /// The features of one scan taken at `pose`.
    pub fn new(pose: Pose, features: &[Feature]) -> Self {
        let mut s = Seen {
            pose,
            ..Seen::default()
        };
        for f in features {
            match f {
                Feature::Line(l) => s.lines.push(LineObs {
                    alpha: f64::from(l.alpha),
                    rho: f64::from(l.rho),
                    cov: [
                        [f64::from(l.var_alpha), f64::from(l.cov_alpha_rho)],
                        [f64::from(l.cov_alpha_rho), f64::from(l.var_rho)],
                    ],
                    start: [f64::from(l.start.x), f64::from(l.start.y)],
                    end: [f64::from(l.end.x), f64::from(l.end.y)],
                    points: usize::from(l.points),
                    beams: [usize::from(l.first), usize::from(l.last)],
                }),
                Feature::Circle(c) => s.circles.push(CircleObs {
                    center: [f64::from(c.center.x), f64::from(c.center.y)],
                    cov: [
                        [f64::from(c.cov[0][0]), f64::from(c.cov[0][1])],
                        [f64::from(c.cov[1][0]), f64::from(c.cov[1][1])],
                    ],
                    radius: f64::from(c.radius),
                }),
                Feature::Object(o) => s.objects.push(CircleObs {
                    center: [f64::from(o.center.x), f64::from(o.center.y)],
                    cov: [
                        [f64::from(o.cov[0][0]), f64::from(o.cov[0][1])],
                        [f64::from(o.cov[1][0]), f64::from(o.cov[1][1])],
                    ],
                    radius: 0.5 * f64::from(o.extent),
                }),
                _ => {}
            }
        }
        s
    }

    /// The same with every covariance multiplied by `k` (tests of the NIS's sensitivity).
    pub fn scaled(&self, k: f64) -> Self {
        let mut s = self.clone();
        let lines = s.lines.iter_mut().map(|l| &mut l.cov);
        let points = s.circles.iter_mut().chain(s.objects.iter_mut());
        for cov in lines.chain(points.map(|c| &mut c.cov)) {
            for v in cov.iter_mut().flatten() {
                *v *= k;
            }
        }
        s
    }
}

/// What the pairs of one method's scans gave, summed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PairTally {
    /// Pairs compared.
    pub pairs: usize,
    /// Points of scan k's lines of ≥ [`MIN_LINE_POINTS`] points.
    pub line_points: usize,
    /// Points of those that re-appear.
    pub line_points_matched: usize,
    /// |Δρ| of matched lines, mm.
    pub d_rho: Vec<f64>,
    /// |Δα| of matched lines, rad.
    pub d_alpha: Vec<f64>,
    /// NIS of matched lines.
    pub nis: Vec<f64>,
    /// NIS of matched lines after the pair's pose refit (pairs with a refit only).
    pub nis_refit: Vec<f64>,
    /// What `nis_refit` would be with consistent covariances ([`consistent_refit_nis`]:
    /// [`CONSISTENT_DRAWS`] draws of each refitted pair's lines).
    pub nis_refit_consistent: Vec<f64>,
    /// Pairs with a pose refit.
    pub refits: usize,
    /// Circles of scan k.
    pub circles: usize,
    /// Of those, re-appearing.
    pub circles_matched: usize,
    /// Centre NIS of matched circles.
    pub circle_nis: Vec<f64>,
    /// Centre NIS of matched circles after the pair's pose refit from its lines (pairs with
    /// a refit only).
    pub circle_nis_refit: Vec<f64>,
    /// Small objects of scan k.
    pub objects: usize,
    /// Of those, re-appearing (an object of k+1 within [`GATE_CENTER_MM`]).
    pub objects_matched: usize,
    /// Centre NIS of matched objects.
    pub object_nis: Vec<f64>,
    /// Centre NIS of matched objects after the pair's pose refit from its lines.
    pub object_nis_refit: Vec<f64>,
}

/// What the centres of one kind of point feature gave over a pair: seen in k, matched in
/// k+1, their NIS and their NIS after the lines' refit.
struct Centres<'a> {
    seen: &'a mut usize,
    matched: &'a mut usize,
    nis: &'a mut Vec<f64>,
    nis_refit: &'a mut Vec<f64>,
}

impl Centres<'_> {
    /// Moves each of `a` by `change`, matches it to the nearest of `b` within
    /// [`GATE_CENTER_MM`] and adds the result.
    fn add(
        self,
        a: &[CircleObs],
        b: &[CircleObs],
        change: &FrameChange,
        delta: Option<&Correction>,
    ) {
        for c in a {
            *self.seen += 1;
            let moved = change.circle(c);
            let best = b
                .iter()
                .map(|o| {
                    let d = [moved.center[0] - o.center[0], moved.center[1] - o.center[1]];
                    (d[0].hypot(d[1]), d, o)
                })
                .filter(|(dist, _, _)| *dist < GATE_CENTER_MM)
                .min_by(|x, y| x.0.total_cmp(&y.0));
            if let Some((_, d, o)) = best {
                *self.matched += 1;
                let s = super::frame::add(&moved.cov, &o.cov);
                self.nis.extend(nis(d, &s));
                if let Some(delta) = delta {
                    let (r, s) = refit_centre(&moved, o, delta);
                    self.nis_refit.extend(nis(r, &s));
                }
            }
        }
    }
}

/// Scan `a`'s lines of ≥ [`MIN_LINE_POINTS`] points that re-appear in scan `b` (`change`:
/// the frame change from `a` to `b`), each with its difference from the nearest line of `b`
/// within the gate whose extent overlaps it.
pub fn matched_lines<'a>(
    a: &'a Seen,
    b: &Seen,
    change: &FrameChange,
) -> Vec<(&'a LineObs, Innovation)> {
    a.lines
        .iter()
        .filter(|l| l.points >= MIN_LINE_POINTS)
        .filter_map(|l| rematch(l, b, change).map(|inn| (l, inn)))
        .collect()
}

/// The difference of scan k's line `l`, moved by `change`, from the nearest line of `b` within
/// the gate whose extent overlaps it; `None` when it does not re-appear.
pub fn rematch(l: &LineObs, b: &Seen, change: &FrameChange) -> Option<Innovation> {
    let moved = change.line(l);
    b.lines
        .iter()
        .filter_map(|c| {
            let (d, s, alpha) = moved.difference(c);
            let gated = d[0].abs() < GATE_ALPHA && d[1].abs() < GATE_RHO_MM;
            let (m0, m1) = moved.extent_along(c);
            let (c0, c1) = c.extent_along(c);
            let overlap = m0 <= c1 && c0 <= m1;
            let cost = (d[0] / GATE_ALPHA).powi(2) + (d[1] / GATE_RHO_MM).powi(2);
            (gated && overlap).then_some((cost, Innovation { d, s, alpha }))
        })
        .min_by(|x, y| x.0.total_cmp(&y.0))
        .map(|(_, inn)| inn)
}

impl PairTally {
    /// Moves `a`'s features into `b`'s frame, matches them and adds the result.
    pub fn add(&mut self, a: &Seen, b: &Seen) {
        self.pairs += 1;
        let change = FrameChange::between(a.pose, b.pose);
        let long = a.lines.iter().filter(|l| l.points >= MIN_LINE_POINTS);
        self.line_points += long.map(|l| l.points).sum::<usize>();
        let matched = matched_lines(a, b, &change);
        let mut innovations = Vec::with_capacity(matched.len());
        for (l, inn) in matched {
            self.line_points_matched += l.points;
            self.d_rho.push(inn.d[1].abs());
            self.d_alpha.push(inn.d[0].abs());
            self.nis.extend(nis(inn.d, &inn.s));
            innovations.push(inn);
        }
        if let Some(v) = refit_nis(&innovations) {
            self.refits += 1;
            self.nis_refit.extend(v);
            // Seeded by the pair's number: the same figures on every run.
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(self.pairs as u64);
            if let Some(v) = consistent_refit_nis(&innovations, CONSISTENT_DRAWS, &mut rng) {
                self.nis_refit_consistent.extend(v);
            }
        }
        // The lines' pose correction, applied to the moved circle centres too, with its own
        // uncertainty.
        let delta = correction(&innovations).zip(correction_covariance(&innovations));
        let delta = delta.as_ref();
        Centres {
            seen: &mut self.circles,
            matched: &mut self.circles_matched,
            nis: &mut self.circle_nis,
            nis_refit: &mut self.circle_nis_refit,
        }
        .add(&a.circles, &b.circles, &change, delta);
        Centres {
            seen: &mut self.objects,
            matched: &mut self.objects_matched,
            nis: &mut self.object_nis,
            nis_refit: &mut self.object_nis_refit,
        }
        .add(&a.objects, &b.objects, &change, delta);
    }
}

/// A pair's pose correction from its lines ([`correction`]) and its covariance.
pub type Correction = ([f64; 3], [[f64; 3]; 3]);

/// The difference of scan k's circle centre, moved into k+1's frame (`moved`), from `o` after
/// the pair's pose correction `delta`, and its covariance: both centres' plus the
/// correction's own.
pub fn refit_centre(moved: &CircleObs, o: &CircleObs, delta: &Correction) -> ([f64; 2], Cov2) {
    let ([dx, dy, dth], p) = delta;
    // The extra motion δ of frame k+1 moves a point p to R(δθ) p + (δx, δy); δ's covariance
    // P enters through J = ∂/∂δ = [[1, 0, −y], [0, 1, x]].
    let (sin, cos) = dth.sin_cos();
    let [mx, my] = moved.center;
    let r = [
        cos * mx - sin * my + dx - o.center[0],
        sin * mx + cos * my + dy - o.center[1],
    ];
    let j = [[1.0, 0.0, -my], [0.0, 1.0, mx]];
    let mut s = super::frame::add(&moved.cov, &o.cov);
    for (a, ja) in j.iter().enumerate() {
        for (b, jb) in j.iter().enumerate() {
            s[a][b] += (0..3)
                .map(|k| (0..3).map(|l| ja[k] * p[k][l] * jb[l]).sum::<f64>())
                .sum::<f64>();
        }
    }
    (r, s)
}
