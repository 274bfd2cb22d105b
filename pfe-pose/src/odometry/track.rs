//! Tracking a scan against the map, the pair registration when tracking fails, and the
//! search of the map when both fail.

use super::{Odometry, Step};
use crate::geom::{compose_covariance, sin_cos, wrap, Cov3, Pose, ZERO3};
use crate::points::{agreement, complete, RangeScan};
use crate::register::{
    register_sets, register_sets_verified, Assoc, Config, Status, NONE, ROTATION_SCALE,
    UNOBSERVABLE_VARIANCE,
};
use crate::set::{Set, MAX_OBS};

impl<const MAP: usize, const PTS: usize> Odometry<MAP, PTS> {
    /// [`Odometry::update_set`] before the scan's ranges replace the previous scan's.
    pub(super) fn update_inner(
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
                    &curr, &predicted, &guess, &reg, &assoc, &line_of, &pt_of, scan, false,
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
                let (pair, replaced) = register_sets_verified::<{ crate::register::VERIFIED }>(
                    &self.last,
                    &curr,
                    motion,
                    &cfg,
                    &mut Assoc::new(),
                    true,
                    Some(&verify),
                );
                let start = motion.map_or(self.last_rel, |m| m.0);
                complete(pair, replaced, prev_pts, c, Some(start), &cfg)
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
        // Without a motion prior, a pair that cannot tell a direction has no information
        // along it: as a prior it would leave the map's registration free along that
        // direction, where the map, seen from the same corridor, cannot tell it either. The
        // pair's answer is taken and the map restarts from this scan (below).
        let unbounded_pair = motion.is_none() && matches!(pair.status, Status::Degenerate { .. });
        let mut reg = if unbounded_pair {
            crate::Registration {
                status: Status::None(crate::Failure::InvalidPrior),
                ..pair
            }
        } else {
            // The map, in the predicted pose's frame, as the "previous scan".
            self.map_in(&predicted, scan, &mut map, &mut line_of, &mut pt_of);
            register_sets(
                &map,
                &curr,
                Some((Pose::IDENTITY, prior_cov)),
                &cfg,
                &mut assoc,
                // The pair's registration is a good guess: refine it against the map; search
                // only without one.
                !pair.is_registered(),
            )
        };
        if let (Status::Degenerate { direction }, true, true) =
            (reg.status, pair.is_registered(), points.is_some())
        {
            // Along what the map cannot tell its answer is not a measurement (the pair's
            // covariance there does not hold it): it stays at the pair's, the prediction.
            reg.rel = along_last(&reg.rel, &Pose::IDENTITY, &direction);
        }
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
        // With the scans' points, such an answer is also refused when they agree with it less
        // than a pair's ICP answer must (`verify_accept`): the map matched features wrongly.
        // The points' second look (`recheck`) then starts from the prediction.
        let map_only_refuted = !pair.is_registered()
            && reg.is_registered()
            && points.is_some_and(|c| {
                !(agreement(&self.pts, c, &guess.compose(&reg.rel)).score() >= cfg.verify_accept)
            });
        let map_only_refused = map_only_degenerate || map_only_refuted;
        // With the scans' points, the map's answer must also agree with the previous scan's
        // points nearly as well as the pair's: otherwise a map feature was fused wrongly (or
        // has moved) and pulled the answer off within both covariances. Then the pair's
        // answer is taken and the map entries it matched are replaced by this scan's features
        // (restarting the whole map loses what the rest of it holds).
        let refuted = pair.is_registered()
            && reg.is_registered()
            && points.is_some_and(|c| {
                let by_map = agreement(&self.pts, c, &guess.compose(&reg.rel)).score();
                let by_pair = agreement(&self.pts, c, &pair.rel).score();
                by_pair > by_map + MAP_REFUTED_MARGIN
            });
        if !reg.is_registered() || disagree || map_only_refused {
            // Not against the map: take the pair's registration (or the prediction) and
            // restart the map from this scan.
            let (mut rel, mut rel_cov, status) = if pair.is_registered() {
                (pair.rel, pair.cov, pair.status)
            } else if map_only_refused {
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
        if refuted {
            // The pair's answer (the prediction, in the predicted pose's frame) with its
            // covariance; the map's matches are kept but the features they matched replaced.
            let (s, c) = sin_cos(-guess.theta);
            let rot = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]];
            reg.rel = Pose::IDENTITY;
            reg.cov = crate::geom::sandwich3(&rot, &pair.cov);
            reg.status = pair.status;
        }
        self.accept(
            &curr, &predicted, &guess, &reg, &assoc, &line_of, &pt_of, scan, refuted,
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
        replace: bool,
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
        self.insert_with(curr, &ids, &new, scan, replace);
        Step {
            scan,
            rel,
            rel_cov,
            pose: new,
            cov: self.cov,
            status: reg.status,
        }
    }
}

/// Standard deviation of the last motion as a guess of the next (mm, rad) when tracking
/// without a motion prior: the refinement's reach (its first gates are about three times
/// its slack), not a statement about the robot.
const TRACK_SIGMA: (f32, f32) = (250.0, 0.1);

/// The map's answer is refused for the pair's when the scans' points agree with the pair's
/// better by more than this ([`crate::points::agreement`]'s score).
const MAP_REFUTED_MARGIN: f32 = 0.1;

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
