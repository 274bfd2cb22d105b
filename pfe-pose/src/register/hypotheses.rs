//! Step 1: hypotheses of the pose from pairs of features, each scored by consensus.

use core::f32::consts::PI;

use super::refine::Work;
use super::{quad3, Config, Prior, REFINE};
use crate::geom::{sin_cos, wrap, Pose};
use crate::set::{top_k, Line, Pt, Set};

/// A scored hypothesis.
#[derive(Clone, Copy, Debug)]
pub(super) struct Hyp {
    pub(super) pose: Pose,
    pub(super) score: f32,
}

/// The best hypotheses so far, distinct from one another (non-maximum suppression).
#[derive(Clone, Debug)]
pub(super) struct Top {
    items: [Hyp; REFINE],
    pub(super) n: usize,
}

impl Top {
    pub(super) const fn new() -> Self {
        Self {
            items: [Hyp {
                pose: Pose::IDENTITY,
                score: 0.0,
            }; REFINE],
            n: 0,
        }
    }

    /// Every slot (only the first [`Top::n`] are hypotheses).
    pub(super) fn all(&self) -> &[Hyp; REFINE] {
        &self.items
    }

    /// The hypotheses (the first [`Top::n`] slots), to be ranked in place.
    pub(super) fn hypotheses_mut(&mut self) -> &mut [Hyp] {
        self.items.get_mut(..self.n).unwrap_or(&mut [])
    }

    fn offer(&mut self, h: Hyp) {
        if !(h.score > 0.0) {
            return;
        }
        // Near an existing one: keep the better of the two.
        let near = |a: &Pose, b: &Pose| {
            crate::geom::hypot(a.x - b.x, a.y - b.y) < 150.0 && wrap(a.theta - b.theta).abs() < 0.05
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

/// Bounds of the squared translation for [`within_translation`]: `max²` less and plus 0.01 %
/// (NaN, so that every test fails, when `max` is not positive and finite).
fn squared_bounds(max: f32) -> (f32, f32) {
    if max > 0.0 && max < 1e18 {
        (max * max * (1.0 - 1e-4), max * max * (1.0 + 1e-4))
    } else {
        (f32::NAN, f32::NAN)
    }
}

/// `hypot(x, y) <= max`, bit for bit, without the square root when the square is clearly
/// inside or outside `square` (from [`squared_bounds`]): the root is within a few ulps, far
/// less than the 0.01 %.
#[inline(always)]
fn within_translation(x: f32, y: f32, max: f32, square: (f32, f32)) -> bool {
    let q = x * x + y * y;
    if q <= square.0 {
        true
    } else if q > square.1 {
        false
    } else {
        crate::geom::sqrt(q) <= max
    }
}

/// `(b − a)` modulo π, in [0, π).
#[inline(always)]
fn undirected(a: f32, b: f32) -> f32 {
    let d = b - a;
    let u = d - PI * crate::geom::floor(d / PI);
    if (0.0..PI).contains(&u) {
        u
    } else {
        0.0
    }
}

/// `x` modulo π, in (−π/2, π/2].
#[inline(always)]
fn mod_pi(x: f32) -> f32 {
    x - PI * crate::geom::round(x / PI)
}

/// Hypotheses of `curr`'s pose in `prev`'s frame, scored; returns how many were scored. Without
/// `search` (and with a prior), the prior's pose alone. Not inlined: its tables are not
/// on the stack during the refinement.
#[inline(never)]
pub(super) fn hypothesise(
    w: &mut Work,
    prev: &Set,
    curr: &Set,
    prior: Option<&Prior>,
    cfg: &Config,
    top: &mut Top,
    search: bool,
) -> u32 {
    let mut votes = Votes::new();
    let count = vote(w, prev, curr, prior, cfg, top, search, &mut votes);
    // Score the best-supported clusters only, each at the mean of its votes.
    for _ in 0..cfg.scored {
        if !score_next(w, &mut votes, top) {
            break;
        }
    }
    count
}

/// Scores the best-supported cluster left in `votes` at its mean into `top` (one
/// association); false when none is left.
#[inline(always)]
pub(super) fn score_next(w: &mut Work, votes: &mut Votes, top: &mut Top) -> bool {
    let Some(v) = votes.take_best() else {
        return false;
    };
    let score = w.score(&v, 1.0);
    top.offer(Hyp { pose: v, score });
    true
}

/// The first part of [`hypothesise`]: the prior's pose (or no motion) scored into `top`, and
/// the hypotheses from pairs of features voted into `votes` (none without `search` when there
/// is a prior); returns how many hypotheses were formed. Inlined with its [`Voting::step`]: [`hypothesise`]'s frame is all the stack they take.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn vote(
    w: &mut Work,
    prev: &Set,
    curr: &Set,
    prior: Option<&Prior>,
    cfg: &Config,
    top: &mut Top,
    search: bool,
    votes: &mut Votes,
) -> u32 {
    let mut v = Voting::new();
    let mut unlimited = u32::MAX;
    v.step(
        w,
        prev,
        curr,
        prior,
        cfg,
        top,
        search,
        votes,
        &mut unlimited,
    );
    v.count
}

/// The kinds of hypotheses, in the order they are formed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Part {
    /// The prior's pose (or no motion), scored.
    Start,
    /// Pairs of non-parallel lines: a pair `(i, j)` of the previous scan's lines a step.
    LinePairs,
    /// Pairs of points at the same distance: a pair `(i, j)` of the previous scan's a step.
    PointPairs,
    /// A line and a point: a line `i` of the previous scan and `j` of the current a step.
    LinePoint,
    /// A corridor (no pair formed a hypothesis): a line `i` of the previous scan a step.
    Corridor,
    /// Every hypothesis formed.
    Done,
}

/// A [`vote`] under way: which part, the indices of the next step in it, and the counts.
#[derive(Clone, Copy, Debug)]
pub(super) struct Voting {
    part: Part,
    i: usize,
    j: usize,
    /// Hypotheses formed within the bounds.
    pub(super) count: u32,
    /// Hypotheses formed from pairs of features.
    pair_hyps: u32,
}

impl Voting {
    pub(super) const fn new() -> Self {
        Self {
            part: Part::Start,
            i: 0,
            j: 0,
            count: 0,
            pair_hyps: 0,
        }
    }

    /// At most `left` units of [`vote`] (a unit: the prior's pose's score, or the hypotheses
    /// of one pair of the previous scan's features), each taken off `left`; true when every
    /// hypothesis is formed. The scans' best features and the current scan's pairs are found
    /// again at each call (from the same sets: the same).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn step<'s>(
        &mut self,
        w: &mut Work,
        prev: &'s Set,
        curr: &'s Set,
        prior: Option<&Prior>,
        cfg: &Config,
        top: &mut Top,
        search: bool,
        votes: &mut Votes,
        left: &mut u32,
    ) -> bool {
        let square = squared_bounds(cfg.max_translation);
        let within = |pose: &Pose| match prior {
            Some(p) => {
                let d = [
                    pose.x - p.pose.x,
                    pose.y - p.pose.y,
                    wrap(pose.theta - p.pose.theta),
                ];
                // The bounds hold around the prior too: a prior wider than them (the
                // odometry's search after a scan nothing registered takes them as its σ, a
                // 99.9 % gate of 12 m) does not reach beyond what one scan can move.
                quad3(&p.gate_info, &d) < cfg.prior_gate
                    && within_translation(d[0], d[1], cfg.max_translation, square)
                    && d[2].abs() <= cfg.max_rotation
            }
            None => {
                within_translation(pose.x, pose.y, cfg.max_translation, square)
                    && pose.theta.abs() <= cfg.max_rotation
            }
        };
        // A hypothesis formed: a vote for its pose (the right pose comes from many pairs;
        // each cluster of votes is scored once, after).
        let consider = |pose: Pose, votes: &mut Votes, count: &mut u32| {
            if !pose.is_finite() || *count >= cfg.max_hypotheses || !within(&pose) {
                return;
            }
            *count = count.saturating_add(1);
            votes.add(pose);
        };
        if self.part == Part::Start && *left > 0 {
            // The prior's pose (or no motion) is always scored.
            let start = prior.map_or(Pose::IDENTITY, |p| p.pose);
            if start.is_finite() && within(&start) {
                self.count = self.count.saturating_add(1);
                let score = w.score(&start, 1.0);
                top.offer(Hyp { pose: start, score });
            }
            self.part = if !search && prior.is_some() {
                Part::Done
            } else {
                Part::LinePairs
            };
            (self.i, self.j) = (0, 1);
            *left -= 1;
        }
        if self.part == Part::Done || *left == 0 {
            return self.part == Part::Done;
        }
        let (pl, cl) = (prev.lines(), curr.lines());
        let (hp, np) = top_k::<12>(pl.iter().map(|l| l.rank));
        let (hc, nc) = top_k::<12>(cl.iter().map(|l| l.rank));
        let hp = hp.get(..np).unwrap_or(&[]);
        let hc = hc.get(..nc).unwrap_or(&[]);
        let line = |s: &'s [Line], i: u8| s.get(usize::from(i));
        let (pp, cp) = (prev.pts(), curr.pts());
        let (qp, nqp) = top_k::<8>(pp.iter().map(|p| p.rank));
        let (qc, nqc) = top_k::<8>(cp.iter().map(|p| p.rank));
        let qp = qp.get(..nqp).unwrap_or(&[]);
        let qc = qc.get(..nqc).unwrap_or(&[]);
        let pt = |s: &'s [Pt], i: u8| s.get(usize::from(i));
        // The current scan's ordered pairs sorted by the angle between them (for the pairs of
        // lines only).
        let mut cpairs = [(0.0f32, 0u8, 0u8); 12 * 11];
        let mut ncp = 0usize;
        let mut max_var_c = 0.0f32;
        let pairs = if self.part == Part::LinePairs {
            hc
        } else {
            &[]
        };
        for &k in pairs {
            let Some(lk) = line(cl, k) else { continue };
            max_var_c = max_var_c.max(lk.cov.a);
            for &l in hc {
                if l == k {
                    continue;
                }
                let Some(ll) = line(cl, l) else { continue };
                let dc = undirected(lk.a, ll.a);
                // Insertion into the sorted prefix.
                let mut pos = ncp;
                while pos > 0 && cpairs.get(pos - 1).is_some_and(|p| p.0 > dc) {
                    if let Some(&prev) = cpairs.get(pos - 1) {
                        if let Some(slot) = cpairs.get_mut(pos) {
                            *slot = prev;
                        }
                    }
                    pos -= 1;
                }
                if let Some(slot) = cpairs.get_mut(pos) {
                    *slot = (dc, k, l);
                    ncp += 1;
                }
            }
        }
        loop {
            if *left == 0 {
                return self.part == Part::Done;
            }
            match self.part {
                // Done above (its own unit).
                Part::Start => self.part = Part::LinePairs,
                Part::LinePairs => {
                    let (Some(&i), Some(&j)) = (hp.get(self.i), hp.get(self.j)) else {
                        if self.i < hp.len() {
                            (self.i, self.j) = (self.i + 1, self.i + 2);
                        } else {
                            (self.part, self.i, self.j) = (Part::PointPairs, 0, 1);
                        }
                        continue;
                    };
                    self.j += 1;
                    let (Some(li), Some(lj)) = (line(pl, i), line(pl, j)) else {
                        continue;
                    };
                    let dp = undirected(li.a, lj.a);
                    if dp.min(PI - dp) < cfg.min_pair_angle {
                        continue;
                    }
                    let cpairs = cpairs.get(..ncp).unwrap_or(&[]);
                    // This pair of the previous scan looked up in them within its gate.
                    // Every gate below is at most this wide; the angle between a pair is
                    // modulo π.
                    let widest = 3.0 * crate::geom::sqrt(li.cov.a + lj.cov.a + 2.0 * max_var_c)
                        + cfg.slack[0];
                    let widest = widest * 1.001 + 1e-5;
                    let mut windows = [(0.0f32, -1.0f32); 3];
                    windows[0] = (dp - widest, dp + widest);
                    if !(widest < 0.5 * PI) {
                        windows[0] = (f32::NEG_INFINITY, f32::INFINITY);
                    } else if dp - widest < 0.0 {
                        windows[1] = (dp - widest + PI, PI);
                    }
                    if dp + widest > PI {
                        windows[2] = (0.0, dp + widest - PI);
                    }
                    for (lo, hi) in windows {
                        let from = cpairs.partition_point(|p| p.0 < lo);
                        let to = cpairs.partition_point(|p| p.0 <= hi);
                        for &(dc, k, l) in cpairs.get(from..to).unwrap_or(&[]) {
                            let (Some(lk), Some(ll)) = (line(cl, k), line(cl, l)) else {
                                continue;
                            };
                            let var = li.cov.a + lj.cov.a + lk.cov.a + ll.cov.a;
                            let gate = 3.0 * crate::geom::sqrt(var) + cfg.slack[0];
                            if mod_pi(dp - dc).abs() > gate {
                                continue;
                            }
                            let t0 = li.a - lk.a;
                            let t1 = t0 + mod_pi(lj.a - ll.a - t0);
                            let theta = wrap(0.5 * (t0 + t1));
                            let (sth, cth) = sin_cos(theta);
                            let scs = [
                                w.prev_sc(usize::from(i)),
                                w.curr_sc(usize::from(k)),
                                w.prev_sc(usize::from(j)),
                                w.curr_sc(usize::from(l)),
                            ];
                            for (th, s, c) in [(theta, sth, cth), (wrap(theta + PI), -sth, -cth)] {
                                if let Some(t) = solve_two_lines(li, lk, lj, ll, scs, [s, c]) {
                                    self.pair_hyps += 1;
                                    consider(Pose::new(t[0], t[1], th), votes, &mut self.count);
                                }
                            }
                        }
                    }
                    *left -= 1;
                }
                Part::PointPairs => {
                    let (Some(&a), Some(&b)) = (qp.get(self.i), qp.get(self.j)) else {
                        if self.i < qp.len() {
                            (self.i, self.j) = (self.i + 1, self.i + 2);
                        } else {
                            (self.part, self.i, self.j) = (Part::LinePoint, 0, 0);
                        }
                        continue;
                    };
                    self.j += 1;
                    let (Some(pa), Some(pb)) = (pt(pp, a), pt(pp, b)) else {
                        continue;
                    };
                    let vp = [pb.p[0] - pa.p[0], pb.p[1] - pa.p[1]];
                    let dp = crate::geom::hypot(vp[0], vp[1]);
                    if dp < 300.0 {
                        continue;
                    }
                    let var_p = pa.cov.a + pa.cov.c + pb.cov.a + pb.cov.c;
                    for &c in qc {
                        let Some(pc) = pt(cp, c) else { continue };
                        for &d in qc {
                            if d == c {
                                continue;
                            }
                            let Some(pd) = pt(cp, d) else { continue };
                            let vc = [pd.p[0] - pc.p[0], pd.p[1] - pc.p[1]];
                            let dc = crate::geom::hypot(vc[0], vc[1]);
                            let var_c = pc.cov.a + pc.cov.c + pd.cov.a + pd.cov.c;
                            let var = var_p + var_c;
                            if (dp - dc).abs() > 3.0 * crate::geom::sqrt(0.5 * var) + cfg.slack[1] {
                                continue;
                            }
                            let th = wrap(libm::atan2f(vp[1], vp[0]) - libm::atan2f(vc[1], vc[0]));
                            let mid_p = [0.5 * (pa.p[0] + pb.p[0]), 0.5 * (pa.p[1] + pb.p[1])];
                            let mid_c = [0.5 * (pc.p[0] + pd.p[0]), 0.5 * (pc.p[1] + pd.p[1])];
                            let rc = Pose::new(0.0, 0.0, th).transform_point(mid_c);
                            self.pair_hyps += 1;
                            consider(
                                Pose::new(mid_p[0] - rc[0], mid_p[1] - rc[1], th),
                                votes,
                                &mut self.count,
                            );
                        }
                    }
                    *left -= 1;
                }
                Part::LinePoint => {
                    let (hp6, hc6) = (hp.get(..6).unwrap_or(hp), hc.get(..6).unwrap_or(hc));
                    let (qp4, qc4) = (qp.get(..5).unwrap_or(qp), qc.get(..5).unwrap_or(qc));
                    let (Some(&i), Some(&k)) = (hp6.get(self.i), hc6.get(self.j)) else {
                        if self.i < hp6.len() {
                            (self.i, self.j) = (self.i + 1, 0);
                        } else {
                            self.part = if self.pair_hyps == 0 {
                                Part::Corridor
                            } else {
                                Part::Done
                            };
                            (self.i, self.j) = (0, 0);
                        }
                        continue;
                    };
                    self.j += 1;
                    let (Some(li), Some(lk)) = (line(pl, i), line(cl, k)) else {
                        continue;
                    };
                    for th in [li.a - lk.a, li.a - lk.a + PI] {
                        let th = wrap(th);
                        let (s, c) = sin_cos(th);
                        let [sa, ca] = w.prev_sc(usize::from(i));
                        let sign = if crate::geom::sin_cos(lk.a + th - li.a).1 >= 0.0 {
                            1.0
                        } else {
                            -1.0
                        };
                        for &a in qp4 {
                            let Some(pa) = pt(pp, a) else { continue };
                            for &b in qc4 {
                                let Some(pb) = pt(cp, b) else { continue };
                                let t = [
                                    pa.p[0] - (c * pb.p[0] - s * pb.p[1]),
                                    pa.p[1] - (s * pb.p[0] + c * pb.p[1]),
                                ];
                                // The line's ρ must agree.
                                let e = li.r - sign * lk.r - (ca * t[0] + sa * t[1]);
                                let sd =
                                    crate::geom::sqrt(li.cov.c + lk.cov.c + pa.cov.a + pb.cov.a);
                                if e.abs() > 3.0 * sd + cfg.slack[1] + cfg.slack[2] * lk.reach {
                                    continue;
                                }
                                self.pair_hyps += 1;
                                consider(Pose::new(t[0], t[1], th), votes, &mut self.count);
                            }
                        }
                    }
                    *left -= 1;
                }
                Part::Corridor => {
                    // Single lines, nothing along them.
                    let Some(&i) = hp.get(self.i) else {
                        self.part = Part::Done;
                        continue;
                    };
                    self.i += 1;
                    let Some(li) = line(pl, i) else { continue };
                    for &k in hc {
                        let Some(lk) = line(cl, k) else { continue };
                        for th in [li.a - lk.a, li.a - lk.a + PI] {
                            let th = wrap(th);
                            let sign = if crate::geom::sin_cos(lk.a + th - li.a).1 >= 0.0 {
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
                            consider(Pose::new(t[0], t[1], th), votes, &mut self.count);
                        }
                    }
                    *left -= 1;
                }
                Part::Done => return true,
            }
        }
    }
}

/// Clusters of hypotheses within this of each other (mm, rad) are one.
const VOTE_DISTANCE: f32 = 150.0;
const VOTE_ANGLE: f32 = 0.035;
/// Clusters kept.
const VOTES: usize = 96;

/// The hypotheses formed, clustered: how many pairs of features agree on each pose. Each
/// cluster's mean (x, y, θ) and count in arrays of their own, so that the search for a
/// vote's cluster runs down the x values alone.
#[derive(Clone, Debug)]
pub(super) struct Votes {
    x: [f32; VOTES],
    y: [f32; VOTES],
    theta: [f32; VOTES],
    n: [u16; VOTES],
    len: usize,
    /// No cluster before this one has a single vote (counts only grow while votes come in,
    /// and a replaced cluster has one vote again: the first single one never moves back).
    single: usize,
}

impl Votes {
    pub(super) const fn new() -> Self {
        Self {
            x: [0.0; VOTES],
            y: [0.0; VOTES],
            theta: [0.0; VOTES],
            n: [0; VOTES],
            len: 0,
            single: 0,
        }
    }

    /// A vote for `pose`: into the first cluster whose mean it is near, else a new one (when
    /// full, in place of a cluster of one vote).
    fn add(&mut self, pose: Pose) {
        let len = self.len.min(VOTES);
        for (j, &mx) in self.x.iter().enumerate().take(len) {
            // The cheapest test first: most clusters differ in x.
            let dx = pose.x - mx;
            if !(dx.abs() < VOTE_DISTANCE) {
                continue;
            }
            let (Some(y), Some(theta), Some(n)) =
                (self.y.get_mut(j), self.theta.get_mut(j), self.n.get_mut(j))
            else {
                continue;
            };
            let d = [dx, pose.y - *y, wrap(pose.theta - *theta)];
            if d[1].abs() < VOTE_DISTANCE && d[2].abs() < VOTE_ANGLE {
                *n = n.saturating_add(1);
                let k = 1.0 / f32::from(*n);
                let mean = Pose::new(mx + d[0] * k, *y + d[1] * k, *theta + d[2] * k);
                *y = mean.y;
                *theta = mean.theta;
                if let Some(x) = self.x.get_mut(j) {
                    *x = mean.x;
                }
                return;
            }
        }
        let slot = if len < VOTES {
            self.len = len + 1;
            Some(len)
        } else {
            let from = self.single;
            let j = self
                .n
                .iter()
                .skip(from)
                .position(|&c| c <= 1)
                .map(|j| j + from);
            self.single = j.unwrap_or(VOTES);
            j
        };
        if let Some(j) = slot {
            for (a, v) in [
                (&mut self.x, pose.x),
                (&mut self.y, pose.y),
                (&mut self.theta, pose.theta),
            ] {
                if let Some(a) = a.get_mut(j) {
                    *a = v;
                }
            }
            if let Some(n) = self.n.get_mut(j) {
                *n = 1;
            }
        }
    }

    /// The mean pose of the cluster with the most votes (the first formed among equals),
    /// removed.
    fn take_best(&mut self) -> Option<Pose> {
        let mut best: Option<(usize, u16)> = None;
        for (j, &n) in self.n.iter().enumerate().take(self.len) {
            if n > 0 && best.is_none_or(|b| n > b.1) {
                best = Some((j, n));
            }
        }
        let (j, _) = best?;
        if let Some(n) = self.n.get_mut(j) {
            *n = 0;
        }
        self.single = 0;
        let mean = Pose {
            x: self.x.get(j).copied()?,
            y: self.y.get(j).copied()?,
            theta: self.theta.get(j).copied()?,
        };
        mean.is_finite().then_some(mean)
    }
}

/// The translation that maps lines `k`, `l` of the current scan onto `i`, `j` of the previous
/// one under the rotation of sine and cosine `th`; `sc`: sine and cosine of the α of `i`, `k`,
/// `j`, `l`.
#[inline(always)]
fn solve_two_lines(
    li: &Line,
    lk: &Line,
    lj: &Line,
    ll: &Line,
    sc: [[f32; 2]; 4],
    th: [f32; 2],
) -> Option<[f32; 2]> {
    let [[si, ci], [sk, ck], [sj, cj], [sl, cl]] = sc;
    let [st, ct] = th;
    // cos(α_c + θ − α_p): the current line's normal turned, against the previous one's.
    let rhs = |p: &Line, c: &Line, (sp, cp): (f32, f32), (sc, cc): (f32, f32)| {
        let (s, co) = (sc * ct + cc * st, cc * ct - sc * st);
        let sign = if co * cp + s * sp >= 0.0 { 1.0 } else { -1.0 };
        p.r - sign * c.r
    };
    let det = ci * sj - si * cj;
    if !(det.abs() > 0.05) {
        return None;
    }
    let (bi, bj) = (
        rhs(li, lk, (si, ci), (sk, ck)),
        rhs(lj, ll, (sj, cj), (sl, cl)),
    );
    let x = (bi * sj - bj * si) / det;
    let y = (ci * bj - cj * bi) / det;
    (x.is_finite() && y.is_finite()).then_some([x, y])
}

#[cfg(test)]
mod tests {
    /// [`super::within_translation`] against `hypot(x, y) <= max` on random translations,
    /// many of them at the bound, and on degenerate bounds.
    #[test]
    fn within_translation_is_hypot() {
        let mut s = 0x853c_49e6_748f_ea9bu64;
        let mut next = || {
            s ^= s >> 12;
            s ^= s << 25;
            s ^= s >> 27;
            (s.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut near = 0;
        for k in 0..400_000 {
            let max = [3000.0f32, 1.0, 1234.567, 0.0, -5.0, f32::NAN, f32::INFINITY][k % 7];
            let r = if max.is_finite() && max > 0.0 {
                max
            } else {
                3000.0
            };
            // Radii within 0.1 % of the bound, or anywhere up to twice it.
            let radius = if k % 2 == 0 {
                r * (1.0 + (next() - 0.5) * 2e-3)
            } else {
                2.0 * r * next()
            };
            let a = next() * core::f32::consts::TAU;
            let (x, y) = (radius * libm::cosf(a), radius * libm::sinf(a));
            let want = crate::geom::hypot(x, y) <= max;
            let got = super::within_translation(x, y, max, super::squared_bounds(max));
            assert_eq!(got, want, "{x} {y} {max}");
            near += usize::from(want != (crate::geom::hypot(x, y) <= max * 0.9999));
        }
        // The bound itself was exercised: points on both sides within 0.01 % of it.
        assert!(near > 1000, "{near}");
    }
}
