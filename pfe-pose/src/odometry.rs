//! Feature odometry: every scan's pose in the frame of the first, registered against a small
//! local map of features rather than only against the previous scan.
//!
//! Each scan is first **tracked**: the motion prior (or, without one, the last motion again)
//! predicts its pose, and Gauss–Newton refines that against the map alone (no search). The
//! result is taken when at least half of the scan's features agree with the map; a direction
//! the map cannot tell (a corridor's length) then keeps the prediction, with the prior's
//! variance along it, or without a prior [`crate::UNOBSERVABLE_VARIANCE`] (the last motion
//! again is a guess, not a measurement). Otherwise the scan is registered
//! against the previous scan ([`crate::register`], gated by the motion prior when one is
//! given); without a prior, a direction that pair cannot tell takes the last motion's value
//! (not "no motion"). That result, widened to three standard deviations, starts the
//! refinement against the map. The map: at
//! most `MAP` features (lines and points) in the odometry frame, taken into the predicted
//! pose's frame for the registration. Matched
//! features are fused into their map feature (information-weighted, the segment's extent the
//! union), unmatched ones are added, and when the map is full the one seen least recently
//! (then least often) is replaced. When the map cannot register the scan, or its answer
//! disagrees with the pair's beyond both covariances (χ²₃ 99.9 %: a wrong map match), the
//! pair's result is taken and the map restarts from this scan. When the pair did not register
//! either, the map is searched from the last motion; an answer that leaves a direction
//! undetermined is refused (from so wide a search it is a guess), and then the scan is not
//! registered ([`Status::None`]): its pose is the prediction (the last motion again, turned by
//! the heading the directions of its lines and the map's agree on, when at least two do) and
//! the map is **kept**, so that the next scan re-localises against it.
//!
//! Lines are kept as a normal angle and an anchor point near the segment's middle, with the
//! covariance of (angle, normal offset at the anchor): (α, ρ) about an origin far away would
//! be nearly singular in f32.
//!
//! Covariance: the relative motion's covariance is the registration's against the map; the
//! pose's covariance chains those (`compose_covariance`), which ignores what the map's
//! memory saves: it bounds the error from above.

use core::f32::consts::PI;

use crate::geom::{compose_covariance, sin_cos, wrap, Cov3, Pose, Sym2, ZERO3};
use crate::obs::{LineObs, Observation, PointObs};
use crate::points::{agreement, complete, recheck, refine_on_key, RangeScan, SCAN_BEAMS};
use crate::register::{
    register_sets, register_sets_verified, Assoc, Config, Status, NONE, ROTATION_SCALE,
    UNOBSERVABLE_VARIANCE,
};
use crate::set::{Set, MAX_OBS};

/// One feature of the map, in the odometry frame. A line is kept as its normal angle α and an
/// anchor point on it (near the segment's middle) with the covariance of (α, d), d the
/// normal offset at the anchor: unlike (α, ρ) about a far origin, well conditioned in f32
/// wherever the robot is.
#[derive(Clone, Copy, Debug)]
struct Entry {
    /// Point (x, y), or a line's anchor point.
    v: [f32; 2],
    /// A line's normal angle.
    alpha: f32,
    /// Point: (x, y); line: (α, d).
    cov: Sym2,
    /// Segment ends of a line (NaN: none).
    ext: ([f32; 2], [f32; 2]),
    line: bool,
    seen: u16,
    last: u32,
}

/// An unused map slot (never read: only the first `n` entries are), all zero bytes so that an
/// [`Odometry`] in a `static` goes to `.bss`.
const EMPTY: Entry = Entry {
    v: [0.0; 2],
    alpha: 0.0,
    cov: Sym2 {
        a: 0.0,
        b: 0.0,
        c: 0.0,
    },
    ext: ([0.0; 2], [0.0; 2]),
    line: false,
    seen: 0,
    last: 0,
};

/// One scan's result of [`Odometry::update`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step {
    /// Index of the scan (0 for the first).
    pub scan: u32,
    /// The pose of this scan in the previous scan's frame.
    pub rel: Pose,
    /// Its covariance (x mm, y mm, θ rad).
    pub rel_cov: Cov3,
    /// The pose of this scan in the first scan's frame.
    pub pose: Pose,
    /// Its covariance.
    pub cov: Cov3,
    /// How the registration went ([`Status::Ok`] for the first scan). For
    /// [`Status::None`] the pose is the prediction (its heading corrected by the lines when
    /// they agree, see [`Odometry`]'s module) and the map is kept (the next scan re-localises
    /// against it).
    pub status: Status,
}

/// Feature odometry with a local map of at most `MAP` features.
///
/// ```
/// use pfe_pose::{LineObs, Observation, Odometry, Pose, Status};
/// let walls = [(0.0f32, 3000.0f32), (1.5708, 2000.0), (3.1416, 1500.0), (-1.5708, 2500.0)];
/// let cov = [[1e-6, 0.0], [0.0, 25.0]];
/// let scan_at = |p: Pose| -> Vec<Observation> {
///     let inv = p.inverse();
///     walls.iter().map(|&(a, r)| {
///         let (a, r) = inv.transform_line(a, r);
///         Observation::Line(LineObs::new(a, r, cov))
///     }).collect()
/// };
/// let mut odo = Odometry::<32>::new(Default::default());
/// odo.update(&scan_at(Pose::IDENTITY), None);
/// odo.update(&scan_at(Pose::new(200.0, 0.0, 0.1)), None);
/// let step = odo.update(&scan_at(Pose::new(400.0, 50.0, 0.2)), None);
/// assert_eq!(step.status, Status::Ok);
/// assert!((step.pose.x - 400.0).abs() < 5.0 && (step.pose.theta - 0.2).abs() < 1e-3);
/// ```
#[derive(Clone, Debug)]
pub struct Odometry<const MAP: usize, const PTS: usize = 0> {
    cfg: ConfigSlot,
    map: [Entry; MAP],
    n: usize,
    pose: Pose,
    cov: Cov3,
    last_rel: Pose,
    scans: u32,
    /// The previous scan's features.
    last: Set,
    /// The previous scan's ranges (empty when it came without: [`Odometry::update_scan`]).
    pts: RangeScan<PTS>,
    /// The key scan's ranges (empty without points) and its pose: each scan's pose is refined
    /// against them ([`crate::points::refine_on_key`]).
    key: RangeScan<PTS>,
    key_pose: Pose,
}

/// The settings of an [`Odometry`]: the default ones as a tag only, so that a new odometry
/// with them is all zero bytes (a `static` of it goes to `.bss`, not copied from flash).
#[derive(Clone, Copy, Debug)]
#[repr(u8)]
enum ConfigSlot {
    Default = 0,
    Custom(Config) = 1,
}

impl ConfigSlot {
    fn get(&self) -> Config {
        match self {
            ConfigSlot::Default => Config::DEFAULT,
            ConfigSlot::Custom(c) => *c,
        }
    }
}

/// A map of this many features is what `pfe odometry` and the firmware use
/// ([`FeatureOdometry`]).
pub const ODOMETRY_MAP: usize = 64;

/// The feature odometry of `pfe odometry` and of the firmware: a local map of
/// [`ODOMETRY_MAP`] features and the default [`Config`]; feed it with
/// [`Odometry::update_features`].
pub type FeatureOdometry = Odometry<ODOMETRY_MAP>;

/// [`FeatureOdometry`] that also keeps the previous scan's and a key scan's ranges
/// ([`SCAN_BEAMS`] u16 each, 1 444 bytes more), so that [`Odometry::update_scan`] verifies and
/// completes the registration by the scans' points and refines each pose against the key scan
/// ([`crate::points`]): `pfe odometry --points` and the pose benchmark.
/// (The firmware runs [`FeatureOdometry`]: without the ranges [`Odometry::update_scan`] is
/// [`Odometry::update_features`].)
pub type PointOdometry = Odometry<ODOMETRY_MAP, SCAN_BEAMS>;

impl<const MAP: usize, const PTS: usize> Default for Odometry<MAP, PTS> {
    fn default() -> Self {
        Self::new_default()
    }
}

impl<const MAP: usize, const PTS: usize> Odometry<MAP, PTS> {
    /// An odometry that has seen no scan, with registration settings `cfg`.
    pub const fn new(cfg: Config) -> Self {
        Self::with_slot(ConfigSlot::Custom(cfg))
    }

    /// An odometry that has seen no scan, with the default settings ([`Config::DEFAULT`]);
    /// all zero bytes, so a `static` of it takes no flash.
    ///
    /// ```
    /// use pfe_pose::{FeatureOdometry, Status};
    /// static ODOMETRY: FeatureOdometry = FeatureOdometry::new_default(); // in .bss
    /// let mut odo = FeatureOdometry::new_default();
    /// assert_eq!(odo.update_features(&[], None).status, Status::Ok); // the first scan
    /// ```
    pub const fn new_default() -> Self {
        Self::with_slot(ConfigSlot::Default)
    }

    const fn with_slot(cfg: ConfigSlot) -> Self {
        Self {
            cfg,
            map: [EMPTY; MAP],
            n: 0,
            pose: Pose::IDENTITY,
            cov: ZERO3,
            last_rel: Pose::IDENTITY,
            scans: 0,
            last: Set::new(),
            pts: RangeScan::new(),
            key: RangeScan::new(),
            key_pose: Pose::IDENTITY,
        }
    }

    /// Forgets every scan.
    pub fn reset(&mut self) {
        self.n = 0;
        self.pose = Pose::IDENTITY;
        self.cov = ZERO3;
        self.last_rel = Pose::IDENTITY;
        self.scans = 0;
        self.pts.clear();
        self.key.clear();
    }

    /// The latest pose in the first scan's frame and its covariance.
    pub fn pose(&self) -> (Pose, Cov3) {
        (self.pose, self.cov)
    }

    /// The map's features in the odometry frame.
    pub fn map(&self) -> impl Iterator<Item = Observation> + '_ {
        self.map.iter().take(self.n).map(|e| {
            if e.line {
                let (a, r, c) = anchor_to_line(e.alpha, e.v, e.cov);
                let cov = [[c.a, c.b], [c.b, c.c]];
                Observation::Line(LineObs::new(a, r, cov).with_extent(e.ext.0, e.ext.1))
            } else {
                let cov = [[e.cov.a, e.cov.b], [e.cov.b, e.cov.c]];
                Observation::Point(PointObs::new(e.v[0], e.v[1], cov))
            }
        })
    }

    /// Registers the scan's features `obs` against the map and updates it. `motion`: a prior
    /// of this scan's pose in the previous scan's frame with its covariance (wheel odometry),
    /// or `None` (then the last motion, with the configured bounds as its uncertainty).
    pub fn update(&mut self, obs: &[Observation], motion: Option<(Pose, Cov3)>) -> Step {
        let cfg = self.cfg.get();
        let curr = Set::from_obs(obs.iter().copied(), &cfg);
        self.update_set(curr, None, motion, cfg)
    }

    /// [`Odometry::update`] with the scan's pfe-core features: those
    /// [`Observation::from_feature`] accepts, in order (no copy of them is made). This is the
    /// one function `pfe odometry` and the firmware call, so that both give the same pose, bit
    /// for bit, for the same features.
    ///
    /// ```
    /// use pfe_core::{Feature, LineFeature, Point};
    /// use pfe_pose::{FeatureOdometry, Status};
    /// let wall = |rho: f32| Feature::Line(LineFeature::new(
    ///     0, 99, 100, 0.0, rho, 1e-6, 4.0, 0.0, Point::new(rho, -900.0), Point::new(rho, 900.0),
    /// ));
    /// let mut odo = FeatureOdometry::new_default();
    /// odo.update_features(&[wall(2000.0)], None);
    /// let step = odo.update_features(&[wall(1900.0)], None);
    /// assert!(matches!(step.status, Status::None(_))); // one wall cannot place the robot
    /// ```
    pub fn update_features(
        &mut self,
        features: &[pfe_core::Feature],
        motion: Option<(Pose, Cov3)>,
    ) -> Step {
        let cfg = self.cfg.get();
        let curr = Set::from_obs(features.iter().filter_map(Observation::from_feature), &cfg);
        self.update_set(curr, None, motion, cfg)
    }

    /// [`Odometry::update_features`] with the scan's ranges too (mm, NaN: no return; beam `i`
    /// at bearing `geometry.bearing(i)`): the scans' own points then verify the registration
    /// and, when the features cannot register a scan, a point-to-line ICP against the
    /// previous scan takes over ([`crate::points`]). The previous scan's ranges are kept (at
    /// most `PTS` beams, u16 mm: [`PointOdometry`]); with `PTS` = 0 ([`FeatureOdometry`])
    /// this is [`Odometry::update_features`].
    ///
    /// ```
    /// use pfe_core::ScanGeometry;
    /// use pfe_pose::{PointOdometry, Status};
    /// // A room's corner; no features given: the points alone register the 0.2 m step.
    /// let g = ScanGeometry::LMS200_180_050;
    /// let room = |dx: f32| -> Vec<f32> {
    ///     (0..361).map(|i| {
    ///         let (s, c) = g.bearing(i).sin_cos();
    ///         let mut r = f32::INFINITY;
    ///         if c > 1e-6 { r = r.min((3000.0 - dx) / c); }
    ///         if s > 1e-6 { r = r.min(2000.0 / s); }
    ///         if s < -1e-6 { r = r.min(2500.0 / -s); }
    ///         r
    ///     }).collect()
    /// };
    /// let mut odo = Box::new(PointOdometry::new_default());
    /// odo.update_scan(&[], &g, &room(0.0), None);
    /// let step = odo.update_scan(&[], &g, &room(200.0), None);
    /// assert_eq!(step.status, Status::Ok);
    /// assert!((step.pose.x - 200.0).abs() < 5.0);
    /// ```
    pub fn update_scan(
        &mut self,
        features: &[pfe_core::Feature],
        geometry: &pfe_core::ScanGeometry,
        ranges_mm: &[f32],
        motion: Option<(Pose, Cov3)>,
    ) -> Step {
        let cfg = self.cfg.get();
        let curr = Set::from_obs(features.iter().filter_map(Observation::from_feature), &cfg);
        let mut pts = RangeScan::new();
        pts.set(geometry.start_angle, geometry.angle_step, ranges_mm);
        self.update_set(curr, Some(&pts), motion, cfg)
    }

    /// [`Odometry::update`] with the scan's ranges `pts` (see [`Odometry::update_scan`]).
    pub fn update_with_points(
        &mut self,
        obs: &[Observation],
        pts: &RangeScan<PTS>,
        motion: Option<(Pose, Cov3)>,
    ) -> Step {
        let cfg = self.cfg.get();
        let curr = Set::from_obs(obs.iter().copied(), &cfg);
        self.update_set(curr, Some(pts), motion, cfg)
    }

    fn update_set(
        &mut self,
        curr: Set,
        curr_pts: Option<&RangeScan<PTS>>,
        motion: Option<(Pose, Cov3)>,
        cfg: Config,
    ) -> Step {
        let scan = self.scans;
        self.scans = self.scans.saturating_add(1);
        let (old, old_cov, old_last) = (self.pose, self.cov, self.last_rel);
        let mut step = self.update_inner(curr, curr_pts, motion, cfg, scan);
        match curr_pts {
            Some(c) if !c.is_empty() => {
                // A step the points contradict is looked at again from the last motion and
                // no motion; a better answer replaces it and restarts the map from this scan
                // (the features were fused into it at the contradicted pose).
                if let Some(r) = (scan > 0)
                    .then(|| recheck(&self.pts, c, &step.rel, &old_last))
                    .flatten()
                {
                    step.rel = r.pose;
                    step.rel_cov = r.cov;
                    step.status = match r.unobservable {
                        Some(direction) => Status::Degenerate { direction },
                        None => Status::Ok,
                    };
                    step.pose = old.compose(&r.pose);
                    step.cov = compose_covariance(&old, &old_cov, &r.pose, &r.cov);
                    self.pose = step.pose;
                    self.cov = step.cov;
                    self.last_rel = r.pose;
                    let curr = self.last.clone();
                    self.n = 0;
                    self.insert_all(&curr, &Assoc::new(), &step.pose, scan);
                }
                // The pose refined against the key scan's points; the key moves on to this
                // scan when they no longer refine it.
                let keep = !self.key.is_empty()
                    && match refine_on_key(&self.key, &self.key_pose, c, &step.pose) {
                        Some(pose) => {
                            step.pose = pose;
                            step.rel = old.inverse().compose(&pose);
                            self.pose = pose;
                            self.last_rel = step.rel;
                            true
                        }
                        None => false,
                    };
                if !keep {
                    self.key.clone_from(c);
                    self.key_pose = step.pose;
                }
                self.pts.clone_from(c);
            }
            _ => {
                self.pts.clear();
                self.key.clear();
            }
        }
        step
    }

    /// [`Odometry::update_set`] before the scan's ranges replace the previous scan's.
    fn update_inner(
        &mut self,
        curr: Set,
        curr_pts: Option<&RangeScan<PTS>>,
        motion: Option<(Pose, Cov3)>,
        cfg: Config,
        scan: u32,
    ) -> Step {
        // This scan's ranges, when the previous scan's are there too.
        let points = curr_pts.filter(|c| !c.is_empty() && !self.pts.is_empty());
        if scan == 0 {
            self.n = 0;
            self.last = curr.clone();
            self.insert_all(&curr, &Assoc::new(), &Pose::IDENTITY, scan);
            return Step {
                scan,
                rel: Pose::IDENTITY,
                rel_cov: ZERO3,
                pose: Pose::IDENTITY,
                cov: ZERO3,
                status: Status::Ok,
            };
        }
        let motion =
            motion.filter(|(m, c)| m.is_finite() && c.iter().flatten().all(|v| v.is_finite()));
        // Tracking: the motion prior (or the last motion again) refined against the map alone,
        // taken when the map confirms it; otherwise the search below.
        let mut map = Set::new();
        let (mut line_of, mut pt_of) = ([NONE; MAX_OBS], [NONE; MAX_OBS]);
        let mut assoc = Assoc::new();
        if self.n > 0 {
            let (t, r) = TRACK_SIGMA;
            let (guess, guess_cov) = motion.unwrap_or((
                self.last_rel,
                [[t * t, 0.0, 0.0], [0.0, t * t, 0.0], [0.0, 0.0, r * r]],
            ));
            let predicted = self.pose.compose(&guess);
            let (s, c) = sin_cos(-guess.theta);
            let prior_cov =
                crate::geom::sandwich3(&[[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]], &guess_cov);
            self.map_in(&predicted, scan, &mut map, &mut line_of, &mut pt_of);
            let mut reg = register_sets(
                &map,
                &curr,
                Some((Pose::IDENTITY, prior_cov)),
                &cfg,
                &mut assoc,
                false,
            );
            if let (Status::Degenerate { direction }, None) = (reg.status, motion) {
                // Along what the map cannot tell the pose is the last motion again, a guess
                // (the tracking's reach is no statement about the robot): unobservable.
                reg.cov = widen_along(&reg.cov, &direction);
            }
            let agrees = points.is_none_or(|c| {
                agreement(&self.pts, c, &guess.compose(&reg.rel)).score() >= cfg.verify_track
            });
            // With the points, a tracking the map leaves degenerate is not taken: it keeps
            // the last motion along what the map cannot tell, and the pair's search along
            // that direction by the points does better.
            let degenerate = matches!(reg.status, Status::Degenerate { .. });
            if tracked(&reg, &curr, &cfg) && agrees && !(points.is_some() && degenerate) {
                self.last = curr.clone();
                return self.accept(
                    &curr, &predicted, &guess, &reg, &assoc, &line_of, &pt_of, scan,
                );
            }
            assoc = Assoc::new();
        }
        // First against the previous scan (the motion prior, if any, gating it): its result,
        // widened to three standard deviations, gates and starts the registration against the
        // map.
        let mut pair = match points {
            Some(c) => {
                let prev_pts = &self.pts;
                let verify = |rel: &Pose| agreement(prev_pts, c, rel).score();
                let pair = register_sets_verified::<{ crate::register::VERIFIED }>(
                    &self.last,
                    &curr,
                    motion,
                    &cfg,
                    &mut Assoc::new(),
                    true,
                    Some(&verify),
                );
                let start = motion.map_or(self.last_rel, |m| m.0);
                complete(pair, prev_pts, c, Some(start), &cfg)
            }
            None => register_sets(&self.last, &curr, motion, &cfg, &mut Assoc::new(), true),
        };
        if motion.is_none() {
            // What the scene cannot tell (a corridor's length) is the last motion again, not
            // no motion: the pair's estimate does not move along that direction from its
            // starting guess.
            if let Status::Degenerate { direction } = pair.status {
                pair.rel = along_last(&pair.rel, &self.last_rel, &direction);
            }
        }
        let (guess, guess_cov) = match motion {
            _ if pair.is_registered() => {
                let mut c = pair.cov;
                for (i, row) in c.iter_mut().enumerate() {
                    for v in row.iter_mut() {
                        *v *= 9.0;
                    }
                    if let Some(d) = row.get_mut(i) {
                        *d += if i == 2 { 1e-4 } else { 2500.0 };
                    }
                }
                (pair.rel, c)
            }
            Some(m) => m,
            None => {
                let (t, r) = (cfg.max_translation, cfg.max_rotation);
                (
                    self.last_rel,
                    [[t * t, 0.0, 0.0], [0.0, t * t, 0.0], [0.0, 0.0, r * r]],
                )
            }
        };
        self.last = curr.clone();
        let predicted = self.pose.compose(&guess);
        // The guess's covariance in the predicted pose's axes.
        let (s, c) = sin_cos(-guess.theta);
        let prior_cov =
            crate::geom::sandwich3(&[[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]], &guess_cov);
        // The map, in the predicted pose's frame, as the "previous scan".
        self.map_in(&predicted, scan, &mut map, &mut line_of, &mut pt_of);
        let reg = register_sets(
            &map,
            &curr,
            Some((Pose::IDENTITY, prior_cov)),
            &cfg,
            &mut assoc,
            // The pair's registration is a good guess: refine it against the map; search
            // only without one.
            !pair.is_registered(),
        );
        let old = self.pose;
        // The map's answer must agree with the pair's (χ²₃ 99.9 %): otherwise a map feature
        // was matched wrongly, and the pair's answer is kept.
        let disagree = pair.is_registered() && reg.is_registered() && {
            let (s, c) = sin_cos(-guess.theta);
            let rot = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]];
            let both = crate::geom::add3(&crate::geom::sandwich3(&rot, &pair.cov), &reg.cov);
            let d = [reg.rel.x, reg.rel.y, reg.rel.theta];
            match crate::geom::inverse_spd3(&both) {
                Some(info) => {
                    let mut q = 0.0;
                    for i in 0..3 {
                        for j in 0..3 {
                            q += d[i] * info[i][j] * d[j];
                        }
                    }
                    !(q < 16.27)
                }
                None => false,
            }
        };
        // Found by a search against the map alone (the pair failed): taken only when the map
        // determines every direction, a degenerate one from such a wide search is a guess.
        let map_only_degenerate =
            !pair.is_registered() && matches!(reg.status, Status::Degenerate { .. });
        if !reg.is_registered() || disagree || map_only_degenerate {
            // Not against the map: take the pair's registration (or the prediction) and
            // restart the map from this scan.
            let (mut rel, mut rel_cov, status) = if pair.is_registered() {
                (pair.rel, pair.cov, pair.status)
            } else if map_only_degenerate {
                (guess, guess_cov, Status::None(crate::Failure::NoConsensus))
            } else {
                (guess, guess_cov, reg.status)
            };
            if !pair.is_registered() && motion.is_none() {
                // Not registered: the last motion again, its heading corrected by the
                // directions of the lines, which the map (in the predicted pose's frame)
                // and the scan share.
                // With the scans' points, the turn is taken only when they agree with it at
                // least as well as with the last motion.
                let turn = heading(&map, &curr).filter(|(d, _)| {
                    points.is_none_or(|c| {
                        let turned = guess.compose(&Pose::new(0.0, 0.0, *d));
                        agreement(&self.pts, c, &turned).score()
                            >= agreement(&self.pts, c, &guess).score()
                    })
                });
                if let Some((d, var)) = turn {
                    rel = guess.compose(&Pose::new(0.0, 0.0, d));
                    rel_cov[2][2] = var;
                    for i in 0..2 {
                        rel_cov[i][2] = 0.0;
                        rel_cov[2][i] = 0.0;
                    }
                }
            }
            self.cov = compose_covariance(&old, &self.cov, &rel, &rel_cov);
            self.pose = old.compose(&rel);
            self.last_rel = rel;
            if pair.is_registered() {
                self.n = 0;
                self.insert_all(&curr, &Assoc::new(), &self.pose.clone(), scan);
            }
            return Step {
                scan,
                rel,
                rel_cov,
                pose: self.pose,
                cov: self.cov,
                status,
            };
        }
        self.accept(
            &curr, &predicted, &guess, &reg, &assoc, &line_of, &pt_of, scan,
        )
    }

    /// Takes the registration `reg` of `curr` against the map (in the frame of `predicted`,
    /// `guess` after the last pose; `assoc` its matches, `line_of` and `pt_of` the map index
    /// of each of the map set's features) and updates the map.
    #[allow(clippy::too_many_arguments)]
    fn accept(
        &mut self,
        curr: &Set,
        predicted: &Pose,
        guess: &Pose,
        reg: &crate::Registration,
        assoc: &Assoc,
        line_of: &[u8; MAX_OBS],
        pt_of: &[u8; MAX_OBS],
        scan: u32,
    ) -> Step {
        let old = self.pose;
        let new = predicted.compose(&reg.rel);
        let rel = old.inverse().compose(&new);
        // The registration's covariance is in the predicted pose's axes: turn it into the
        // previous scan's.
        let (s, c) = sin_cos(guess.theta);
        let rot = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]];
        let rel_cov = crate::geom::sandwich3(&rot, &reg.cov);
        self.cov = compose_covariance(&old, &self.cov, &rel, &rel_cov);
        self.pose = new;
        self.last_rel = rel;
        // Map ids of the matches.
        let mut ids = Assoc::new();
        for (slot, m) in ids.lines.iter_mut().zip(&assoc.lines) {
            *slot = line_of.get(usize::from(*m)).copied().unwrap_or(NONE);
        }
        for (slot, m) in ids.pts.iter_mut().zip(&assoc.pts) {
            *slot = pt_of.get(usize::from(*m)).copied().unwrap_or(NONE);
        }
        self.insert_all(curr, &ids, &new, scan);
        Step {
            scan,
            rel,
            rel_cov,
            pose: new,
            cov: self.cov,
            status: reg.status,
        }
    }

    /// The map in the frame of `predicted`, as the "previous scan" of a registration, with the
    /// map index of each of its lines and points.
    fn map_in(
        &self,
        predicted: &Pose,
        scan: u32,
        map: &mut Set,
        line_of: &mut [u8; MAX_OBS],
        pt_of: &mut [u8; MAX_OBS],
    ) {
        let to_local = predicted.inverse();
        let (ls, lc) = sin_cos(-predicted.theta);
        // `to_local.transform_point` with its sine and cosine once.
        let local = |p: [f32; 2]| {
            [
                lc * p[0] - ls * p[1] + to_local.x,
                ls * p[0] + lc * p[1] + to_local.y,
            ]
        };
        map.clear();
        *line_of = [NONE; MAX_OBS];
        *pt_of = [NONE; MAX_OBS];
        let (mut nl, mut np) = (0usize, 0usize);
        for (i, e) in self.map.iter().take(self.n).enumerate() {
            let Ok(iu) = u8::try_from(i) else { break };
            let age = scan.saturating_sub(e.last) as f32;
            if e.line {
                let ext = e.ext.0.iter().chain(&e.ext.1).all(|v| v.is_finite());
                let ext = ext.then_some(e.ext);
                let len = ext.map_or(0.0, |(s, t)| crate::geom::hypot(t[0] - s[0], t[1] - s[1]));
                let ext = ext.map(|(s, t)| (local(s), local(t)));
                let (a, r, cov) = anchor_to_line(e.alpha - predicted.theta, local(e.v), e.cov);
                if map.push_line(a, r, cov, ext, len / (1.0 + age), None) {
                    if let Some(s) = line_of.get_mut(nl) {
                        *s = iu;
                    }
                    nl += 1;
                }
            } else if map.push_pt(local(e.v), e.cov.rotate(ls, lc), 1.0 / (1.0 + age), None) {
                if let Some(s) = pt_of.get_mut(np) {
                    *s = iu;
                }
                np += 1;
            }
        }
    }

    /// Fuses the matched features of `curr` (seen from `pose`) into their map entries and adds
    /// the others.
    fn insert_all(&mut self, curr: &Set, ids: &Assoc, pose: &Pose, scan: u32) {
        let at = pose.transformer();
        for (k, l) in curr.lines().iter().enumerate() {
            let (sa, ca) = sin_cos(l.a);
            // Anchor at the segment's middle (the foot of the normal without extent).
            let mid = match l.ext {
                Some((s, e)) => -sa * 0.5 * (s[0] + e[0]) + ca * 0.5 * (s[1] + e[1]),
                None => 0.0,
            };
            let anchor = [l.r * ca - mid * sa, l.r * sa + mid * ca];
            let cov = Sym2 {
                a: l.cov.a,
                b: l.cov.b - mid * l.cov.a,
                c: l.cov.c - 2.0 * mid * l.cov.b + mid * mid * l.cov.a,
            };
            let ext = match l.ext {
                Some((s, e)) => (at(s), at(e)),
                None => ([f32::NAN; 2], [f32::NAN; 2]),
            };
            let id = ids.lines.get(k).copied().unwrap_or(NONE);
            let new = Entry {
                v: at(anchor),
                alpha: wrap(l.a + pose.theta),
                cov,
                ext,
                line: true,
                seen: 1,
                last: scan,
            };
            match self.map.get_mut(usize::from(id)).filter(|_| id != NONE) {
                Some(e) if e.line && usize::from(id) < self.n => fuse_line(e, &new),
                _ => self.add(new),
            }
        }
        for (k, p) in curr.pts().iter().enumerate() {
            let (s, c) = sin_cos(pose.theta);
            let new = Entry {
                v: at(p.p),
                alpha: 0.0,
                cov: p.cov.rotate(s, c),
                ext: ([f32::NAN; 2], [f32::NAN; 2]),
                line: false,
                seen: 1,
                last: scan,
            };
            let id = ids.pts.get(k).copied().unwrap_or(NONE);
            match self.map.get_mut(usize::from(id)).filter(|_| id != NONE) {
                Some(e) if !e.line && usize::from(id) < self.n => fuse_2(e, &new),
                _ => self.add(new),
            }
        }
    }

    /// Adds `e`, replacing the entry seen least recently (then least often) when full.
    fn add(&mut self, e: Entry) {
        if let Some(slot) = self.map.get_mut(self.n) {
            *slot = e;
            self.n += 1;
            return;
        }
        let n = self.n;
        if let Some(victim) = self
            .map
            .iter_mut()
            .take(n)
            .filter(|v| v.last < e.last)
            .min_by_key(|v| (v.last, v.seen))
        {
            *victim = e;
        }
    }
}

/// Standard deviation of the last motion as a guess of the next (mm, rad) when tracking
/// without a motion prior: the refinement's reach (its first gates are about three times
/// its slack), not a statement about the robot.
const TRACK_SIGMA: (f32, f32) = (250.0, 0.1);

/// A tracking registration is taken when it registered (a degenerate one keeps the
/// prediction along what it cannot tell) and at least half of the scan's features (and the
/// configured least number) agree with the map.
fn tracked(reg: &crate::Registration, curr: &Set, cfg: &Config) -> bool {
    let matched = usize::from(reg.matches.0) + usize::from(reg.matches.1);
    matches!(reg.status, Status::Ok | Status::Degenerate { .. })
        && matched >= cfg.min_matches
        && 2 * matched >= curr.len()
}

/// `cov` (x mm, y mm, θ rad) with [`UNOBSERVABLE_VARIANCE`] added along the unit `direction`
/// (x mm, y mm, θ·[`ROTATION_SCALE`]).
fn widen_along(cov: &Cov3, direction: &[f32; 3]) -> Cov3 {
    let d = [direction[0], direction[1], direction[2] / ROTATION_SCALE];
    let mut c = *cov;
    for (row, di) in c.iter_mut().zip(&d) {
        for (v, dj) in row.iter_mut().zip(&d) {
            *v += UNOBSERVABLE_VARIANCE * di * dj;
        }
    }
    if c.iter().flatten().all(|v| v.is_finite()) {
        c
    } else {
        *cov
    }
}

/// Widest heading correction [`heading`] looks for, rad.
const HEADING_GATE: f32 = 0.6;
/// Lines whose heading corrections differ by less than this agree, rad.
const HEADING_AGREE: f32 = 0.026;

/// The rotation that turns the lines of `curr` onto those of `prev` (two scans or a scan and
/// the map, near the same pose; rotation about the scanner) and its variance, rad and rad²:
/// each of the longest 32 lines of `curr` votes for the angle to the line of `prev` nearest in
/// direction (within [`HEADING_GATE`]), weighted by its length; the vote most lines agree with
/// (within [`HEADING_AGREE`]) wins. `None` unless two lines agree. Ranges are not compared:
/// the translation may be far off.
#[inline(never)]
fn heading(prev: &Set, curr: &Set) -> Option<(f32, f32)> {
    let (top, n) = crate::set::top_k::<32>(curr.lines().iter().map(|l| l.rank));
    // (correction, weight, variance)
    let mut votes = [(0.0f32, 0.0f32, 0.0f32); 32];
    let mut nv = 0usize;
    for &k in top.iter().take(n) {
        let Some(lk) = curr.lines().get(usize::from(k)) else {
            continue;
        };
        let mut nearest: Option<(f32, f32)> = None;
        for li in prev.lines() {
            let d = wrap(li.a - lk.a);
            if d.abs() < HEADING_GATE && nearest.is_none_or(|(b, _)| d.abs() < b.abs()) {
                nearest = Some((d, li.cov.a + lk.cov.a));
            }
        }
        if let (Some((d, v)), Some(slot)) = (nearest, votes.get_mut(nv)) {
            *slot = (d, lk.rank.max(1.0), v);
            nv += 1;
        }
    }
    let votes = votes.get(..nv).unwrap_or(&[]);
    let support = |c: f32| -> (f32, usize) {
        votes
            .iter()
            .filter(|v| (v.0 - c).abs() < HEADING_AGREE)
            .fold((0.0, 0), |(w, n), v| (w + v.1, n + 1))
    };
    let mut best: Option<(f32, f32)> = None;
    for v in votes {
        let (w, _) = support(v.0);
        if best.is_none_or(|(_, bw)| w > bw) {
            best = Some((v.0, w));
        }
    }
    let (centre, _) = best?;
    let (count, _) = (support(centre).1, ());
    if count < 2 {
        return None;
    }
    // Information-weighted mean of the agreeing votes; the variance also covers their scatter.
    let (mut sw, mut swd) = (0.0f32, 0.0f32);
    for v in votes
        .iter()
        .filter(|v| (v.0 - centre).abs() < HEADING_AGREE)
    {
        let w = 1.0 / v.2.max(1e-8);
        sw += w;
        swd += w * v.0;
    }
    let d = swd / sw;
    let mut spread = 0.0f32;
    for v in votes
        .iter()
        .filter(|v| (v.0 - centre).abs() < HEADING_AGREE)
    {
        spread += (v.0 - d) * (v.0 - d);
    }
    let var = (1.0 / sw + spread / count as f32).max(HEADING_AGREE * HEADING_AGREE / 4.0);
    (d.is_finite() && var.is_finite()).then_some((d, var))
}

/// `pose` moved along the unit `direction` (x mm, y mm, θ·[`ROTATION_SCALE`]) to where
/// `last` lies along it.
fn along_last(pose: &Pose, last: &Pose, direction: &[f32; 3]) -> Pose {
    let d = [
        last.x - pose.x,
        last.y - pose.y,
        wrap(last.theta - pose.theta) * ROTATION_SCALE,
    ];
    let c = d[0] * direction[0] + d[1] * direction[1] + d[2] * direction[2];
    let moved = Pose::new(
        pose.x + c * direction[0],
        pose.y + c * direction[1],
        pose.theta + c * direction[2] / ROTATION_SCALE,
    );
    if moved.is_finite() {
        moved
    } else {
        *pose
    }
}

/// The line through `anchor` with normal angle `alpha` and covariance `cov` of (α, d) as
/// (α, ρ) with ρ ≥ 0 and the covariance of (α, ρ), in the frame the anchor is given in.
fn anchor_to_line(alpha: f32, anchor: [f32; 2], cov: Sym2) -> (f32, f32, Sym2) {
    let (sa, ca) = sin_cos(alpha);
    let rho = ca * anchor[0] + sa * anchor[1];
    // Along-line position of the anchor from the normal's foot: δρ = d + s δα.
    let s = -sa * anchor[0] + ca * anchor[1];
    let c = Sym2 {
        a: cov.a,
        b: cov.b + s * cov.a,
        c: cov.c + 2.0 * s * cov.b + s * s * cov.a,
    };
    if rho < 0.0 {
        (
            wrap(alpha + PI),
            -rho,
            Sym2 {
                a: c.a,
                b: -c.b,
                c: c.c,
            },
        )
    } else {
        (wrap(alpha), rho, c)
    }
}

/// Fuses the observation `o` of a line into the map entry `e` (same line), both anchored.
fn fuse_line(e: &mut Entry, o: &Entry) {
    let mut o = *o;
    if crate::geom::sin_cos(o.alpha - e.alpha).1 < 0.0 {
        // The same line with the opposite normal: d and cov(α, d) change sign.
        o.alpha = wrap(o.alpha + PI);
        o.cov.b = -o.cov.b;
    }
    let (so, co) = sin_cos(o.alpha);
    // The observation re-anchored at the entry's anchor: d(s) = d − s δα.
    let s = -so * (e.v[0] - o.v[0]) + co * (e.v[1] - o.v[1]);
    let d = co * (o.v[0] - e.v[0]) + so * (o.v[1] - e.v[1]);
    let r = Sym2 {
        a: o.cov.a,
        b: o.cov.b - s * o.cov.a,
        c: o.cov.c - 2.0 * s * o.cov.b + s * s * o.cov.a,
    };
    let mut state = Entry {
        v: [0.0, 0.0],
        ..*e
    };
    let z = Entry {
        v: [wrap(o.alpha - e.alpha), d],
        cov: r,
        ..o
    };
    fuse_2(&mut state, &z);
    let (se, ce) = sin_cos(e.alpha);
    let anchor = [e.v[0] + state.v[1] * ce, e.v[1] + state.v[1] * se];
    let alpha = wrap(e.alpha + state.v[0]);
    // Extent: the union of both segments along the fused line.
    let (sa, ca) = sin_cos(alpha);
    let ends = [e.ext.0, e.ext.1, o.ext.0, o.ext.1];
    let mut lo = f32::INFINITY;
    let mut hi = f32::NEG_INFINITY;
    for p in ends.iter().filter(|p| p[0].is_finite() && p[1].is_finite()) {
        let t = -sa * (p[0] - anchor[0]) + ca * (p[1] - anchor[1]);
        lo = lo.min(t);
        hi = hi.max(t);
    }
    if lo <= hi {
        e.ext = (
            [anchor[0] - sa * lo, anchor[1] + ca * lo],
            [anchor[0] - sa * hi, anchor[1] + ca * hi],
        );
    }
    if anchor[0].is_finite() && anchor[1].is_finite() && alpha.is_finite() {
        e.v = anchor;
        e.alpha = alpha;
        e.cov = state.cov;
    }
    e.seen = state.seen;
    e.last = state.last;
}

/// Information-weighted fusion of the 2-vector of `o` into `e`.
fn fuse_2(e: &mut Entry, o: &Entry) {
    let s = e.cov.add(o.cov);
    let Some(si) = s.inverse() else { return };
    // K = P_e S⁻¹.
    let p = e.cov;
    let k = [
        [p.a * si.a + p.b * si.b, p.a * si.b + p.b * si.c],
        [p.b * si.a + p.c * si.b, p.b * si.b + p.c * si.c],
    ];
    let d = [o.v[0] - e.v[0], o.v[1] - e.v[1]];
    let v = [
        e.v[0] + k[0][0] * d[0] + k[0][1] * d[1],
        e.v[1] + k[1][0] * d[0] + k[1][1] * d[1],
    ];
    // P = (I − K) P_e.
    let cov = Sym2 {
        a: (1.0 - k[0][0]) * p.a - k[0][1] * p.b,
        b: (1.0 - k[0][0]) * p.b - k[0][1] * p.c,
        c: -k[1][0] * p.b + (1.0 - k[1][1]) * p.c,
    };
    if v[0].is_finite() && v[1].is_finite() && cov.finite() && cov.a > 0.0 && cov.c > 0.0 {
        e.v = v;
        e.cov = cov;
    }
    e.seen = e.seen.saturating_add(1);
    e.last = e.last.max(o.last);
}

#[cfg(test)]
mod tests {
    use super::*;

    const COV: [[f32; 2]; 2] = [[1e-6, 0.0], [0.0, 25.0]];

    /// The lines (α, ρ) of the odometry frame as seen from `pose`.
    fn seen_from<const N: usize>(walls: &[(f32, f32); N], pose: Pose) -> [Observation; N] {
        let inv = pose.inverse();
        walls.map(|(a, r)| {
            let (a, r) = inv.transform_line(a, r);
            Observation::Line(LineObs::new(a, r, COV))
        })
    }

    /// A scan that nothing registers (no features) keeps the map: the next scan re-localises
    /// against it (the map used to restart from the empty scan, and the next scan had nothing
    /// to register against).
    #[test]
    fn map_kept_through_a_scan_without_features() {
        let walls = [
            (0.0f32, 3000.0f32),
            (core::f32::consts::FRAC_PI_2, 2000.0),
            (core::f32::consts::PI, 1500.0),
            (-core::f32::consts::FRAC_PI_2, 2500.0),
        ];
        let mut odo = Odometry::<32>::new(Config::default());
        odo.update(&seen_from(&walls, Pose::IDENTITY), None);
        odo.update(&seen_from(&walls, Pose::new(200.0, 0.0, 0.05)), None);
        let lost = odo.update(&[], None);
        assert!(matches!(lost.status, Status::None(_)), "{:?}", lost.status);
        let truth = Pose::new(600.0, 0.0, 0.15);
        let step = odo.update(&seen_from(&walls, truth), None);
        assert_eq!(step.status, Status::Ok);
        let e = crate::geom::hypot(step.pose.x - truth.x, step.pose.y - truth.y);
        assert!(e < 5.0, "{:?}", step.pose);
        assert!(
            (step.pose.theta - truth.theta).abs() < 1e-3,
            "{:?}",
            step.pose
        );
    }

    /// A scan that cannot be registered (two parallel walls after a room's four) still tells
    /// the heading: the last motion again, turned by what its lines say, with the heading's
    /// variance measured and the translation's the motion bounds.
    #[test]
    fn heading_from_the_lines_of_an_unregistered_scan() {
        let walls = [
            (0.0f32, 3000.0f32),
            (core::f32::consts::FRAC_PI_2, 2000.0),
            (core::f32::consts::PI, 1500.0),
            (-core::f32::consts::FRAC_PI_2, 2500.0),
        ];
        let mut odo = Odometry::<32>::new(Config::default());
        odo.update(&seen_from(&walls, Pose::IDENTITY), None);
        odo.update(&seen_from(&walls, Pose::new(200.0, 0.0, 0.0)), None);
        let truth = Pose::new(400.0, 0.0, 0.15);
        let [_, left, _, right] = seen_from(&walls, truth);
        let step = odo.update(&[left, right], None);
        assert!(matches!(step.status, Status::None(_)), "{:?}", step.status);
        assert!(
            (step.pose.theta - truth.theta).abs() < 0.005,
            "{:?}",
            step.pose
        );
        assert!(step.rel_cov[2][2] < 0.02 * 0.02, "{:?}", step.rel_cov);
        assert!(step.rel_cov[0][0] >= 1e6, "{:?}", step.rel_cov);
    }

    /// Down a corridor whose end wall has gone out of sight, the scene tells nothing along it:
    /// the odometry keeps the last motion along it (it used to take "no motion") and says
    /// degenerate, with the unobservable variance along the corridor: with two walls through
    /// the pair's registration (the first scan without the end is not registered), with three
    /// through the tracking against the map.
    #[test]
    fn corridor_keeps_the_last_motion_along_it() {
        use core::f32::consts::FRAC_PI_2;
        corridor([(FRAC_PI_2, 1500.0), (-FRAC_PI_2, 1500.0)], false);
        corridor(
            [
                (FRAC_PI_2, 1500.0),
                (-FRAC_PI_2, 1500.0),
                (FRAC_PI_2, 3000.0),
            ],
            true,
        );
    }

    fn corridor<const N: usize>(side: [(f32, f32); N], tracked: bool) {
        let mut odo = Odometry::<32>::new(Config::default());
        for k in 0..3 {
            // The end wall and a pillar near it fix the position along the corridor (two
            // features: the direction is confirmed).
            let pose = Pose::new(300.0 * k as f32, 0.0, 0.0);
            let [end] = seen_from(&[(0.0, 6000.0)], pose);
            let p = pose.inverse().transform_point([5000.0, 1000.0]);
            let pillar = Observation::Point(PointObs::new(p[0], p[1], [[25.0, 0.0], [0.0, 25.0]]));
            let walls = seen_from(&side, pose);
            let mut obs = [end; 8];
            for (o, s) in obs.iter_mut().zip(walls.iter().chain([&end, &pillar])) {
                *o = *s;
            }
            let step = odo.update(obs.get(..N + 2).unwrap_or(&[]), None);
            assert_eq!(step.status, Status::Ok, "{N} walls, scan {k}");
        }
        for k in 3..8 {
            let truth = Pose::new(300.0 * k as f32, 0.0, 0.0);
            let step = odo.update(&seen_from(&side, truth), None);
            // With two walls, scan 3, the first without the end, is not registered (its two
            // walls against the previous scan's four features: too few matches, and not a
            // corridor on both sides): the prediction, the last motion again.
            let expected = match step.status {
                Status::Degenerate { direction } => (tracked || k > 3) && direction[0].abs() > 0.99,
                Status::None(_) => !tracked && k == 3,
                Status::Ok => false,
            };
            assert!(expected, "{N} walls, scan {k}: {:?}", step.status);
            assert!((step.rel.x - 300.0).abs() < 1.0, "scan {k}: {:?}", step.rel);
            assert!(
                (step.pose.x - truth.x).abs() < 5.0,
                "scan {k}: {:?}",
                step.pose
            );
            assert!(
                step.pose.y.abs() < 5.0 && step.pose.theta.abs() < 1e-3,
                "{:?}",
                step.pose
            );
            // Unobservable along the corridor (the last motion is a guess, not a measurement);
            // the scan without any registration has the motion bounds as its covariance.
            let along = if matches!(step.status, Status::None(_)) {
                1e6
            } else {
                1e11
            };
            assert!(
                step.rel_cov[0][0] >= along,
                "{N} walls, scan {k}: {:?}",
                step.rel_cov
            );
        }
    }
}
