//! The registration spread over several calls: [`Search`] holds what must persist between
//! them (the clusters of votes, the ranked hypotheses, the Gauss–Newton under way, the best so
//! far) and [`Search::step`] advances it by at most a budget of associations. Run to
//! completion it is [`super::register_sets`], bit for bit: both run the same parts in the same
//! order (the tables of [`Work`] are rebuilt each call, from the same sets); the judgement of
//! a refined hypothesis and the end are [`super::register_sets_verified`]'s, held to it by
//! `tests/resumable.rs`.

use super::hypotheses::{score_next, Top, Votes, Voting};
use super::refine::{finish, Converging, Refined, Scratch, Work};
use super::visibility::visibility_penalty;
use super::{
    better, check_prior, close, fallback, is_corridor, Assoc, Config, Failure, Prior, Registration,
    Status, REFINE_RATIO,
};
use crate::geom::{Cov3, Pose};
use crate::obs::Observation;
use crate::set::Set;

/// The refined hypotheses judged so far: the best and the best distinct runner-up's score.
#[derive(Clone, Copy, Debug)]
struct Verdict {
    best: Option<Refined>,
    second_score: f32,
    /// The runner-up cannot make the result ambiguous (see [`super::register_sets_verified`]).
    lazy: bool,
    /// Both scans a corridor ([`is_corridor`]).
    corridor: bool,
}

impl Verdict {
    const fn new(lazy: bool, corridor: bool) -> Self {
        Self {
            best: None,
            second_score: 0.0,
            lazy,
            corridor,
        }
    }

    /// Judges the hypothesis that converged to `pose` (one or two associations and the
    /// visibility check): its refinement, when it has enough matches to compete. Not
    /// inlined, as [`conclude`].
    #[inline(never)]
    fn judge(
        &mut self,
        w: &mut Work,
        prev: &Set,
        curr: &Set,
        pose: Pose,
        prior: Option<&Prior>,
        cfg: &Config,
    ) -> Option<Refined> {
        let lazy = self.lazy;
        let mut r = finish(w, pose, prior, !lazy, None);
        if usize::from(r.matches.0) + usize::from(r.matches.1) < cfg.min_matches {
            // Fewer matches than asked for: in a corridor, enough for what its parallel walls
            // tell (the heading and the offset across it), registered as degenerate.
            if r.matches.0 < 2 || !self.corridor {
                return None;
            }
            let full = finish(w, r.pose, prior, true, None);
            if !full.scene_degenerate {
                return None;
            }
            r = full;
        }
        // The visibility check lowers the score: a hypothesis that cannot beat the best even
        // without it needs none.
        let hopeless = lazy && self.best.as_ref().is_some_and(|b| b.score > r.score * 1.01);
        if cfg.visibility_weight > 0.0 && !hopeless {
            r.score -= cfg.visibility_weight * visibility_penalty(prev, curr, &r.pose);
        }
        match &self.best {
            Some(b) if !better(&r, b) => {
                if lazy || !close(&r.pose, &b.pose, &b.cov_scene_pinv) {
                    self.second_score = self.second_score.max(r.score);
                }
            }
            _ => {
                if let Some(b) = &self.best {
                    if lazy || !close(&r.pose, &b.pose, &r.cov_scene_pinv) {
                        self.second_score = self.second_score.max(b.score);
                    }
                }
                self.best = Some(r);
            }
        }
        Some(r)
    }
}

/// The end of a registration: the winner `best` checked (matches, score, ambiguity against
/// `second_score` unless `resolved`), then its covariance, status and associations (into
/// `assoc`, for the odometry's map); one association.
/// Not inlined: its frame is taken only while it runs.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn conclude(
    w: &mut Work,
    best: Refined,
    second_score: f32,
    resolved: bool,
    corridor: bool,
    prior: Option<&Prior>,
    cfg: &Config,
    assoc: &mut Assoc,
    hypotheses: u32,
) -> Result<Registration, Failure> {
    let matched = usize::from(best.matches.0) + usize::from(best.matches.1);
    if matched < cfg.min_matches && !(corridor && best.scene_degenerate && best.matches.0 >= 2) {
        return Err(Failure::NoConsensus);
    }
    if !(best.score > cfg.min_score) {
        return Err(Failure::NoConsensus);
    }
    if !resolved && second_score >= cfg.ambiguity * best.score {
        return Err(Failure::Ambiguous);
    }
    let best = Refined {
        score: best.score,
        ..finish(w, best.pose, prior, true, Some(assoc))
    };
    let status = match best.unobservable {
        Some(direction) => Status::Degenerate { direction },
        None => Status::Ok,
    };
    Ok(Registration {
        rel: best.pose,
        cov: best.cov,
        status,
        matches: best.matches,
        hypotheses,
        dropped: 0,
        invalid: 0,
        chi2: best.chi2,
    })
}

/// What a step of a resumable search ([`Resumable::step`]) came to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Progress {
    /// Not done yet: step again.
    Pending,
    /// The registration, the one [`crate::register_with`] gives.
    Done(Registration),
}

/// Where a [`Search`] is.
#[derive(Clone, Copy, Debug)]
enum Phase {
    /// Scoring the prior's pose and voting the hypotheses.
    Vote(Voting),
    /// Scoring the clusters of votes, `scored` of them done.
    Score { scored: u32 },
    /// Refining the ranked hypotheses: the `i`-th next, or its Gauss–Newton under way.
    Refine { i: usize, gn: Option<Converging> },
    /// The `i`-th ranked hypothesis converged to `pose`: judged next.
    Judge { i: usize, pose: Pose },
    /// The winner's covariance and status next.
    Conclude,
    /// Finished.
    Done(Registration),
}

/// A registration of the current scan's set against the previous one's, resumable: see the
/// module. The sets themselves are not kept: every [`Search::step`] must be given the same.
#[derive(Clone, Debug)]
pub(crate) struct Search {
    phase: Phase,
    prior: Option<Prior>,
    search: bool,
    hypotheses: u32,
    votes: Votes,
    /// The scored hypotheses, ranked best first in place before the refinement.
    top: Top,
    first: f32,
    verdict: Verdict,
}

impl Search {
    /// A search of `curr`'s pose in `prev`'s frame (see [`super::register_sets`] for `prior`
    /// and `search`).
    pub(crate) fn new(
        prev: &Set,
        curr: &Set,
        prior: Option<(Pose, Cov3)>,
        cfg: &Config,
        search: bool,
    ) -> Self {
        let mut s = Self {
            phase: Phase::Vote(Voting::new()),
            prior: None,
            search,
            hypotheses: 0,
            votes: Votes::new(),
            top: Top::new(),
            first: 0.0,
            verdict: Verdict::new(
                cfg.ambiguity >= 1.2,
                is_corridor(prev, cfg) && is_corridor(curr, cfg),
            ),
        };
        match check_prior(prior, cfg) {
            Err(f) => s.phase = Phase::Done(fallback(f, None, 0)),
            Ok(p) => {
                s.prior = p;
                if prev.len() < 2 || curr.len() < 2 {
                    s.phase = Phase::Done(fallback(Failure::TooFewFeatures, p.as_ref(), 0));
                }
            }
        }
        s
    }

    /// Advances the search by at most `budget` units of work (a unit: one association of the
    /// scan's features; the hypotheses of one pair of the previous scan's features; the
    /// judgement of a converged hypothesis, one or two associations and the visibility check;
    /// a budget of 0 is taken as 1) and returns
    /// [`Progress::Done`] with the registration once it is complete (then again on every
    /// call). `assoc` receives the winner's matches when it completes.
    pub(crate) fn step(
        &mut self,
        prev: &Set,
        curr: &Set,
        cfg: &Config,
        assoc: &mut Assoc,
        budget: u32,
    ) -> Progress {
        if let Phase::Done(r) = self.phase {
            return Progress::Done(r);
        }
        let prior = self.prior;
        let prior = prior.as_ref();
        let mut scratch = Scratch::new();
        let mut w = Work::new(prev, curr, cfg, prior, &mut scratch);
        let mut left = budget.max(1);
        while left > 0 {
            left -= 1;
            self.phase = match self.phase {
                Phase::Vote(mut v) => {
                    left += 1; // taken by the voting itself
                    let done = v.step(
                        &mut w,
                        prev,
                        curr,
                        prior,
                        cfg,
                        &mut self.top,
                        self.search,
                        &mut self.votes,
                        &mut left,
                    );
                    if done {
                        self.hypotheses = v.count;
                        Phase::Score { scored: 0 }
                    } else {
                        Phase::Vote(v)
                    }
                }
                Phase::Score { scored } => {
                    if scored < cfg.scored && score_next(&mut w, &mut self.votes, &mut self.top) {
                        Phase::Score { scored: scored + 1 }
                    } else {
                        left += 1; // no association
                        self.rank()
                    }
                }
                Phase::Refine { i, gn } => self.refine(&mut w, i, gn, &mut left),
                Phase::Judge { i, pose } => {
                    self.verdict.judge(&mut w, prev, curr, pose, prior, cfg);
                    Phase::Refine { i: i + 1, gn: None }
                }
                Phase::Conclude => Phase::Done(self.conclude(&mut w, cfg, assoc)),
                Phase::Done(r) => Phase::Done(r),
            };
            if let Phase::Done(r) = self.phase {
                return Progress::Done(r);
            }
        }
        Progress::Pending
    }

    /// The scored hypotheses ranked best first, to be refined (none: no hypothesis).
    fn rank(&mut self) -> Phase {
        if self.top.n == 0 {
            return Phase::Done(fallback(
                Failure::NoHypothesis,
                self.prior.as_ref(),
                self.hypotheses,
            ));
        }
        let ranked = self.top.hypotheses_mut();
        ranked.sort_unstable_by(|a, b| b.score.total_cmp(&a.score));
        self.first = ranked.first().map_or(0.0, |h| h.score);
        Phase::Refine { i: 0, gn: None }
    }

    /// One Gauss–Newton step (one association) of the `i`-th ranked hypothesis's refinement
    /// (`gn`: under way); `left` is given back what was not spent.
    fn refine(&mut self, w: &mut Work, i: usize, gn: Option<Converging>, left: &mut u32) -> Phase {
        let prior = self.prior;
        let prior = prior.as_ref();
        let ranked = self.top.hypotheses_mut();
        let Some((done, rest)) = ranked.split_at_mut_checked(i) else {
            *left += 1;
            return Phase::Conclude;
        };
        let Some(h) = rest.first_mut() else {
            *left += 1;
            return Phase::Conclude;
        };
        let mut gn = match gn {
            Some(gn) => gn,
            None => {
                // One that the rest of the scene supports far less than the best is not refined.
                if h.score < REFINE_RATIO * self.first {
                    *left += 1;
                    return Phase::Conclude;
                }
                Converging::new(h.pose)
            }
        };
        match gn.step(w, prior, done) {
            None => Phase::Refine { i, gn: Some(gn) },
            Some(None) => {
                h.pose.x = f32::NAN;
                Phase::Refine { i: i + 1, gn: None }
            }
            Some(Some(pose)) => {
                h.pose = pose;
                Phase::Judge { i, pose }
            }
        }
    }

    /// The end: the winner's checks, covariance and status.
    fn conclude(&mut self, w: &mut Work, cfg: &Config, assoc: &mut Assoc) -> Registration {
        let prior = self.prior.as_ref();
        let Some(best) = self.verdict.best else {
            return fallback(Failure::NoConsensus, prior, self.hypotheses);
        };
        conclude(
            w,
            best,
            self.verdict.second_score,
            false,
            self.verdict.corridor,
            prior,
            cfg,
            assoc,
            self.hypotheses,
        )
        .unwrap_or_else(|f| fallback(f, prior, self.hypotheses))
    }
}

/// [`crate::register_with`] spread over several calls: the sets of both scans, the
/// configuration and the search's state (about 13 KiB; the odometry keeps only the search's state).
///
/// ```
/// use pfe_pose::register::{Progress, Resumable};
/// use pfe_pose::{register, LineObs, Observation, Pose};
/// let truth = Pose::new(300.0, 100.0, 0.2);
/// let walls = [(0.0f32, 3000.0f32), (1.5708, 2000.0), (3.1416, 1500.0), (-1.5708, 2500.0)];
/// let cov = [[1e-6, 0.0], [0.0, 25.0]];
/// let inv = truth.inverse();
/// let prev: Vec<_> = walls.iter().map(|&(a, r)| Observation::Line(LineObs::new(a, r, cov))).collect();
/// let curr: Vec<_> = walls.iter().map(|&(a, r)| {
///     let (a, r) = inv.transform_line(a, r);
///     Observation::Line(LineObs::new(a, r, cov))
/// }).collect();
/// let mut search = Resumable::new(&prev, &curr, None, &Default::default());
/// let mut calls = 1;
/// let reg = loop {
///     match search.step(2) {
///         Progress::Done(reg) => break reg,
///         Progress::Pending => calls += 1,
///     }
/// };
/// assert_eq!(reg, register(&prev, &curr, None)); // bit for bit
/// assert!(calls > 1);
/// ```
#[derive(Clone, Debug)]
pub struct Resumable {
    prev: Set,
    curr: Set,
    cfg: Config,
    search: Search,
    assoc: Assoc,
}

impl Resumable {
    /// The registration of `curr` against `prev` (see [`crate::register_with`]), not started.
    pub fn new(
        prev: &[Observation],
        curr: &[Observation],
        prior: Option<(Pose, Cov3)>,
        cfg: &Config,
    ) -> Self {
        let p = Set::from_obs(prev.iter().copied(), cfg);
        let c = Set::from_obs(curr.iter().copied(), cfg);
        let search = Search::new(&p, &c, prior, cfg, true);
        Self {
            prev: p,
            curr: c,
            cfg: *cfg,
            search,
            assoc: Assoc::new(),
        }
    }

    /// Advances the registration by at most `budget` associations of the scan's features
    /// (at least one); once complete, [`Progress::Done`] with [`crate::register_with`]'s
    /// result, bit for bit, for any sequence of budgets.
    pub fn step(&mut self, budget: u32) -> Progress {
        match self
            .search
            .step(&self.prev, &self.curr, &self.cfg, &mut self.assoc, budget)
        {
            Progress::Pending => Progress::Pending,
            Progress::Done(mut r) => {
                r.dropped = self.prev.dropped.saturating_add(self.curr.dropped);
                r.invalid = self.prev.invalid.saturating_add(self.curr.invalid);
                Progress::Done(r)
            }
        }
    }
}

#[cfg(test)]
mod size {
    /// What a pending search keeps between scans (the odometry's, on the board, in static
    /// RAM): the clusters of votes are most of it.
    #[test]
    fn search_state_stays_small() {
        let search = core::mem::size_of::<super::Search>();
        assert!(search <= 2 * 1024, "{search}");
    }
}
