//! The step with the scan's ranges: the points check the features' registration and refine
//! the pose against the key scan.

use super::{Odometry, Step};
use crate::geom::{compose_covariance, Cov3, Pose};
use crate::points::{bridge, recheck, refine_on_key, RangeScan};
use crate::register::{Assoc, Config, Status};
use crate::set::Set;

impl<const MAP: usize, const PTS: usize> Odometry<MAP, PTS> {
    /// Registers `curr` (with the scan's ranges `curr_pts`, when given) and updates the map,
    /// the previous scan's ranges and the key scan.
    pub(super) fn update_set(
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
                } else if let Some((rel, cov)) =
                    (scan > 0 && motion.is_none() && matches!(step.status, Status::None(_)))
                        .then(|| bridge(&self.pts, c, &step.rel))
                        .flatten()
                {
                    // Nothing registered the scan: the bridge the points support replaces
                    // the last motion again; it stays "none", the map is kept and so is the
                    // motion the next scan is predicted by (one step the features could not
                    // register says little about the next).
                    step.rel = rel;
                    step.rel_cov = cov;
                    step.pose = old.compose(&rel);
                    step.cov = compose_covariance(&old, &old_cov, &rel, &cov);
                    self.pose = step.pose;
                    self.cov = step.cov;
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
}
