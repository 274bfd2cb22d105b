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
pub(super) struct Top {
    items: [Hyp; REFINE],
    pub(super) n: usize,
}

impl Top {
    pub(super) fn new() -> Self {
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

    pub(super) fn items(&self) -> &[Hyp] {
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
pub(super) fn hypothesise(
    w: &mut Work,
    prev: &Set,
    curr: &Set,
    prior: Option<&Prior>,
    cfg: &Config,
    top: &mut Top,
) -> u32 {
    let mut count = 0u32;
    let consider = |pose: Pose, w: &mut Work, top: &mut Top, count: &mut u32| {
        if !pose.is_finite() || *count >= cfg.max_hypotheses {
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
        let score = w.score(&pose, 1.0);
        top.offer(Hyp { pose, score });
    };
    match prior {
        Some(p) => consider(p.pose, w, top, &mut count),
        None => consider(Pose::IDENTITY, w, top, &mut count),
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
                            consider(Pose::new(t[0], t[1], th), w, top, &mut count);
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
                        w,
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
                        consider(Pose::new(t[0], t[1], th), w, top, &mut count);
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
                    consider(Pose::new(t[0], t[1], th), w, top, &mut count);
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
