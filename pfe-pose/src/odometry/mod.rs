//! Feature odometry: every scan's pose in the frame of the first, registered against a small
//! local map of features rather than only against the previous scan.
//!
//! Each scan is first **tracked**: the motion prior (or, without one, the last motion again)
//! predicts its pose, and Gauss–Newton refines that against the map alone (no search). The
//! result is taken when at least half of the scan's features agree with the map; a direction
//! the map cannot tell (a corridor's length) then keeps the prediction, with the prior's
//! variance along it, or without a prior [`crate::UNOBSERVABLE_VARIANCE`] (the last motion
//! again is a guess, not a measurement). Otherwise the scan is registered
//! against the previous scan ([`crate::register()`], gated by the motion prior when one is
//! given); without a prior, a direction that pair cannot tell takes the last motion's value
//! (not "no motion"). That result, widened to three standard deviations, starts the
//! refinement against the map. The map: at
//! most `MAP` features (lines and points) in the odometry frame, taken into the predicted
//! pose's frame for the registration. Matched
//! features are fused into their map feature (information-weighted, the segment's extent the
//! union), unmatched ones are added, and when the map is full the one seen least recently
//! (then least often) is replaced. When the map cannot register the scan, or its answer
//! disagrees with the pair's beyond both covariances (χ²₃ 99.9 %: a wrong map match), the
//! pair's result is taken and the map restarts from this scan; so too, without a motion
//! prior, when the pair cannot tell a direction (it would be a prior without information
//! along it). When the pair did not register
//! either, the map is searched from the last motion; an answer that leaves a direction
//! undetermined is refused (from so wide a search it is a guess), and so is, with the scans'
//! points, one they agree with less than [`Config::verify_accept`]; then the scan is not
//! registered ([`Status::None`]): its pose is the prediction (the last motion again, turned by
//! the heading the directions of its lines and the map's agree on, when at least two do) and
//! the map is **kept**, so that the next scan re-localises against it. With the scans'
//! points, a bridge they support (no motion, or any heading, refined by their ICP:
//! [`crate::points::bridge`]) replaces the prediction, still [`Status::None`], with a
//! covariance as wide as its distance from the last motion; the next scan is still predicted
//! by the last motion.
//!
//! Lines are kept as a normal angle and an anchor point near the segment's middle, with the
//! covariance of (angle, normal offset at the anchor): (α, ρ) about an origin far away would
//! be nearly singular in f32.
//!
//! Covariance: the relative motion's covariance is the registration's against the map; the
//! pose's covariance chains those (`compose_covariance`), which ignores what the map's
//! memory saves: it bounds the error from above.

mod map;
mod points;
#[cfg(test)]
mod tests;
mod track;

use crate::geom::{Cov3, Pose, ZERO3};
use crate::obs::{LineObs, Observation, PointObs};
use crate::points::{RangeScan, SCAN_BEAMS};
use crate::register::{Config, Status};
use crate::set::Set;
use map::{anchor_to_line, Entry, EMPTY};

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
    /// The key scan before the last one (empty: none to go back to), its pose, the pose the
    /// motion before the key moved predicts for the current scan, that motion, and the scans
    /// since the key moved ([`crate::points::back_to_key`]).
    back: RangeScan<PTS>,
    back_pose: Pose,
    back_guess: Pose,
    back_motion: Pose,
    back_age: u8,
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
            back: RangeScan::new(),
            back_pose: Pose::IDENTITY,
            back_guess: Pose::IDENTITY,
            back_motion: Pose::IDENTITY,
            back_age: 0,
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
        self.back.clear();
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
}
