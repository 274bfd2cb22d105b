//! Registration of two scans' features: hypotheses from the features themselves, consensus,
//! weighted least squares, covariance and an honest status.
//!
//! 1. **Hypotheses** (no first guess needed): a pair of non-parallel lines of the previous scan
//!    and a pair of the current one with the same angle between them fix the rotation (from
//!    the normals' angles α) and the translation (from the two ρ); a pair of points at the same
//!    distance fixes both too, and so does a line with a point. Only when none of these exist
//!    (a corridor), single lines give the rotation and the translation across them, with none
//!    along them. With a prior, the prior's pose is a hypothesis too and every hypothesis must
//!    lie within its covariance (χ²₃ < [`Config::prior_gate`]) and within the motion bounds
//!    [`Config::max_translation`] and [`Config::max_rotation`] of its pose (without a prior:
//!    of no motion). Pairs of lines are
//!    matched through the angle between them (the current scan's pairs sorted by it, each
//!    previous pair looked up within its gate). The hypotheses formed are **voted** into
//!    clusters of nearby poses (the right pose comes from many pairs of features); the
//!    [`Config::scored`] best-supported clusters are scored at their mean, besides the prior's
//!    pose (or no motion).
//! 2. **Consensus**: each hypothesis is scored by the features of the current scan that then
//!    agree with one of the previous scan's (Mahalanobis distance with both covariances plus a
//!    slack for the hypothesis's own error, truncated-quadratic score, weighted by how much
//!    the two segments overlap): features seen in one scan only, and moving objects, simply do
//!    not agree.
//!    Association looks only at the previous lines whose angle lies within the gate (an
//!    index of them by α).
//! 3. **Refinement**: the best few hypotheses (at least half the best one's score) are
//!    refined by Gauss–Newton over the gated
//!    matches (re-associated each step while the slack shrinks to zero), weighted by the
//!    features' covariances; the prior enters as one more measurement. A hypothesis whose
//!    refinement lands on the pose another one was refined to (within 30 mm and 0.01 rad) is
//!    that solution again and stops there. The best refined one
//!    wins, after a visibility check: a pose under which one scan's segments
//!    would hide what the other scan saw, or the robot would have gone through a wall, loses
//!    score.
//! 4. **Covariance and status**: `(Jᵀ W J)⁻¹` (scaled up by the residuals' χ² per degree of
//!    freedom when above 1). The eigen-analysis of the scene's information (x, y in mm, θ in
//!    units of 1 m) finds directions the scene cannot tell (standard deviation above
//!    [`Config::degenerate_sigma`]), and with [`Config::confirm`] also a direction that one
//!    match alone determines (an association no other feature confirms), unless both of its
//!    segments are at least [`Config::trusted_length`] long: the status is then
//!    [`Status::Degenerate`], the estimate does not move along them, and their variance is the
//!    prior's or [`UNOBSERVABLE_VARIANCE`]. In a corridor (both scans nothing but parallel
//!    lines), two line matches suffice for a [`Status::Degenerate`] registration (the heading
//!    and the offset across it), fewer than [`Config::min_matches`].

mod config;
mod hypotheses;
mod refine;
/// Compiled into the firmware too (not yet called there): its call of [`Scratch::new`] once
/// left `register_sets_verified` building the scratch in temporaries and copying it in
/// (9 336 B frame; fixed in [`Scratch::new`]).
mod search;
mod visibility;

use crate::geom::{finite3, inverse_spd3, wrap, Cov3, Pose};
use crate::obs::Observation;
use crate::set::{Set, MAX_OBS};
pub use config::Config;
use hypotheses::{hypothesise, Top};
use refine::{converge, finish, refine, Refined, Scratch, Work};
pub use search::{Progress, Resumable};
use visibility::visibility_penalty;

/// Variance given to a direction the scene cannot tell when there is no prior: 10⁸ mm² (a
/// standard deviation of 10 km) for translation; a rotation's part is in units of 1 m
/// (10² rad²). Small enough that f32's rounding of it along a direction tilted from the axes
/// (a few mm² an entry) leaves the measured variances across it standing; invert such a
/// covariance in f64, or across the direction only.
pub const UNOBSERVABLE_VARIANCE: f32 = 1e8;

/// Length that puts rotation in the units of translation for the eigen-analysis, mm per rad.
pub const ROTATION_SCALE: f32 = 1000.0;

/// Hypotheses refined (the best by consensus).
const REFINE: usize = 12;
/// Hypotheses scoring below this fraction of the best one's are not refined.
const REFINE_RATIO: f32 = 0.5;
/// Refined hypotheses kept for the points' verification.
pub(crate) const VERIFIED: usize = REFINE;
/// A refined hypothesis this far from the winner (mm, rad) is a distinct solution, which the
/// points' verification may prefer.
const DISTINCT_MM: f32 = 300.0;
const DISTINCT_RAD: f32 = 0.087;
/// Gauss–Newton steps at most.
const ITERATIONS: usize = 10;

/// Why there is no registration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Failure {
    /// Fewer than two usable features in a scan.
    TooFewFeatures,
    /// No hypothesis could be formed (or none within the bounds or the prior).
    NoHypothesis,
    /// The best hypothesis is agreed on by fewer than [`Config::min_matches`] features.
    NoConsensus,
    /// Two distinct solutions agree nearly as well (see [`Config::ambiguity`]).
    Ambiguous,
    /// The prior is not finite or its covariance not positive definite.
    InvalidPrior,
}

/// How a registration went.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Status {
    /// Every direction of the pose is determined by the scene.
    Ok,
    /// The scene cannot tell the pose along `direction` (a unit vector in (x mm, y mm,
    /// θ·[`ROTATION_SCALE`])): a corridor, say. The covariance along it is the prior's, or
    /// [`UNOBSERVABLE_VARIANCE`] without a prior; the other directions are measured.
    Degenerate {
        /// The least determined direction.
        direction: [f32; 3],
    },
    /// No registration: `rel` is the prior's pose (identity without one) and `cov` the
    /// prior's ([`UNOBSERVABLE_VARIANCE`] on the diagonal without one).
    None(Failure),
}

/// The result of [`register`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Registration {
    /// The pose of the current scan in the previous scan's frame.
    pub rel: Pose,
    /// Its covariance, (x mm, y mm, θ rad).
    pub cov: Cov3,
    /// Whether the scene determined it.
    pub status: Status,
    /// Features of the current scan matched (lines, points).
    pub matches: (u16, u16),
    /// Hypotheses formed within the bounds or the prior's gate (voted into clusters before
    /// scoring, see [`Config::scored`]).
    pub hypotheses: u32,
    /// Valid features left out for want of room (see [`crate::MAX_OBS`]).
    pub dropped: u16,
    /// Invalid features ignored (NaN, negative ρ, covariance not positive definite).
    pub invalid: u16,
    /// χ² of the matched features' residuals.
    pub chi2: f32,
}

impl Registration {
    /// True for [`Status::Ok`] and [`Status::Degenerate`].
    pub fn is_registered(&self) -> bool {
        !matches!(self.status, Status::None(_))
    }
}

/// Registers `curr` against `prev` with the default [`Config`]: the pose of the current scan
/// in the previous scan's frame, its covariance and status. `prior`: a guess of that pose with
/// its covariance (wheel odometry, a gyro), or `None`.
///
/// ```
/// use pfe_pose::{register, LineObs, Observation, Pose, Status};
/// // A room's three walls and a pillar, seen before and after a move of (300 mm, 100 mm, 0.2 rad).
/// let truth = Pose::new(300.0, 100.0, 0.2);
/// let walls = [(0.0f32, 3000.0f32), (1.5708, 2000.0), (3.1416, 1500.0), (-1.5708, 2500.0)];
/// let cov = [[1e-6, 0.0], [0.0, 25.0]];
/// let inv = truth.inverse();
/// let prev: Vec<_> = walls.iter().map(|&(a, r)| Observation::Line(LineObs::new(a, r, cov))).collect();
/// let curr: Vec<_> = walls.iter().map(|&(a, r)| {
///     let (a, r) = inv.transform_line(a, r);
///     Observation::Line(LineObs::new(a, r, cov))
/// }).collect();
/// let reg = register(&prev, &curr, None);
/// assert_eq!(reg.status, Status::Ok);
/// assert!((reg.rel.x - 300.0).abs() < 5.0 && (reg.rel.theta - 0.2).abs() < 1e-3);
/// ```
pub fn register(
    prev: &[Observation],
    curr: &[Observation],
    prior: Option<(Pose, Cov3)>,
) -> Registration {
    register_with(prev, curr, prior, &Config::default())
}

/// [`register`] with a configuration.
///
/// ```
/// use pfe_pose::{register_with, Config, Failure, Status};
/// let reg = register_with(&[], &[], None, &Config::default());
/// assert_eq!(reg.status, Status::None(Failure::TooFewFeatures));
/// ```
pub fn register_with(
    prev: &[Observation],
    curr: &[Observation],
    prior: Option<(Pose, Cov3)>,
    cfg: &Config,
) -> Registration {
    let p = Set::from_obs(prev.iter().copied(), cfg);
    let c = Set::from_obs(curr.iter().copied(), cfg);
    let mut assoc = Assoc::new();
    let mut r = register_sets(&p, &c, prior, cfg, &mut assoc, true);
    r.dropped = p.dropped.saturating_add(c.dropped);
    r.invalid = p.invalid.saturating_add(c.invalid);
    r
}

/// Which feature of the previous set each current one matched (`NONE` when none).
#[derive(Clone, Debug)]
pub(crate) struct Assoc {
    pub lines: [u8; MAX_OBS],
    pub pts: [u8; MAX_OBS],
}

pub(crate) const NONE: u8 = u8::MAX;

impl Assoc {
    pub const fn new() -> Self {
        Self {
            lines: [NONE; MAX_OBS],
            pts: [NONE; MAX_OBS],
        }
    }
}

/// A validated prior: pose, information matrix, covariance.
#[derive(Clone, Copy, Debug)]
struct Prior {
    pose: Pose,
    info: Cov3,
    cov: Cov3,
    /// Information of the prior widened by the hypotheses' slack, for gating.
    gate_info: Cov3,
}

fn check_prior(prior: Option<(Pose, Cov3)>, cfg: &Config) -> Result<Option<Prior>, Failure> {
    let Some((pose, cov)) = prior else {
        return Ok(None);
    };
    if !pose.is_finite() || !finite3(&cov) {
        return Err(Failure::InvalidPrior);
    }
    let cov = crate::geom::symmetrise3(&cov);
    let info = inverse_spd3(&cov).ok_or(Failure::InvalidPrior)?;
    let mut wide = cov;
    let (st, sa) = (cfg.slack[1] * 2.0, cfg.slack[0] * 2.0);
    wide[0][0] += st * st;
    wide[1][1] += st * st;
    wide[2][2] += sa * sa;
    let gate_info = inverse_spd3(&wide).ok_or(Failure::InvalidPrior)?;
    Ok(Some(Prior {
        pose: Pose::new(pose.x, pose.y, pose.theta),
        info,
        cov,
        gate_info,
    }))
}

/// The registration on prepared sets; `assoc` receives the final matches. Without `search`
/// (and with a prior) the prior's pose is the only hypothesis: the refinement of a good guess.
/// Not inlined: its frame (a [`Work`] of a few KiB) is shared by every caller's calls.
#[inline(never)]
pub(crate) fn register_sets(
    prev: &Set,
    curr: &Set,
    prior: Option<(Pose, Cov3)>,
    cfg: &Config,
    assoc: &mut Assoc,
    search: bool,
) -> Registration {
    register_sets_verified::<0>(prev, curr, prior, cfg, assoc, search, None).0
}

/// No registration: the prior's pose and covariance (no motion and
/// [`UNOBSERVABLE_VARIANCE`] without one).
fn fallback(failure: Failure, prior: Option<&Prior>, hypotheses: u32) -> Registration {
    let (rel, cov) = match prior {
        Some(p) => (p.pose, p.cov),
        None => (
            Pose::IDENTITY,
            [
                [UNOBSERVABLE_VARIANCE, 0.0, 0.0],
                [0.0, UNOBSERVABLE_VARIANCE, 0.0],
                [
                    0.0,
                    0.0,
                    UNOBSERVABLE_VARIANCE / (ROTATION_SCALE * ROTATION_SCALE),
                ],
            ],
        ),
    };
    Registration {
        rel,
        cov,
        status: Status::None(failure),
        matches: (0, 0),
        hypotheses,
        dropped: 0,
        invalid: 0,
        chi2: 0.0,
    }
}

/// [`register_sets`] with `verify`: a score of a pose by the scans' own points (higher is
/// better, see [`crate::points::agreement`]). Among the refined hypotheses, one whose points
/// agree better than the features' winner's by [`Config::verify_margin`] wins instead (the
/// features alone cannot tell aliased poses apart: periodic pillars, short lines far away);
/// an ambiguity the points resolve is no failure.
/// `K`: refined hypotheses kept for the verification ([`VERIFIED`] with `verify`; 0 without,
/// so that the features-only registration's frame does not grow). With the registration, the
/// features' winner when the points' verification replaced it.
#[inline(never)]
pub(crate) fn register_sets_verified<const K: usize>(
    prev: &Set,
    curr: &Set,
    prior: Option<(Pose, Cov3)>,
    cfg: &Config,
    assoc: &mut Assoc,
    search: bool,
    verify: Option<&dyn Fn(&Pose) -> f32>,
) -> (Registration, Option<Pose>) {
    let prior = check_prior(prior, cfg);
    let prior = match prior {
        Ok(p) => p,
        Err(f) => return (fallback(f, None, 0), None),
    };
    if prev.len() < 2 || curr.len() < 2 {
        return (fallback(Failure::TooFewFeatures, prior.as_ref(), 0), None);
    }
    let mut top = Top::new();
    let mut scratch = Scratch::new();
    let mut w = Work::new(prev, curr, cfg, prior.as_ref(), &mut scratch);
    let hypotheses = hypothesise(&mut w, prev, curr, prior.as_ref(), cfg, &mut top, search);
    if top.n == 0 {
        return (
            fallback(Failure::NoHypothesis, prior.as_ref(), hypotheses),
            None,
        );
    }
    // Refine the best few; keep the best refined and the best distinct runner-up. When the
    // runner-up cannot make the result ambiguous (a best keeps at least 1/1.01 of the score
    // of the one it replaced, over at most REFINE of them: below 1.2 of the final best), the
    // covariance and the visibility check are needed for the winner only.
    let lazy = cfg.ambiguity >= 1.2;
    let corridor = is_corridor(prev, cfg) && is_corridor(curr, cfg);
    let mut best: Option<Refined> = None;
    let mut second_score = 0.0f32;
    // Best first, so that hopeless ones are found early (see below).
    let mut order = *top.all();
    let ranked = order.get_mut(..top.n).unwrap_or(&mut []);
    ranked.sort_unstable_by(|a, b| b.score.total_cmp(&a.score));
    let first = ranked.first().map_or(0.0, |h| h.score);
    // The refined candidates, for the points' verification.
    let mut cands = [Pose::IDENTITY; K];
    let mut nc = 0usize;
    for i in 0..ranked.len() {
        let Some((done, rest)) = ranked.split_at_mut_checked(i) else {
            break;
        };
        let Some(h) = rest.first_mut() else { break };
        // One that the rest of the scene supports far less than the best is not refined.
        if h.score < REFINE_RATIO * first {
            break;
        }
        // Each refined one's slot keeps the pose it reached; one that converges onto such a
        // pose is that solution again, not refined further (its slot NaN: matches nothing).
        let Some(pose) = converge(&mut w, h.pose, prior.as_ref(), done) else {
            h.pose.x = f32::NAN;
            continue;
        };
        h.pose = pose;
        let mut r = finish(&mut w, pose, prior.as_ref(), !lazy, None);
        if usize::from(r.matches.0) + usize::from(r.matches.1) < cfg.min_matches {
            // Fewer matches than asked for: in a corridor, enough for what its parallel walls
            // tell (the heading and the offset across it), registered as degenerate.
            if r.matches.0 < 2 || !corridor {
                continue;
            }
            let full = finish(&mut w, r.pose, prior.as_ref(), true, None);
            if !full.scene_degenerate {
                continue;
            }
            r = full;
        }
        // The visibility check lowers the score: a hypothesis that cannot beat the best even
        // without it needs none.
        let hopeless = lazy && best.as_ref().is_some_and(|b| b.score > r.score * 1.01);
        if cfg.visibility_weight > 0.0 && !hopeless {
            r.score -= cfg.visibility_weight * visibility_penalty(prev, curr, &r.pose);
        }
        if verify.is_some() && r.score > cfg.min_score {
            if let Some(slot) = cands.get_mut(nc) {
                *slot = r.pose;
                nc += 1;
            }
        }
        match &best {
            Some(b) if !better(&r, b) => {
                if lazy || !close(&r.pose, &b.pose, &b.cov_scene_pinv) {
                    second_score = second_score.max(r.score);
                }
            }
            _ => {
                if let Some(b) = &best {
                    if lazy || !close(&r.pose, &b.pose, &r.cov_scene_pinv) {
                        second_score = second_score.max(b.score);
                    }
                }
                best = Some(r);
            }
        }
    }
    let Some(mut best) = best else {
        return (
            fallback(Failure::NoConsensus, prior.as_ref(), hypotheses),
            None,
        );
    };
    let mut resolved = false;
    let mut replaced = None;
    if let Some(v) = verify {
        let own = v(&best.pose);
        let mut top = own;
        let mut pick = None;
        for c in cands.iter().take(nc) {
            // Only a distinct solution (aliasing): near the winner the points, with their
            // tolerance of several cm, cannot judge better than the features.
            let far = crate::geom::hypot(c.x - best.pose.x, c.y - best.pose.y) > DISTINCT_MM
                || wrap(c.theta - best.pose.theta).abs() > DISTINCT_RAD;
            if !far {
                continue;
            }
            let score = v(c);
            if score > top && score > own + cfg.verify_margin {
                top = score;
                pick = Some(*c);
            }
        }
        if let Some(start) = pick {
            // Refined again from its answer (the candidates keep their poses only).
            let mut r = refine(&mut w, start, prior.as_ref(), !lazy);
            if usize::from(r.matches.0) + usize::from(r.matches.1) < cfg.min_matches {
                r = finish(&mut w, r.pose, prior.as_ref(), true, None);
            }
            if cfg.visibility_weight > 0.0 {
                r.score -= cfg.visibility_weight * visibility_penalty(prev, curr, &r.pose);
            }
            replaced = Some(best.pose);
            best = r;
            resolved = true;
        }
        if !resolved && own >= cfg.verify_accept {
            // The points confirm the winner: a close runner-up is no ambiguity.
            resolved = true;
        }
    }
    let matched = usize::from(best.matches.0) + usize::from(best.matches.1);
    if matched < cfg.min_matches && !(corridor && best.scene_degenerate && best.matches.0 >= 2) {
        return (
            fallback(Failure::NoConsensus, prior.as_ref(), hypotheses),
            replaced,
        );
    }
    if !(best.score > cfg.min_score) {
        return (
            fallback(Failure::NoConsensus, prior.as_ref(), hypotheses),
            replaced,
        );
    }
    if !resolved && second_score >= cfg.ambiguity * best.score {
        return (
            fallback(Failure::Ambiguous, prior.as_ref(), hypotheses),
            None,
        );
    }
    // The winner's covariance and status, and its associations (for the odometry's map).
    let best = Refined {
        score: best.score,
        ..finish(&mut w, best.pose, prior.as_ref(), true, Some(assoc))
    };
    let status = match best.unobservable {
        Some(direction) => Status::Degenerate { direction },
        None => Status::Ok,
    };
    (
        Registration {
            rel: best.pose,
            cov: best.cov,
            status,
            matches: best.matches,
            hypotheses,
            dropped: 0,
            invalid: 0,
            chi2: best.chi2,
        },
        replaced,
    )
}

/// A corridor: lines only, all parallel (within [`Config::min_pair_angle`]).
fn is_corridor(set: &Set, cfg: &Config) -> bool {
    let lines = set.lines();
    set.pts().is_empty()
        && lines.iter().all(|l| {
            lines.first().is_some_and(|f| {
                let d = wrap(l.a - f.a).abs();
                d.min(core::f32::consts::PI - d) < cfg.min_pair_angle
            })
        })
}

/// True when `a` should be preferred to `b`: a higher score, or (within 1 %) a smaller motion.
fn better(a: &Refined, b: &Refined) -> bool {
    if a.score > b.score * 1.01 {
        return true;
    }
    if b.score > a.score * 1.01 {
        return false;
    }
    let size = |p: &Pose| crate::geom::hypot(p.x, p.y) + ROTATION_SCALE * p.theta.abs();
    size(&a.pose) < size(&b.pose)
}

/// True when `a` lies within the 99.9 % ellipsoid of `b` (or within 50 mm and 1°).
fn close(a: &Pose, b: &Pose, cov: &Cov3) -> bool {
    let d = [a.x - b.x, a.y - b.y, wrap(a.theta - b.theta)];
    if crate::geom::hypot(d[0], d[1]) < 50.0 && d[2].abs() < 0.0175 {
        return true;
    }
    match inverse_spd3(cov) {
        Some(info) => quad3(&info, &d) < 16.27,
        None => false,
    }
}

fn quad3(m: &Cov3, d: &[f32; 3]) -> f32 {
    let mut s = 0.0;
    for i in 0..3 {
        for j in 0..3 {
            s += d[i] * m[i][j] * d[j];
        }
    }
    s
}
