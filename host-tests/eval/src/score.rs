//! Scoring an [`Extraction`] against simulator ground truth (the paper's §4.2 metrics and
//! more). Pure functions; [`Score`] values add up over many scans (sums first, ratios last).
//!
//! Definitions (indices count every beam):
//! - **Counted points**: the beams inside a ground-truth feature (runs of ≥ 4 beams on one
//!   primitive). Beams without return, mixed pixels and runs of 1–3 beams (a box corner seen
//!   edge-on) are "don't care": an extractor may or may not mark them.
//! - **FalseMarkRatio** = (counted points marked that are not true marks + true marks not
//!   marked) / counted points. A mark shifted by one beam therefore counts 2.
//! - **Matching**: a predicted feature matches a truth feature when their index ranges
//!   `[first, last]` overlap with IoU ≥ [`MIN_IOU`]; one-to-one, greedily by best IoU.
//! - **FalseIdenRatio** = (truth circles matched by a line + truth lines matched by a circle
//!   or a small object) / matched features (the paper divides by all features; unmatched ones
//!   have no type to judge). A small object (`Feature::Object`) matched to a truth circle (a
//!   small pillar) is found and of the right kind (it has no radius to score).
//! - **missed** = truth features without a match, **spurious** = predicted features without a
//!   match, both reported as fractions of the number of truth features. A small object that
//!   holds fewer beams of every truth feature than a truth feature has (`truth::MIN_RUN`: e.g.
//!   the two short faces of a box's corner seen between range jumps, 3 + 1 beams) is outside
//!   what the truth lists: not spurious when it matches nothing.
//! - **Parameter errors** of matched features of the right type: line |Δρ| (mm) and |Δα| (rad,
//!   wrapped; (α, ρ) and (α + π, −ρ) are the same line), circle centre distance and |ΔR| (mm),
//!   each with the Cramér–Rao bound of its truth feature.
//!
//! ```
//! use pfe_eval::methods::Extraction;
//! use pfe_eval::score::{score, GroundTruth};
//! use pfe_eval::scene::{Scenario, SceneKind};
//! let sim = Scenario::new(SceneKind::Office, 1).simulate();
//! let gt = GroundTruth::from_sim(&sim);
//! let s = score(&Extraction::default(), &gt);
//! assert_eq!(s.missed, s.truth_features); // nothing found: everything missed
//! ```

use crate::methods::Extraction;
use crate::scene::{Crb, SimScan, TruthFeature, TruthKind};
use pfe_core::Feature;
use std::f64::consts::{PI, TAU};

/// Smallest index-range IoU for a predicted feature to match a truth feature.
pub const MIN_IOU: f64 = 0.5;

/// What the scorer needs to know about one scan.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GroundTruth {
    /// Number of beams.
    pub beams: usize,
    /// Ground-truth features (disjoint index ranges, in scan order).
    pub features: Vec<TruthFeature>,
}

impl GroundTruth {
    /// Ground truth of a simulated scan.
    pub fn from_sim(sim: &SimScan) -> Self {
        Self {
            beams: sim.ranges_mm.len(),
            features: sim.truth.clone(),
        }
    }

    /// Whether beam `i` is a counted point.
    fn counted(&self) -> Vec<bool> {
        let mut c = vec![false; self.beams];
        for f in &self.features {
            for v in c.iter_mut().take(f.last + 1).skip(f.first) {
                *v = true;
            }
        }
        c
    }

    /// True marks: first and last beam of every feature.
    fn marks(&self) -> Vec<bool> {
        let mut m = vec![false; self.beams];
        for f in &self.features {
            for i in [f.first, f.last] {
                if let Some(v) = m.get_mut(i) {
                    *v = true;
                }
            }
        }
        m
    }
}

/// Error of one matched line, with the Cramér–Rao bound of its truth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineError {
    /// |Δρ|, mm.
    pub rho: f64,
    /// |Δα|, rad.
    pub alpha: f64,
    /// CRB σ_ρ, mm.
    pub crb_rho: f64,
    /// CRB σ_α, rad.
    pub crb_alpha: f64,
}

/// Error of one matched circle, with the Cramér–Rao bound of its truth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CircleError {
    /// Centre distance, mm.
    pub center: f64,
    /// |ΔR|, mm.
    pub radius: f64,
    /// CRB RMS centre error, mm.
    pub crb_center: f64,
    /// CRB σ_R, mm.
    pub crb_radius: f64,
}

/// Counts and errors of one or many scans (merge with [`Score::add`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Score {
    /// Scans scored.
    pub scans: usize,
    /// Counted points (beams inside truth features).
    pub points: usize,
    /// Counted points marked that are not true marks.
    pub false_marks: usize,
    /// True marks not marked.
    pub omitted_marks: usize,
    /// Truth features.
    pub truth_features: usize,
    /// Predicted features.
    pub predicted_features: usize,
    /// Matched pairs.
    pub matched: usize,
    /// Truth circles matched by a predicted line.
    pub circles_as_lines: usize,
    /// Truth lines matched by a predicted circle.
    pub lines_as_circles: usize,
    /// Truth features without a match.
    pub missed: usize,
    /// Predicted features without a match.
    pub spurious: usize,
    /// Errors of correctly typed matched lines.
    pub line_errors: Vec<LineError>,
    /// Errors of correctly typed matched circles.
    pub circle_errors: Vec<CircleError>,
}

fn ratio(num: usize, den: usize) -> f64 {
    if den == 0 {
        0.0
    } else {
        num as f64 / den as f64
    }
}

impl Score {
    /// Adds another score (counts and error lists).
    pub fn add(&mut self, other: &Score) {
        self.scans += other.scans;
        self.points += other.points;
        self.false_marks += other.false_marks;
        self.omitted_marks += other.omitted_marks;
        self.truth_features += other.truth_features;
        self.predicted_features += other.predicted_features;
        self.matched += other.matched;
        self.circles_as_lines += other.circles_as_lines;
        self.lines_as_circles += other.lines_as_circles;
        self.missed += other.missed;
        self.spurious += other.spurious;
        self.line_errors.extend_from_slice(&other.line_errors);
        self.circle_errors.extend_from_slice(&other.circle_errors);
    }

    /// (false marks + omitted marks) / counted points.
    pub fn false_mark_ratio(&self) -> f64 {
        ratio(self.false_marks + self.omitted_marks, self.points)
    }

    /// Mistyped matched features / matched features.
    pub fn false_iden_ratio(&self) -> f64 {
        ratio(self.circles_as_lines + self.lines_as_circles, self.matched)
    }

    /// Missed truth features / truth features.
    pub fn missed_ratio(&self) -> f64 {
        ratio(self.missed, self.truth_features)
    }

    /// Spurious predicted features / truth features.
    pub fn spurious_ratio(&self) -> f64 {
        ratio(self.spurious, self.truth_features)
    }
}

/// Intersection over union of two inclusive index ranges.
///
/// ```
/// assert_eq!(pfe_eval::score::iou((0, 9), (5, 14)), 5.0 / 15.0);
/// ```
pub fn iou(a: (usize, usize), b: (usize, usize)) -> f64 {
    let lo = a.0.max(b.0);
    let hi = a.1.min(b.1);
    let inter = if hi >= lo { hi - lo + 1 } else { 0 };
    let la = a.1.saturating_sub(a.0) + 1;
    let lb = b.1.saturating_sub(b.0) + 1;
    ratio(inter, la + lb - inter)
}

/// One-to-one matches `(truth index, predicted index)` with IoU ≥ [`MIN_IOU`], best first.
pub fn match_features(truth: &[TruthFeature], predicted: &[Feature]) -> Vec<(usize, usize)> {
    let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
    for (ti, t) in truth.iter().enumerate() {
        for (pi, p) in predicted.iter().enumerate() {
            let v = iou((t.first, t.last), (p.first(), p.last()));
            if v >= MIN_IOU {
                pairs.push((v, ti, pi));
            }
        }
    }
    pairs.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut used_t = vec![false; truth.len()];
    let mut used_p = vec![false; predicted.len()];
    let mut out = Vec::new();
    for (_, ti, pi) in pairs {
        if !used_t[ti] && !used_p[pi] {
            used_t[ti] = true;
            used_p[pi] = true;
            out.push((ti, pi));
        }
    }
    out.sort_unstable();
    out
}

/// |a − b| wrapped to [0, π].
pub fn angle_diff(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(TAU);
    if d > PI {
        TAU - d
    } else {
        d
    }
}

/// Line error `(|Δρ|, |Δα|)`, comparing (α, ρ) with whichever of (α_t, ρ_t) and
/// (α_t + π, −ρ_t) (the same line) has its normal within π/2 of α.
///
/// ```
/// use pfe_eval::score::line_error;
/// let (dr, da) = line_error(0.1 + std::f64::consts::PI, 2.0, 0.1, 3.0);
/// assert!((dr - 5.0).abs() < 1e-9 && da < 1e-9); // x·n = −2 vs x·n = 3
/// ```
pub fn line_error(alpha: f64, rho: f64, t_alpha: f64, t_rho: f64) -> (f64, f64) {
    let da = angle_diff(alpha, t_alpha);
    if da <= PI / 2.0 {
        ((rho - t_rho).abs(), da)
    } else {
        ((rho + t_rho).abs(), angle_diff(alpha, t_alpha + PI))
    }
}

/// Scores one extraction against ground truth (see the module docs for the definitions).
pub fn score(ex: &Extraction, gt: &GroundTruth) -> Score {
    let counted = gt.counted();
    let true_mark = gt.marks();
    let mut marked = vec![false; gt.beams];
    for &m in &ex.marks {
        if let Some(v) = marked.get_mut(m) {
            *v = true;
        }
    }
    let mut s = Score {
        scans: 1,
        truth_features: gt.features.len(),
        predicted_features: ex.features.len(),
        ..Score::default()
    };
    for i in 0..gt.beams {
        if !counted[i] {
            continue;
        }
        s.points += 1;
        match (marked[i], true_mark[i]) {
            (true, false) => s.false_marks += 1,
            (false, true) => s.omitted_marks += 1,
            _ => {}
        }
    }
    let matches = match_features(&gt.features, &ex.features);
    s.matched = matches.len();
    s.missed = gt.features.len() - matches.len();
    // A small object that holds fewer beams of every truth feature than a truth feature has
    // (`MIN_RUN`) is outside what the truth can score: not spurious (before objects, such
    // runs gave no feature).
    let unscorable = ex
        .features
        .iter()
        .enumerate()
        .filter(|(pi, f)| {
            f.is_object()
                && gt.features.iter().all(|t| {
                    let (lo, hi) = (t.first.max(f.first()), t.last.min(f.last()));
                    hi < lo || hi + 1 - lo < crate::scene::truth::MIN_RUN
                })
                && !matches.iter().any(|m| m.1 == *pi)
        })
        .count();
    s.spurious = ex.features.len() - matches.len() - unscorable;
    for (ti, pi) in matches {
        let (Some(t), Some(p)) = (gt.features.get(ti), ex.features.get(pi)) else {
            continue;
        };
        match (&t.kind, p) {
            (TruthKind::Line { alpha, rho }, Feature::Line(l)) => {
                let (dr, da) = line_error(f64::from(l.alpha), f64::from(l.rho), *alpha, *rho);
                let Crb { position, shape } = t.crb;
                s.line_errors.push(LineError {
                    rho: dr,
                    alpha: da,
                    crb_rho: position,
                    crb_alpha: shape,
                });
            }
            (TruthKind::Circle { center, radius }, Feature::Circle(c)) => {
                let dc =
                    (f64::from(c.center.x) - center[0]).hypot(f64::from(c.center.y) - center[1]);
                s.circle_errors.push(CircleError {
                    center: dc,
                    radius: (f64::from(c.radius) - radius).abs(),
                    crb_center: t.crb.position,
                    crb_radius: t.crb.shape,
                });
            }
            (TruthKind::Line { .. }, Feature::Circle(_)) => s.lines_as_circles += 1,
            (TruthKind::Circle { .. }, Feature::Line(_)) => s.circles_as_lines += 1,
            // A small object on a truth circle (a small pillar) is found: matched, with no
            // circle error (it states no radius). On a truth line it is the wrong kind,
            // counted with the lines taken for circles (FalseIden).
            (TruthKind::Circle { .. }, Feature::Object(_)) => {}
            (TruthKind::Line { .. }, _) => s.lines_as_circles += 1,
            (TruthKind::Circle { .. }, _) => s.circles_as_lines += 1,
        }
    }
    s
}

/// [`score`] against a simulated scan.
pub fn score_sim(ex: &Extraction, sim: &SimScan) -> Score {
    score(ex, &GroundTruth::from_sim(sim))
}

/// The `q`-quantile (0–1, nearest rank) of `values`; NaN when empty.
///
/// ```
/// assert_eq!(pfe_eval::score::quantile(&[3.0, 1.0, 2.0], 0.5), 2.0);
/// ```
pub fn quantile(values: &[f64], q: f64) -> f64 {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let k = ((q.clamp(0.0, 1.0) * (v.len() - 1) as f64).round()) as usize;
    v.get(k).copied().unwrap_or(f64::NAN)
}
