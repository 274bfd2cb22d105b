//! The step with the scan's ranges: the points check the features' registration and refine
//! the pose against the key scan.

use super::{Odometry, Step};
use crate::geom::{compose_covariance, wrap, Cov3, Pose};
use crate::points::{back_to_key, bridge, recheck, refine_on_key, RangeScan};
use crate::register::{Assoc, Config, Status, ROTATION_SCALE};
use crate::set::Set;

/// Scans after the key moved during which the former key may take a scan back
/// ([`back_to_key`]).
const BACK_SCANS: u8 = 3;
/// A step this far from the last motion (mm, θ in units of [`ROTATION_SCALE`]) is a jump: the
/// key scan before it is the one to go back to.
const JUMP: f32 = 500.0;

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
                self.back_guess = self.back_guess.compose(&self.back_motion);
                self.back_age = self.back_age.saturating_add(1);
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
                    let back = (self.back_age <= BACK_SCANS)
                        .then(|| {
                            back_to_key(
                                &self.back,
                                &self.back_pose,
                                c,
                                &self.back_guess,
                                &step.pose,
                            )
                        })
                        .flatten();
                    if let Some((pose, cov)) = back {
                        // The scans since the key moved came from elsewhere (registered as a
                        // jump and back): this scan is placed against the former key, which
                        // becomes the key again, and the map restarts from it.
                        step.pose = pose;
                        step.rel = old.inverse().compose(&pose);
                        step.rel_cov = cov;
                        step.cov = compose_covariance(&old, &old_cov, &step.rel, &cov);
                        step.status = Status::Ok;
                        self.pose = pose;
                        self.cov = step.cov;
                        self.last_rel = self.back_motion;
                        core::mem::swap(&mut self.key, &mut self.back);
                        self.key_pose = self.back_pose;
                        self.back.clear();
                        let curr = self.last.clone();
                        self.n = 0;
                        self.insert_all(&curr, &Assoc::new(), &pose, scan);
                    } else {
                        // The key scan becomes the one to go back to when the one before
                        // has been so for a few scans, or when this step jumped from the
                        // motion before that one (otherwise the scans since it may be the
                        // ones from elsewhere).
                        let m = self.back_motion;
                        let d = [
                            step.rel.x - m.x,
                            step.rel.y - m.y,
                            wrap(step.rel.theta - m.theta) * ROTATION_SCALE,
                        ];
                        let jump = d[0] * d[0] + d[1] * d[1] + d[2] * d[2] > JUMP * JUMP;
                        if jump || self.back_age > BACK_SCANS || self.back.is_empty() {
                            core::mem::swap(&mut self.key, &mut self.back);
                            self.back_pose = self.key_pose;
                            self.back_guess = old.compose(&old_last);
                            self.back_motion = old_last;
                            self.back_age = 0;
                        }
                        self.key.clone_from(c);
                        self.key_pose = step.pose;
                    }
                }
                self.pts.clone_from(c);
            }
            _ => {
                self.pts.clear();
                self.key.clear();
                self.back.clear();
            }
        }
        step
    }
}
