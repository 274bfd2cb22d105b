//! The pose step: pfe-pose's feature odometry on each scan's features, as the frame's pose
//! block.
//!
//! [`PoseStep`] holds a [`FeatureOdometry`] (a local map of 64 features and the last scan's features, 7.7 KiB, all zero
//! when new so that it lives in `.bss` inside the `App`'s `static`) and calls
//! [`FeatureOdometry::update_features`], the same call `pfe odometry` makes: for the same
//! features, in the same order, the board's pose is the host's, bit for bit.

use pfe_core::Feature;
use pfe_frame::{PoseBlock, PoseCov, PoseFailure, PoseStatus};
use pfe_pose::{Cov3, Failure, FeatureOdometry, Pose, Status, Step};

/// The firmware's pose step: every scan's pose in the first scan's frame, registered against
/// a local map, without a motion prior.
///
/// ```
/// use firmware::app::PoseStep;
/// use pfe_frame::PoseStatus;
/// let mut pose = PoseStep::new();
/// let first = pose.update(&[]);
/// assert_eq!(first.status, PoseStatus::Ok); // the first scan defines the frame
/// assert_eq!((first.pose.x, first.pose.y, first.pose.theta), (0.0, 0.0, 0.0));
/// assert!(matches!(pose.update(&[]).status, PoseStatus::None(_))); // nothing to register
/// ```
#[derive(Clone, Debug, Default)]
pub struct PoseStep {
    odometry: FeatureOdometry,
}

impl PoseStep {
    /// A pose step that has seen no scan (`const`, all zero bytes).
    pub const fn new() -> Self {
        Self {
            odometry: FeatureOdometry::new_default(),
        }
    }

    /// Forgets every scan: the next one is the first (its frame the odometry's).
    pub fn reset(&mut self) {
        self.odometry.reset();
    }

    /// Registers the scan's `features` and returns its pose block. Never inlined: its stack
    /// (about 15 KiB: feature sets and per-match information) is taken only while it runs,
    /// not by every caller's frame (with the pose step off, the pipeline's stack stays the
    /// extraction's).
    #[inline(never)]
    pub fn update(&mut self, features: &[Feature]) -> PoseBlock {
        pose_block(&self.odometry.update_features(features, None))
    }

    /// The odometry (its map and latest pose).
    pub fn odometry(&self) -> &FeatureOdometry {
        &self.odometry
    }
}

/// pfe-pose's result for one scan as the frame's pose block (values bit for bit).
pub fn pose_block(step: &Step) -> PoseBlock {
    PoseBlock {
        rel: pose_cov(&step.rel, &step.rel_cov),
        pose: pose_cov(&step.pose, &step.cov),
        status: match step.status {
            Status::Ok => PoseStatus::Ok,
            Status::Degenerate { direction } => PoseStatus::Degenerate { direction },
            Status::None(f) => PoseStatus::None(match f {
                Failure::TooFewFeatures => PoseFailure::TooFewFeatures,
                Failure::NoHypothesis => PoseFailure::NoHypothesis,
                Failure::NoConsensus => PoseFailure::NoConsensus,
                Failure::Ambiguous => PoseFailure::Ambiguous,
                Failure::InvalidPrior => PoseFailure::InvalidPrior,
                _ => PoseFailure::Other,
            }),
        },
    }
}

fn pose_cov(p: &Pose, c: &Cov3) -> PoseCov {
    PoseCov {
        x: p.x,
        y: p.y,
        theta: p.theta,
        cov: *c,
    }
}
