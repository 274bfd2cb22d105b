//! Registration of two scans' features: hypotheses from the features themselves, consensus,
//! weighted least squares, covariance and an honest status.
//!
//! 1. **Hypotheses** (no first guess needed): a pair of non-parallel lines of the previous scan
//!    and a pair of the current one with the same angle between them fix the rotation (from
//!    the normals' angles α) and the translation (from the two ρ); a pair of points at the same
//!    distance fixes both too, and so does a line with a point. Only when none of these exist
//!    (a corridor), single lines give the rotation and the translation across them, with none
//!    along them. With a prior, the prior's pose is a hypothesis too and every hypothesis must
//!    lie within its covariance (χ²₃ < [`Config::prior_gate`]); without one, the motion bounds
//!    [`Config::max_translation`] and [`Config::max_rotation`] apply.
//! 2. **Consensus**: each hypothesis is scored by the features of the current scan that then
//!    agree with one of the previous scan's (Mahalanobis distance with both covariances plus a
//!    slack for the hypothesis's own error, truncated-quadratic score): features seen in one
//!    scan only, and moving objects, simply do not agree.
//! 3. **Refinement**: the best few hypotheses are refined by Gauss–Newton over the gated
//!    matches (re-associated each step while the slack shrinks to zero), weighted by the
//!    features' covariances; the prior enters as one more measurement. The best refined one
//!    wins.
//! 4. **Covariance and status**: `(Jᵀ W J)⁻¹` (scaled up by the residuals' χ² per degree of
//!    freedom when above 1). The eigen-analysis of the scene's information (x, y in mm, θ in
//!    units of 1 m) finds directions the scene cannot tell (standard deviation above
//!    [`Config::degenerate_sigma`]): the status is then [`Status::Degenerate`], the estimate
//!    does not move along them, and their variance is the prior's or
//!    [`UNOBSERVABLE_VARIANCE`].

use core::f32::consts::PI;

use crate::geom::{eigen_sym3, finite3, inverse_spd3, sin_cos, wrap, Cov3, Pose, Sym2, ZERO3};
use crate::obs::Observation;
use crate::set::{top_k, Line, Pt, Set, MAX_OBS};

/// Variance given to a direction the scene cannot tell when there is no prior: 10¹² mm² (a
/// standard deviation of 1000 km) for translation; a rotation's part is in units of 1 m
/// (10⁶ rad²). Finite, so sums and products stay finite; invert such a covariance in f64.
pub const UNOBSERVABLE_VARIANCE: f32 = 1e12;

/// Length that puts rotation in the units of translation for the eigen-analysis, mm per rad.
pub const ROTATION_SCALE: f32 = 1000.0;

/// Hypotheses refined (the best by consensus).
const REFINE: usize = 12;
/// Gauss–Newton steps at most.
const ITERATIONS: usize = 10;

/// Settings of the registration.
///
/// ```
/// let c = pfe_pose::Config::default();
/// assert!(c.max_rotation > 1.4 && c.max_translation >= 1800.0);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct Config {
    /// Largest translation between two scans considered without a prior, mm.
    pub max_translation: f32,
    /// Largest rotation between two scans considered without a prior, rad.
    pub max_rotation: f32,
    /// Model noise added to every line: (σ_α rad, σ_ρ mm). Covers what the range noise does
    /// not: walls that are not perfectly straight, partial views, the extraction's choices.
    pub line_floor: [f32; 2],
    /// Model noise added to every point feature, σ per axis, mm.
    pub point_floor: f32,
    /// Lines closer than this to parallel (rad) do not make a hypothesis pair.
    pub min_pair_angle: f32,
    /// χ²₂ gate for a match (9.21: 99 %).
    pub gate: f32,
    /// χ²₃ gate of a hypothesis against the prior.
    pub prior_gate: f32,
    /// Slack for a hypothesis's own error while scoring: (σ_α rad, σ_ρ mm, σ per mm of reach).
    pub slack: [f32; 3],
    /// Segments farther apart along their line than this (mm) do not match.
    pub overlap_slack: f32,
    /// A direction whose standard deviation (x, y in mm; θ in units of
    /// [`ROTATION_SCALE`]) exceeds this is one the scene cannot tell, mm.
    pub degenerate_sigma: f32,
    /// Weight of the segments' overlap in a line match's score (0: none; 1: a match counts in
    /// proportion to how much of the shorter segment the other covers).
    pub overlap_weight: f32,
    /// Weight of the visibility check in the choice among refined hypotheses: each segment
    /// that would hide, seen from the other scan, what that scan saw costs up to this much
    /// score (0: no check).
    pub visibility_weight: f32,
    /// Least score (matches' agreement less the visibility penalty) for a registration.
    pub min_score: f32,
    /// Count a direction that a single match alone determines as unobservable (its
    /// information dropped): an association no other feature confirms is not trusted.
    pub confirm: bool,
    /// Fewest matched features for a registration.
    pub min_matches: usize,
    /// Scale the covariance by the residuals' χ² per degree of freedom when above 1.
    pub scale_by_residuals: bool,
    /// Give up ([`Failure::Ambiguous`]) when a distinct second solution scores at least this
    /// fraction of the best (above 1: never).
    pub ambiguity: f32,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            max_translation: 3000.0,
            max_rotation: 1.75,
            line_floor: [0.008, 15.0],
            point_floor: 15.0,
            min_pair_angle: 0.17,
            gate: 9.21,
            prior_gate: 16.27,
            slack: [0.05, 100.0, 0.03],
            overlap_slack: 500.0,
            degenerate_sigma: 300.0,
            overlap_weight: 0.5,
            visibility_weight: 1.0,
            min_score: 0.0,
            confirm: true,
            min_matches: 3,
            scale_by_residuals: true,
            ambiguity: 2.0,
        }
    }
}

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
    /// Hypotheses scored.
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
    let p = Set::from_obs(prev, cfg);
    let c = Set::from_obs(curr, cfg);
    let mut assoc = Assoc::new();
    let mut r = register_sets(&p, &c, prior, cfg, &mut assoc);
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
#[derive(Clone, Copy)]
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

/// The registration on prepared sets; `assoc` receives the final matches.
pub(crate) fn register_sets(
    prev: &Set,
    curr: &Set,
    prior: Option<(Pose, Cov3)>,
    cfg: &Config,
    assoc: &mut Assoc,
) -> Registration {
    let prior = check_prior(prior, cfg);
    let fallback = |failure: Failure, prior: Option<&Prior>, hypotheses: u32| {
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
    };
    let prior = match prior {
        Ok(p) => p,
        Err(f) => return fallback(f, None, 0),
    };
    if prev.len() < 2 || curr.len() < 2 {
        return fallback(Failure::TooFewFeatures, prior.as_ref(), 0);
    }
    let mut top = Top::new();
    let hypotheses = hypothesise(prev, curr, prior.as_ref(), cfg, &mut top);
    if top.n == 0 {
        return fallback(Failure::NoHypothesis, prior.as_ref(), hypotheses);
    }
    // Refine the best few; keep the best refined and the best distinct runner-up.
    let mut best: Option<Refined> = None;
    let mut second_score = 0.0f32;
    for h in top.items() {
        let r = refine(prev, curr, h.pose, prior.as_ref(), cfg);
        if usize::from(r.matches.0) + usize::from(r.matches.1) < cfg.min_matches {
            continue;
        }
        match &best {
            Some(b) if !better(&r, b) => {
                if !close(&r.pose, &b.pose, &b.cov_scene_pinv) {
                    second_score = second_score.max(r.score);
                }
            }
            _ => {
                if let Some(b) = &best {
                    if !close(&r.pose, &b.pose, &r.cov_scene_pinv) {
                        second_score = second_score.max(b.score);
                    }
                }
                best = Some(r);
            }
        }
    }
    let Some(best) = best else {
        return fallback(Failure::NoConsensus, prior.as_ref(), hypotheses);
    };
    let matched = usize::from(best.matches.0) + usize::from(best.matches.1);
    if matched < cfg.min_matches {
        return fallback(Failure::NoConsensus, prior.as_ref(), hypotheses);
    }
    if !(best.score > cfg.min_score) {
        return fallback(Failure::NoConsensus, prior.as_ref(), hypotheses);
    }
    if second_score >= cfg.ambiguity * best.score {
        return fallback(Failure::Ambiguous, prior.as_ref(), hypotheses);
    }
    // Associations of the best, for the odometry's map.
    let mut w = Work::new(prev, curr, cfg, None);
    w.associate(&best.pose, 0.0, Some(assoc));
    let status = match best.unobservable {
        Some(direction) => Status::Degenerate { direction },
        None => Status::Ok,
    };
    Registration {
        rel: best.pose,
        cov: best.cov,
        status,
        matches: best.matches,
        hypotheses,
        dropped: 0,
        invalid: 0,
        chi2: best.chi2,
    }
}

/// True when `a` should be preferred to `b`: a higher score, or (within 1 %) a smaller motion.
fn better(a: &Refined, b: &Refined) -> bool {
    if a.score > b.score * 1.01 {
        return true;
    }
    if b.score > a.score * 1.01 {
        return false;
    }
    let size = |p: &Pose| libm::hypotf(p.x, p.y) + ROTATION_SCALE * p.theta.abs();
    size(&a.pose) < size(&b.pose)
}

/// True when `a` lies within the 99.9 % ellipsoid of `b` (or within 50 mm and 1°).
fn close(a: &Pose, b: &Pose, cov: &Cov3) -> bool {
    let d = [a.x - b.x, a.y - b.y, wrap(a.theta - b.theta)];
    if libm::hypotf(d[0], d[1]) < 50.0 && d[2].abs() < 0.0175 {
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

/// A scored hypothesis.
#[derive(Clone, Copy, Debug)]
struct Hyp {
    pose: Pose,
    score: f32,
}

/// The best hypotheses so far, distinct from one another (non-maximum suppression).
struct Top {
    items: [Hyp; REFINE],
    n: usize,
}

impl Top {
    fn new() -> Self {
        Self {
            items: [Hyp {
                pose: Pose::IDENTITY,
                score: 0.0,
            }; REFINE],
            n: 0,
        }
    }

    fn items(&self) -> &[Hyp] {
        self.items.get(..self.n).unwrap_or(&[])
    }

    /// True when a kept hypothesis lies within `dist` mm and `angle` rad of `pose`.
    fn has_near(&self, pose: &Pose, dist: f32, angle: f32) -> bool {
        self.items().iter().any(|e| {
            libm::hypotf(e.pose.x - pose.x, e.pose.y - pose.y) < dist
                && wrap(e.pose.theta - pose.theta).abs() < angle
        })
    }

    fn offer(&mut self, h: Hyp) {
        if !(h.score > 0.0) {
            return;
        }
        // Near an existing one: keep the better of the two.
        let near = |a: &Pose, b: &Pose| {
            libm::hypotf(a.x - b.x, a.y - b.y) < 150.0 && wrap(a.theta - b.theta).abs() < 0.05
        };
        let n = self.n;
        if let Some(e) = self
            .items
            .iter_mut()
            .take(n)
            .find(|e| near(&e.pose, &h.pose))
        {
            if h.score > e.score {
                *e = h;
            }
            return;
        }
        if n < REFINE {
            if let Some(slot) = self.items.get_mut(n) {
                *slot = h;
                self.n += 1;
            }
            return;
        }
        if let Some(worst) = self
            .items
            .iter_mut()
            .min_by(|a, b| a.score.total_cmp(&b.score))
        {
            if h.score > worst.score {
                *worst = h;
            }
        }
    }
}

/// `(b − a)` modulo π, in [0, π).
fn undirected(a: f32, b: f32) -> f32 {
    let d = b - a;
    let u = d - PI * libm::floorf(d / PI);
    if (0.0..PI).contains(&u) {
        u
    } else {
        0.0
    }
}

/// `x` modulo π, in (−π/2, π/2].
fn mod_pi(x: f32) -> f32 {
    x - PI * libm::roundf(x / PI)
}

/// Hypotheses of `curr`'s pose in `prev`'s frame, scored; returns how many were scored.
fn hypothesise(prev: &Set, curr: &Set, prior: Option<&Prior>, cfg: &Config, top: &mut Top) -> u32 {
    let mut w = Work::new(prev, curr, cfg, prior);
    let mut count = 0u32;
    let consider = |pose: Pose, w: &mut Work, top: &mut Top, count: &mut u32| {
        if !pose.is_finite() {
            return;
        }
        match prior {
            Some(p) => {
                let d = [
                    pose.x - p.pose.x,
                    pose.y - p.pose.y,
                    wrap(pose.theta - p.pose.theta),
                ];
                if !(quad3(&p.gate_info, &d) < cfg.prior_gate) {
                    return;
                }
            }
            None => {
                if !(libm::hypotf(pose.x, pose.y) <= cfg.max_translation)
                    || !(pose.theta.abs() <= cfg.max_rotation)
                {
                    return;
                }
            }
        }
        *count = count.saturating_add(1);
        // A kept hypothesis is already this one (the right pose comes from many pairs).
        if top.has_near(&pose, 40.0, 0.01) {
            return;
        }
        let score = w.associate(&pose, 1.0, None).score;
        top.offer(Hyp { pose, score });
    };
    match prior {
        Some(p) => consider(p.pose, &mut w, top, &mut count),
        None => consider(Pose::IDENTITY, &mut w, top, &mut count),
    }
    let (pl, cl) = (prev.lines(), curr.lines());
    let (hp, np) = top_k::<12>(pl.iter().map(|l| l.rank));
    let (hc, nc) = top_k::<12>(cl.iter().map(|l| l.rank));
    let hp = hp.get(..np).unwrap_or(&[]);
    let hc = hc.get(..nc).unwrap_or(&[]);
    let line = |s: &[Line], i: u8| s.get(usize::from(i)).copied();
    let mut pair_hyps = 0u32;
    // Pairs of non-parallel lines.
    for (ii, &i) in hp.iter().enumerate() {
        let Some(li) = line(pl, i) else { continue };
        for &j in hp.get(ii + 1..).unwrap_or(&[]) {
            let Some(lj) = line(pl, j) else { continue };
            let dp = undirected(li.a, lj.a);
            if dp.min(PI - dp) < cfg.min_pair_angle {
                continue;
            }
            for &k in hc {
                let Some(lk) = line(cl, k) else { continue };
                for &l in hc {
                    if l == k {
                        continue;
                    }
                    let Some(ll) = line(cl, l) else { continue };
                    let dc = undirected(lk.a, ll.a);
                    let var = li.cov.a + lj.cov.a + lk.cov.a + ll.cov.a;
                    let gate = 3.0 * libm::sqrtf(var) + cfg.slack[0];
                    if mod_pi(dp - dc).abs() > gate {
                        continue;
                    }
                    let t0 = li.a - lk.a;
                    let t1 = t0 + mod_pi(lj.a - ll.a - t0);
                    let theta = 0.5 * (t0 + t1);
                    for th in [theta, theta + PI] {
                        let th = wrap(th);
                        if let Some(t) = solve_two_lines(&li, &lk, &lj, &ll, th) {
                            pair_hyps += 1;
                            consider(Pose::new(t[0], t[1], th), &mut w, top, &mut count);
                        }
                    }
                }
            }
        }
    }
    // Pairs of points at the same distance.
    let (pp, cp) = (prev.pts(), curr.pts());
    let (qp, nqp) = top_k::<8>(pp.iter().map(|p| p.rank));
    let (qc, nqc) = top_k::<8>(cp.iter().map(|p| p.rank));
    let qp = qp.get(..nqp).unwrap_or(&[]);
    let qc = qc.get(..nqc).unwrap_or(&[]);
    let pt = |s: &[Pt], i: u8| s.get(usize::from(i)).copied();
    for (ai, &a) in qp.iter().enumerate() {
        let Some(pa) = pt(pp, a) else { continue };
        for &b in qp.get(ai + 1..).unwrap_or(&[]) {
            let Some(pb) = pt(pp, b) else { continue };
            let vp = [pb.p[0] - pa.p[0], pb.p[1] - pa.p[1]];
            let dp = libm::hypotf(vp[0], vp[1]);
            if dp < 300.0 {
                continue;
            }
            for &c in qc {
                let Some(pc) = pt(cp, c) else { continue };
                for &d in qc {
                    if d == c {
                        continue;
                    }
                    let Some(pd) = pt(cp, d) else { continue };
                    let vc = [pd.p[0] - pc.p[0], pd.p[1] - pc.p[1]];
                    let dc = libm::hypotf(vc[0], vc[1]);
                    let var = pa.cov.a + pa.cov.c + pb.cov.a + pb.cov.c;
                    let var = var + pc.cov.a + pc.cov.c + pd.cov.a + pd.cov.c;
                    if (dp - dc).abs() > 3.0 * libm::sqrtf(0.5 * var) + cfg.slack[1] {
                        continue;
                    }
                    let th = wrap(libm::atan2f(vp[1], vp[0]) - libm::atan2f(vc[1], vc[0]));
                    let mid_p = [0.5 * (pa.p[0] + pb.p[0]), 0.5 * (pa.p[1] + pb.p[1])];
                    let mid_c = [0.5 * (pc.p[0] + pd.p[0]), 0.5 * (pc.p[1] + pd.p[1])];
                    let rc = Pose::new(0.0, 0.0, th).transform_point(mid_c);
                    pair_hyps += 1;
                    consider(
                        Pose::new(mid_p[0] - rc[0], mid_p[1] - rc[1], th),
                        &mut w,
                        top,
                        &mut count,
                    );
                }
            }
        }
    }
    // A line and a point.
    let (hp6, hc6) = (hp.get(..6).unwrap_or(hp), hc.get(..6).unwrap_or(hc));
    let (qp4, qc4) = (qp.get(..5).unwrap_or(qp), qc.get(..5).unwrap_or(qc));
    for &i in hp6 {
        let Some(li) = line(pl, i) else { continue };
        for &k in hc6 {
            let Some(lk) = line(cl, k) else { continue };
            for th in [li.a - lk.a, li.a - lk.a + PI] {
                let th = wrap(th);
                let (s, c) = sin_cos(th);
                for &a in qp4 {
                    let Some(pa) = pt(pp, a) else { continue };
                    for &b in qc4 {
                        let Some(pb) = pt(cp, b) else { continue };
                        let t = [
                            pa.p[0] - (c * pb.p[0] - s * pb.p[1]),
                            pa.p[1] - (s * pb.p[0] + c * pb.p[1]),
                        ];
                        // The line's ρ must agree.
                        let (sa, ca) = sin_cos(li.a);
                        let sign = if libm::cosf(lk.a + th - li.a) >= 0.0 {
                            1.0
                        } else {
                            -1.0
                        };
                        let e = li.r - sign * lk.r - (ca * t[0] + sa * t[1]);
                        let sd = libm::sqrtf(li.cov.c + lk.cov.c + pa.cov.a + pb.cov.a);
                        if e.abs() > 3.0 * sd + cfg.slack[1] + cfg.slack[2] * lk.reach {
                            continue;
                        }
                        pair_hyps += 1;
                        consider(Pose::new(t[0], t[1], th), &mut w, top, &mut count);
                    }
                }
            }
        }
    }
    // A corridor: single lines, nothing along them.
    if pair_hyps == 0 {
        for &i in hp {
            let Some(li) = line(pl, i) else { continue };
            for &k in hc {
                let Some(lk) = line(cl, k) else { continue };
                for th in [li.a - lk.a, li.a - lk.a + PI] {
                    let th = wrap(th);
                    let sign = if libm::cosf(lk.a + th - li.a) >= 0.0 {
                        1.0
                    } else {
                        -1.0
                    };
                    let (sa, ca) = sin_cos(li.a);
                    let mut along = 0.0;
                    if let Some(p) = prior {
                        along = -sa * p.pose.x + ca * p.pose.y;
                    }
                    let d = li.r - sign * lk.r;
                    let t = [d * ca - along * sa, d * sa + along * ca];
                    consider(Pose::new(t[0], t[1], th), &mut w, top, &mut count);
                }
            }
        }
    }
    count
}

/// The translation that maps lines `k`, `l` of the current scan onto `i`, `j` of the previous
/// one under rotation `th`.
fn solve_two_lines(li: &Line, lk: &Line, lj: &Line, ll: &Line, th: f32) -> Option<[f32; 2]> {
    let rhs = |p: &Line, c: &Line| {
        let sign = if libm::cosf(c.a + th - p.a) >= 0.0 {
            1.0
        } else {
            -1.0
        };
        p.r - sign * c.r
    };
    let (si, ci) = sin_cos(li.a);
    let (sj, cj) = sin_cos(lj.a);
    let det = ci * sj - si * cj;
    if !(det.abs() > 0.05) {
        return None;
    }
    let (bi, bj) = (rhs(li, lk), rhs(lj, ll));
    let x = (bi * sj - bj * si) / det;
    let y = (ci * bj - cj * bi) / det;
    (x.is_finite() && y.is_finite()).then_some([x, y])
}

/// A hypothesis after Gauss–Newton.
#[derive(Clone, Copy, Debug)]
struct Refined {
    pose: Pose,
    cov: Cov3,
    /// Pseudo-inverse of the scene's information (for "distinct" tests).
    cov_scene_pinv: Cov3,
    score: f32,
    chi2: f32,
    matches: (u16, u16),
    unobservable: Option<[f32; 3]>,
}

/// Normal equations of one association.
struct Normal {
    h: Cov3,
    g: [f32; 3],
    chi2: f32,
    score: f32,
    lines: u16,
    pts: u16,
}

/// The data of one registration.
struct Work<'a> {
    prev: &'a Set,
    curr: &'a Set,
    cfg: &'a Config,
    #[allow(dead_code)]
    prior: Option<&'a Prior>,
    /// Each match's information `Jᵀ W J` in the last association.
    contrib: [Cov3; 2 * MAX_OBS],
    nc: usize,
}

impl<'a> Work<'a> {
    fn new(prev: &'a Set, curr: &'a Set, cfg: &'a Config, prior: Option<&'a Prior>) -> Self {
        Self {
            prev,
            curr,
            cfg,
            prior,
            contrib: [ZERO3; 2 * MAX_OBS],
            nc: 0,
        }
    }

    /// Matches every current feature to its nearest previous one under `pose` (Mahalanobis,
    /// with `slack` times the configured slack), and the normal equations of those matches.
    fn associate(&mut self, pose: &Pose, slack: f32, mut out: Option<&mut Assoc>) -> Normal {
        let cfg = self.cfg;
        let mut n = Normal {
            h: ZERO3,
            g: [0.0; 3],
            chi2: 0.0,
            score: 0.0,
            lines: 0,
            pts: 0,
        };
        let gate = cfg.gate;
        self.nc = 0;
        let (x, y) = (pose.x, pose.y);
        let (st, ct) = sin_cos(pose.theta);
        let sa2 = (slack * cfg.slack[0]) * (slack * cfg.slack[0]);
        for (k, lk) in self.curr.lines().iter().enumerate() {
            let a = lk.a + pose.theta;
            let (sa, ca) = sin_cos(a);
            let r = lk.r + x * ca + y * sa;
            let h = -x * sa + y * ca;
            // Covariance of the transformed line.
            let ct_ = Sym2 {
                a: lk.cov.a,
                b: lk.cov.b + h * lk.cov.a,
                c: lk.cov.c + 2.0 * h * lk.cov.b + h * h * lk.cov.a,
            };
            let sr = slack * (cfg.slack[1] + cfg.slack[2] * lk.reach);
            let ext = lk
                .ext
                .map(|(s, e)| (pose.transform_point(s), pose.transform_point(e)));
            let mut best: Option<(f32, u8, [f32; 2], Sym2, f32, f32)> = None;
            for (i, li) in self.prev.lines().iter().enumerate() {
                let dcos = libm::cosf(a - li.a);
                let sign = if dcos >= 0.0 { 1.0 } else { -1.0 };
                let ea = if sign > 0.0 {
                    wrap(a - li.a)
                } else {
                    wrap(a + PI - li.a)
                };
                let var_a = ct_.a + li.cov.a + sa2;
                if ea * ea > gate * var_a {
                    continue;
                }
                let er = sign * r - li.r;
                let var_r = ct_.c + li.cov.c + sr * sr;
                if er * er > gate * var_r {
                    continue;
                }
                let s = Sym2 {
                    a: var_a,
                    b: sign * ct_.b + li.cov.b,
                    c: var_r,
                };
                let Some(w) = s.inverse() else { continue };
                let e = [ea, er];
                let d2 = w.quad(e);
                if !(d2 < gate) {
                    continue;
                }
                let Some(frac) = overlap(ext, li, cfg.overlap_slack + sr) else {
                    continue;
                };
                if best.is_none_or(|b| d2 < b.0) {
                    let Ok(iu) = u8::try_from(i) else { continue };
                    best = Some((d2, iu, e, w, sign, frac));
                }
            }
            if let Some(o) = out.as_deref_mut() {
                if let Some(slot) = o.lines.get_mut(k) {
                    *slot = best.map_or(NONE, |b| b.1);
                }
            }
            let Some((d2, _, e, w, sign, frac)) = best else {
                continue;
            };
            n.lines += 1;
            n.score += (1.0 - d2 / gate) * (1.0 - cfg.overlap_weight + cfg.overlap_weight * frac);
            n.chi2 += d2;
            // Jacobian rows: e_α = [0, 0, 1]; e_ρ = sign · [cos a, sin a, h].
            let ja = [0.0, 0.0, 1.0];
            let jr = [sign * ca, sign * sa, sign * h];
            let hi = accumulate(&mut n, &ja, &jr, &w, &e);
            self.record(hi);
        }
        for (k, pk) in self.curr.pts().iter().enumerate() {
            let q = pose.transform_point(pk.p);
            let cq = pk.cov.rotate(st, ct);
            let reach = libm::hypotf(pk.p[0], pk.p[1]);
            let sr = slack * (cfg.slack[1] + cfg.slack[2] * reach);
            let mut best: Option<(f32, u8, [f32; 2], Sym2)> = None;
            for (i, pi) in self.prev.pts().iter().enumerate() {
                let e = [q[0] - pi.p[0], q[1] - pi.p[1]];
                let s = cq.add(pi.cov).add(Sym2 {
                    a: sr * sr,
                    b: 0.0,
                    c: sr * sr,
                });
                if e[0] * e[0] > gate * s.a || e[1] * e[1] > gate * s.c {
                    continue;
                }
                let Some(w) = s.inverse() else { continue };
                let d2 = w.quad(e);
                if d2 < gate && best.is_none_or(|b| d2 < b.0) {
                    let Ok(iu) = u8::try_from(i) else { continue };
                    best = Some((d2, iu, e, w));
                }
            }
            if let Some(o) = out.as_deref_mut() {
                if let Some(slot) = o.pts.get_mut(k) {
                    *slot = best.map_or(NONE, |b| b.1);
                }
            }
            let Some((d2, _, e, w)) = best else { continue };
            n.pts += 1;
            n.score += 1.0 - d2 / gate;
            n.chi2 += d2;
            let jx = [1.0, 0.0, -st * pk.p[0] - ct * pk.p[1]];
            let jy = [0.0, 1.0, ct * pk.p[0] - st * pk.p[1]];
            let hi = accumulate(&mut n, &jx, &jy, &w, &e);
            self.record(hi);
        }
        n
    }
}

impl Work<'_> {
    fn record(&mut self, hi: Cov3) {
        if let Some(slot) = self.contrib.get_mut(self.nc) {
            *slot = hi;
            self.nc += 1;
        }
    }

    /// The information of the last association without its most critical match: the one
    /// whose removal leaves the smallest least eigenvalue (scaled units). A direction that
    /// one match alone determines is not confirmed by any other.
    fn without_critical(&self, h: &Cov3) -> Cov3 {
        let mut worst = *h;
        let mut least = f32::INFINITY;
        for hi in self.contrib.iter().take(self.nc) {
            let mut r = *h;
            for (row, hr) in r.iter_mut().zip(hi) {
                for (v, x) in row.iter_mut().zip(hr) {
                    *v -= x;
                }
            }
            let l = eigen_sym3(&to_scaled_info(&r)).0[0];
            if l < least {
                least = l;
                worst = r;
            }
        }
        worst
    }
}

/// `H += Jᵀ W J`, `g += Jᵀ W e` for a 2-row residual with rows `j0`, `j1`; returns the
/// match's `Jᵀ W J`.
fn accumulate(n: &mut Normal, j0: &[f32; 3], j1: &[f32; 3], w: &Sym2, e: &[f32; 2]) -> Cov3 {
    let mut hi = ZERO3;
    // W J: rows.
    let mut wj0 = [0.0f32; 3];
    let mut wj1 = [0.0f32; 3];
    for c in 0..3 {
        wj0[c] = w.a * j0[c] + w.b * j1[c];
        wj1[c] = w.b * j0[c] + w.c * j1[c];
    }
    for r in 0..3 {
        for c in 0..3 {
            hi[r][c] = j0[r] * wj0[c] + j1[r] * wj1[c];
            n.h[r][c] += hi[r][c];
        }
        n.g[r] += wj0[r] * e[0] + wj1[r] * e[1];
    }
    hi
}

/// `None` when the segment `ext` (in the previous frame) and `li`'s segment are farther apart
/// along `li` than `slack`; otherwise the length of their overlap over the shorter one's (1
/// when either has no extent).
fn overlap(ext: Option<([f32; 2], [f32; 2])>, li: &Line, slack: f32) -> Option<f32> {
    let (Some((s, e)), Some((ps, pe))) = (ext, li.ext) else {
        return Some(1.0);
    };
    let (sa, ca) = sin_cos(li.a);
    let along = |p: [f32; 2]| -sa * p[0] + ca * p[1];
    let (a0, a1) = (along(s), along(e));
    let (b0, b1) = (along(ps), along(pe));
    let (alo, ahi) = (a0.min(a1), a0.max(a1));
    let (blo, bhi) = (b0.min(b1), b0.max(b1));
    let gap = alo.max(blo) - ahi.min(bhi);
    if !(gap <= slack) {
        return None;
    }
    let shorter = (ahi - alo).min(bhi - blo).max(1.0);
    Some((-gap / shorter).clamp(0.0, 1.0))
}

/// Scales to put θ in mm: (1, 1, [`ROTATION_SCALE`]).
const SCALE: [f32; 3] = [1.0, 1.0, ROTATION_SCALE];

fn to_scaled_info(h: &Cov3) -> Cov3 {
    let mut r = ZERO3;
    for i in 0..3 {
        for j in 0..3 {
            r[i][j] = h[i][j] / (SCALE[i] * SCALE[j]);
        }
    }
    r
}

fn from_scaled_cov(c: &Cov3) -> Cov3 {
    let mut r = ZERO3;
    for i in 0..3 {
        for j in 0..3 {
            r[i][j] = c[i][j] / (SCALE[i] * SCALE[j]);
        }
    }
    r
}

/// Gauss–Newton from `start`.
fn refine(prev: &Set, curr: &Set, start: Pose, prior: Option<&Prior>, cfg: &Config) -> Refined {
    let mut w = Work::new(prev, curr, cfg, prior);
    let mut pose = start;
    let slacks = [1.0, 0.5, 0.25, 0.1, 0.0];
    let limit = 1.0 / (cfg.degenerate_sigma * cfg.degenerate_sigma);
    for it in 0..ITERATIONS {
        let slack = slacks.get(it).copied().unwrap_or(0.0);
        let mut n = w.associate(&pose, slack, None);
        if let Some(p) = prior {
            add_prior(&mut n, &pose, p);
        }
        let hs = to_scaled_info(&n.h);
        let gs = [n.g[0], n.g[1], n.g[2] / ROTATION_SCALE];
        let (vals, vecs) = eigen_sym3(&hs);
        let floor = if prior.is_some() {
            vals[2] * 1e-7
        } else {
            limit.max(vals[2] * 1e-7)
        };
        let mut step = [0.0f32; 3];
        for (l, v) in vals.iter().zip(&vecs) {
            if !(*l > floor) {
                continue;
            }
            let c = (v[0] * gs[0] + v[1] * gs[1] + v[2] * gs[2]) / l;
            for (s, vi) in step.iter_mut().zip(v) {
                *s -= c * vi;
            }
        }
        let step_theta = step[2] / ROTATION_SCALE;
        if !(step[0].is_finite() && step[1].is_finite() && step_theta.is_finite()) {
            break;
        }
        pose = Pose::new(pose.x + step[0], pose.y + step[1], pose.theta + step_theta);
        let small = libm::hypotf(step[0], step[1]) < 0.05 && step_theta.abs() < 5e-5;
        if small && slack == 0.0 {
            break;
        }
    }
    // Final association, covariance and status.
    let mut n = w.associate(&pose, 0.0, None);
    let (vals, vecs) = eigen_sym3(&to_scaled_info(&n.h));
    if cfg.confirm && vals[0] > limit {
        // A direction only one match determines is taken as unobservable.
        let robust = w.without_critical(&n.h);
        if !(eigen_sym3(&to_scaled_info(&robust)).0[0] > limit) {
            n.h = robust;
        }
    }
    let (vals, vecs) = if cfg.confirm {
        eigen_sym3(&to_scaled_info(&n.h))
    } else {
        (vals, vecs)
    };
    let unobservable = (!(vals[0] > limit)).then_some(vecs[0]);
    let m = usize::from(n.lines) * 2 + usize::from(n.pts) * 2;
    let factor = if cfg.scale_by_residuals && m > 3 {
        (n.chi2 / (m - 3) as f32).max(1.0)
    } else {
        1.0
    };
    // Scene-only pseudo-inverse (sentinel on the unobservable directions).
    let mut pinv = ZERO3;
    for (l, v) in vals.iter().zip(&vecs) {
        let var = if *l > limit {
            (factor / l).min(UNOBSERVABLE_VARIANCE)
        } else {
            UNOBSERVABLE_VARIANCE
        };
        for i in 0..3 {
            for j in 0..3 {
                pinv[i][j] += var * v[i] * v[j];
            }
        }
    }
    let cov_scene = from_scaled_cov(&pinv);
    let cov = match prior {
        Some(p) => {
            let mut h = n.h;
            for r in h.iter_mut() {
                for v in r.iter_mut() {
                    *v /= factor;
                }
            }
            let h = crate::geom::add3(&h, &p.info);
            inverse_spd3(&h).unwrap_or(p.cov)
        }
        None => cov_scene,
    };
    let penalty = if cfg.visibility_weight > 0.0 {
        cfg.visibility_weight * visibility_penalty(prev, curr, &pose)
    } else {
        0.0
    };
    Refined {
        pose,
        cov,
        cov_scene_pinv: cov_scene,
        score: n.score - penalty,
        chi2: n.chi2,
        matches: (n.lines, n.pts),
        unobservable,
    }
}

/// How much the segments of each scan, seen from the other scan's position under `pose`, would
/// hide segments that scan did see: the number of hidden samples over 5 per segment, summed
/// over both directions. A right pose hides nothing (static, opaque scene); a wrong one puts
/// walls in front of what was seen.
fn visibility_penalty(prev: &Set, curr: &Set, pose: &Pose) -> f32 {
    let inv = pose.inverse();
    let a = hidden(
        curr.lines()
            .iter()
            .filter_map(|l| l.ext)
            .map(|(s, e)| (pose.transform_point(s), pose.transform_point(e))),
        prev.lines(),
    );
    let b = hidden(
        prev.lines()
            .iter()
            .filter_map(|l| l.ext)
            .map(|(s, e)| (inv.transform_point(s), inv.transform_point(e))),
        curr.lines(),
    );
    a + b + 2.0 * crossings(prev, curr, pose)
}

/// How many segments of either scan the straight path between the two scan positions goes
/// through (in the middle 90 % of the segment): a robot does not pass through walls.
fn crossings(prev: &Set, curr: &Set, pose: &Pose) -> f32 {
    let to = [pose.x, pose.y];
    let through = |(s, e): ([f32; 2], [f32; 2])| -> bool {
        // Path 0 + u·to, u in (0, 1); segment s + μ (e − s), μ in [0.05, 0.95].
        let w = [e[0] - s[0], e[1] - s[1]];
        let den = to[0] * w[1] - to[1] * w[0];
        if !(den.abs() > 1e-3) {
            return false;
        }
        let u = (s[0] * w[1] - s[1] * w[0]) / den;
        let mu = (s[0] * to[1] - s[1] * to[0]) / den;
        u > 0.0 && u < 1.0 && (0.05..=0.95).contains(&mu)
    };
    let a = prev
        .lines()
        .iter()
        .filter_map(|l| l.ext)
        .filter(|&x| through(x))
        .count();
    let b = curr
        .lines()
        .iter()
        .filter_map(|l| l.ext)
        .map(|(s, e)| (pose.transform_point(s), pose.transform_point(e)))
        .filter(|&x| through(x))
        .count();
    (a + b) as f32
}

/// Samples of the segments `front` (in a scan's frame) that lie clearly in front of one of the
/// segments `seen` by that scan, over 5 per segment.
fn hidden(front: impl Iterator<Item = ([f32; 2], [f32; 2])>, seen: &[Line]) -> f32 {
    const SAMPLES: usize = 5;
    const END: f32 = 150.0;
    const DEPTH: f32 = 250.0;
    let mut total = 0.0;
    for (s, e) in front {
        let d = [e[0] - s[0], e[1] - s[1]];
        let len = libm::hypotf(d[0], d[1]);
        if !(len > 2.0 * END + 100.0) {
            continue;
        }
        let mut count = 0usize;
        for k in 0..SAMPLES {
            let u = (END + (len - 2.0 * END) * k as f32 / (SAMPLES - 1) as f32) / len;
            let q = [s[0] + d[0] * u, s[1] + d[1] * u];
            let rq = libm::hypotf(q[0], q[1]);
            if !(rq > 1.0) {
                continue;
            }
            let dir = [q[0] / rq, q[1] / rq];
            let behind = seen.iter().filter_map(|l| l.ext).any(|(ps, pe)| {
                // Ray origin + λ dir meets ps + μ (pe − ps).
                let w = [pe[0] - ps[0], pe[1] - ps[1]];
                let den = dir[0] * w[1] - dir[1] * w[0];
                if !(den.abs() > 1e-6 * libm::hypotf(w[0], w[1])) {
                    return false;
                }
                let lambda = (ps[0] * w[1] - ps[1] * w[0]) / den;
                let mu = (ps[0] * dir[1] - ps[1] * dir[0]) / den;
                (0.05..=0.95).contains(&mu) && lambda > rq + DEPTH
            });
            if behind {
                count += 1;
            }
        }
        total += count as f32 / SAMPLES as f32;
    }
    total
}

fn add_prior(n: &mut Normal, pose: &Pose, p: &Prior) {
    let e = [
        pose.x - p.pose.x,
        pose.y - p.pose.y,
        wrap(pose.theta - p.pose.theta),
    ];
    n.h = crate::geom::add3(&n.h, &p.info);
    for (g, row) in n.g.iter_mut().zip(&p.info) {
        *g += row[0] * e[0] + row[1] * e[1] + row[2] * e[2];
    }
}
