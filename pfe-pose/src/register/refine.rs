//! Steps 2–4: association with Mahalanobis gates, consensus score, Gauss–Newton, covariance
//! and degeneracy.

use core::f32::consts::PI;

use super::hypotheses::Hyp;
use super::{Assoc, Config, Prior, ITERATIONS, NONE, ROTATION_SCALE, UNOBSERVABLE_VARIANCE};
use crate::geom::{eigen_sym3, inverse_spd3, sin_cos, wrap, Cov3, Pose, Sym2, ZERO3};
use crate::set::{Line, Set, MAX_OBS};

/// A hypothesis after Gauss–Newton.
#[derive(Clone, Copy, Debug)]
pub(super) struct Refined {
    pub(super) pose: Pose,
    pub(super) cov: Cov3,
    /// Pseudo-inverse of the scene's information (for "distinct" tests).
    pub(super) cov_scene_pinv: Cov3,
    pub(super) score: f32,
    pub(super) chi2: f32,
    pub(super) matches: (u16, u16),
    pub(super) unobservable: Option<[f32; 3]>,
    /// The matches themselves leave a direction undetermined (before the confirmation rule):
    /// parallel lines only, say.
    pub(super) scene_degenerate: bool,
}

/// Normal equations of one association.
pub(super) struct Normal {
    pub(super) h: Cov3,
    pub(super) g: [f32; 3],
    pub(super) chi2: f32,
    pub(super) score: f32,
    pub(super) lines: u16,
    pub(super) pts: u16,
}

/// The tables of one registration (a few KiB: kept by the caller, filled in place).
pub(super) struct Scratch {
    /// Each match's information `Jᵀ W J` in the last association (its upper triangle, row
    /// by row).
    contrib: [[f32; 6]; 2 * MAX_OBS],
    /// Whether each match is trusted without confirmation (both segments long).
    trusted: [bool; 2 * MAX_OBS],
    /// Sine and cosine of each current line's α.
    curr_sc: [[f32; 2]; MAX_OBS],
    /// Sine and cosine of each previous line's α.
    prev_sc: [[f32; 2]; MAX_OBS],
    /// The angle index: for each of [`BUCKETS`] equal ranges of α over the circle, the
    /// previous lines (bit `i`: line `i`) within their own reach of it: the widest angle
    /// gate of a pair with their own variance, `√(gate (σ²_i + σ²_c + slack_α²))` (`σ²_c`:
    /// [`Work::curr_var`]).
    buckets: [u64; BUCKETS],
}

/// Ranges of α in the angle index.
const BUCKETS: usize = 64;
/// Widest angle gate the index serves, rad (wider gates look at every line).
const MAX_REACH: f32 = 0.6;
/// Largest variance of a current line's α the index serves, rad² (σ 0.05 rad).
const MAX_CURR_VAR: f32 = 0.0025;

/// The bucket of angle `x` (any finite value).
#[inline(always)]
fn bucket(x: f32) -> usize {
    let u = (wrap(x) + PI) * (BUCKETS as f32 / (2.0 * PI));
    // `as` saturates (NaN to 0); the last bucket takes α = π.
    (u as usize).min(BUCKETS - 1)
}

impl Scratch {
    /// All zero, evaluated at compile time: each caller's frame gets one `memset` into its
    /// `Scratch`, not the arrays built in temporaries and copied in (3.3 KiB more of
    /// `register_sets_verified`'s frame on the firmware while `Search::step` also called this).
    const EMPTY: Self = Self {
        contrib: [[0.0; 6]; 2 * MAX_OBS],
        trusted: [false; 2 * MAX_OBS],
        curr_sc: [[0.0; 2]; MAX_OBS],
        prev_sc: [[0.0; 2]; MAX_OBS],
        buckets: [0; BUCKETS],
    };

    pub(super) const fn new() -> Self {
        Self::EMPTY
    }
}

/// The data of one registration.
pub(super) struct Work<'a> {
    prev: &'a Set,
    curr: &'a Set,
    cfg: &'a Config,
    #[allow(dead_code)]
    prior: Option<&'a Prior>,
    nc: usize,
    /// The previous lines in every bucket (a reach beyond [`MAX_REACH`], or not finite).
    wide: u64,
    /// The largest variance of α among the current lines, at most [`MAX_CURR_VAR`]: the
    /// index serves the current lines within it (the others try every previous line).
    curr_var: f32,
    s: &'a mut Scratch,
    /// Tests only: every previous line a candidate (the reference the index is held to).
    #[cfg(test)]
    pub(super) brute: bool,
}

impl<'a> Work<'a> {
    pub(super) fn new(
        prev: &'a Set,
        curr: &'a Set,
        cfg: &'a Config,
        prior: Option<&'a Prior>,
        s: &'a mut Scratch,
    ) -> Self {
        for (sc, l) in s.curr_sc.iter_mut().zip(curr.lines()) {
            let (sn, c) = sin_cos(l.a);
            *sc = [sn, c];
        }
        for (sc, l) in s.prev_sc.iter_mut().zip(prev.lines()) {
            let (sn, c) = sin_cos(l.a);
            *sc = [sn, c];
        }
        // The angle index, each line by its own reach (slack at most 1) for any current line
        // whose variance is at most `curr_var`.
        let curr_var = curr
            .lines()
            .iter()
            .map(|l| l.cov.a)
            .filter(|&v| v <= MAX_CURR_VAR)
            .fold(0.0f32, |m, v| if v > m { v } else { m });
        s.buckets = [0; BUCKETS];
        let mut wide = 0u64;
        let width = 2.0 * PI / BUCKETS as f32;
        let sa2 = cfg.slack[0] * cfg.slack[0];
        for (i, l) in prev.lines().iter().enumerate().take(64) {
            let bit = 1u64 << i;
            let reach = crate::geom::sqrt(cfg.gate * (l.cov.a + curr_var + sa2)) * 1.001 + 1e-4;
            if !(reach <= MAX_REACH) {
                wide |= bit;
                continue;
            }
            let from = crate::geom::floor((l.a - reach + PI) / width);
            let to = crate::geom::floor((l.a + reach + PI) / width);
            if !(from.is_finite() && to.is_finite()) {
                wide |= bit;
                continue;
            }
            // Within a turn either side (α is in (−π, π], but the index must not overflow).
            let turn = BUCKETS as f32;
            let (from, to) = (from.clamp(-turn, 2.0 * turn), to.clamp(-turn, 2.0 * turn));
            let (from, to) = (from as i32, to as i32);
            for b in from..=to.min(from.saturating_add(BUCKETS as i32)) {
                if let Some(m) = s.buckets.get_mut(b.rem_euclid(BUCKETS as i32) as usize) {
                    *m |= bit;
                }
            }
        }
        Self {
            prev,
            curr,
            cfg,
            prior,
            nc: 0,
            wide,
            curr_var,
            s,
            #[cfg(test)]
            brute: false,
        }
    }

    /// Sine and cosine of previous line `i`'s α.
    pub(super) fn prev_sc(&self, i: usize) -> [f32; 2] {
        self.s.prev_sc.get(i).copied().unwrap_or([0.0, 1.0])
    }

    /// Sine and cosine of current line `k`'s α.
    pub(super) fn curr_sc(&self, k: usize) -> [f32; 2] {
        self.s.curr_sc.get(k).copied().unwrap_or([0.0, 1.0])
    }

    /// The previous lines whose α may lie within their reach of `centre` or of `centre + π`
    /// (angles modulo 2π), as bits (bit `i`: line `i`), for a current line of α variance
    /// `var` at a slack at most 1: all of them otherwise.
    #[inline(always)]
    fn candidates(&self, centre: f32, var: f32, slack: f32) -> u64 {
        let nl = self.prev.lines().len().min(64);
        let all = if nl >= 64 { u64::MAX } else { (1u64 << nl) - 1 };
        #[cfg(test)]
        if self.brute {
            return all;
        }
        if !(var <= self.curr_var && slack <= 1.0 && centre.is_finite()) {
            return all;
        }
        let at = |x: f32| self.s.buckets.get(bucket(x)).copied().unwrap_or(u64::MAX);
        (at(centre) | at(centre + PI) | self.wide) & all
    }

    /// Matches every current feature to its nearest previous one under `pose` (Mahalanobis,
    /// with `slack` times the configured slack), and the normal equations of those matches.
    pub(super) fn associate(&mut self, pose: &Pose, slack: f32, out: Option<&mut Assoc>) -> Normal {
        self.associate_with::<true, true>(pose, slack, out)
    }

    /// [`Work::associate`] without recording each match's information (what a Gauss–Newton
    /// step needs: only [`finish`]'s association is searched for a critical match).
    fn associate_step(&mut self, pose: &Pose, slack: f32) -> Normal {
        self.associate_with::<true, false>(pose, slack, None)
    }

    /// The consensus score of [`Work::associate`] alone (bit for bit the same: the same
    /// matches, summed in the same order), without the normal equations.
    pub(super) fn score(&mut self, pose: &Pose, slack: f32) -> f32 {
        self.associate_with::<false, false>(pose, slack, None).score
    }

    /// [`Work::associate`]; with `FULL` false only the score (and the match counts) are
    /// computed; with `RECORD` (and `FULL`) each match's information is kept for
    /// [`Work::without_critical`].
    #[inline(always)]
    pub(super) fn associate_with<const FULL: bool, const RECORD: bool>(
        &mut self,
        pose: &Pose,
        slack: f32,
        mut out: Option<&mut Assoc>,
    ) -> Normal {
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
        // `pose.transform_point` with its sine and cosine computed once (the same arithmetic).
        let transform = |p: [f32; 2]| [ct * p[0] - st * p[1] + x, st * p[0] + ct * p[1] + y];
        let sa2 = (slack * cfg.slack[0]) * (slack * cfg.slack[0]);
        let curr = self.curr;
        for (k, lk) in curr.lines().iter().enumerate() {
            let sc = self.s.curr_sc.get(k).copied().unwrap_or([0.0, 1.0]);
            let a = lk.a + pose.theta;
            // sin, cos of α + θ from those of α and θ.
            let (sa, ca) = (sc[0] * ct + sc[1] * st, sc[1] * ct - sc[0] * st);
            let r = lk.r + x * ca + y * sa;
            let h = -x * sa + y * ca;
            // Covariance of the transformed line.
            let ct_ = Sym2 {
                a: lk.cov.a,
                b: lk.cov.b + h * lk.cov.a,
                c: lk.cov.c + 2.0 * h * lk.cov.b + h * h * lk.cov.a,
            };
            let sr = slack * (cfg.slack[1] + cfg.slack[2] * lk.reach);
            // The segment in the previous frame, when first needed.
            let mut ext_prev = None;
            let mut best: Option<(f32, u8, [f32; 2], Sym2, f32, f32)> = None;
            // Only the previous lines within the angle gate (either orientation) can match.
            let bits = self.candidates(a, ct_.a, slack);
            // As two 32-bit words: the Cortex-M4 has no 64-bit bit scan.
            let (mut lo, mut hi) = (bits as u32, (bits >> 32) as u32);
            loop {
                let i = if lo != 0 {
                    let t = lo.trailing_zeros();
                    lo &= lo - 1;
                    t as usize
                } else if hi != 0 {
                    let t = hi.trailing_zeros();
                    hi &= hi - 1;
                    32 + t as usize
                } else {
                    break;
                };
                let Ok(iu) = u8::try_from(i) else { break };
                let (Some(li), Some(psc)) = (self.prev.lines().get(i), self.s.prev_sc.get(i))
                else {
                    continue;
                };
                let var_a = ct_.a + li.cov.a + sa2;
                let var_r = ct_.c + li.cov.c + sr * sr;
                let (ga, gr) = (gate * var_a, gate * var_r);
                let (rp, rm) = (r - li.r, -r - li.r);
                if rp * rp > gr && rm * rm > gr {
                    continue;
                }
                // cos(a − α_i): the orientation.
                let dcos = ca * psc[1] + sa * psc[0];
                let sign = if dcos >= 0.0 { 1.0 } else { -1.0 };
                let ea = if sign > 0.0 {
                    wrap(a - li.a)
                } else {
                    wrap(a + PI - li.a)
                };
                if ea * ea > ga {
                    continue;
                }
                let er = sign * r - li.r;
                if er * er > gr {
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
                let ext = *ext_prev
                    .get_or_insert_with(|| lk.ext.map(|(s, e)| (transform(s), transform(e))));
                let Some(frac) = overlap(ext, li, *psc, cfg.overlap_slack + sr) else {
                    continue;
                };
                // The nearest; the lowest index among equals (the order of the scan).
                if best.is_none_or(|b| d2 < b.0 || (d2 == b.0 && iu < b.1)) {
                    best = Some((d2, iu, e, w, sign, frac));
                }
            }
            if let Some(o) = out.as_deref_mut() {
                if let Some(slot) = o.lines.get_mut(k) {
                    *slot = best.map_or(NONE, |b| b.1);
                }
            }
            let Some((d2, i, e, w, sign, frac)) = best else {
                continue;
            };
            if !FULL {
                n.lines += 1;
                n.score +=
                    (1.0 - d2 / gate) * (1.0 - cfg.overlap_weight + cfg.overlap_weight * frac);
                continue;
            }
            n.lines += 1;
            n.score += (1.0 - d2 / gate) * (1.0 - cfg.overlap_weight + cfg.overlap_weight * frac);
            n.chi2 += d2;
            // Jacobian rows: e_α = [0, 0, 1]; e_ρ = sign · [cos a, sin a, h].
            let ja = [0.0, 0.0, 1.0];
            let jr = [sign * ca, sign * sa, sign * h];
            let hi = accumulate(&mut n, &ja, &jr, &w, &e);
            if RECORD {
                let length = |ext: Option<([f32; 2], [f32; 2])>| {
                    ext.map_or(0.0, |(s, e)| {
                        let d = [e[0] - s[0], e[1] - s[1]];
                        crate::geom::sqrt(d[0] * d[0] + d[1] * d[1])
                    })
                };
                let prev_len = self
                    .prev
                    .lines()
                    .get(usize::from(i))
                    .map_or(0.0, |l| length(l.ext));
                let trusted = length(lk.ext).min(prev_len) >= cfg.trusted_length;
                self.record(hi, trusted);
            }
        }
        for (k, pk) in self.curr.pts().iter().enumerate() {
            let q = transform(pk.p);
            let cq = pk.cov.rotate(st, ct);
            let reach = crate::geom::sqrt(pk.p[0] * pk.p[0] + pk.p[1] * pk.p[1]);
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
            if !FULL {
                continue;
            }
            n.chi2 += d2;
            let jx = [1.0, 0.0, -st * pk.p[0] - ct * pk.p[1]];
            let jy = [0.0, 1.0, ct * pk.p[0] - st * pk.p[1]];
            let hi = accumulate(&mut n, &jx, &jy, &w, &e);
            if RECORD {
                self.record(hi, false);
            }
        }
        n
    }
}

impl Work<'_> {
    fn record(&mut self, hi: Cov3, trusted: bool) {
        if let (Some(slot), Some(t)) = (
            self.s.contrib.get_mut(self.nc),
            self.s.trusted.get_mut(self.nc),
        ) {
            *slot = [hi[0][0], hi[0][1], hi[0][2], hi[1][1], hi[1][2], hi[2][2]];
            *t = trusted;
            self.nc += 1;
        }
    }

    /// The information of the last association without its most critical match: the one
    /// whose removal leaves the smallest least eigenvalue (scaled units). A direction that
    /// one match alone determines is not confirmed by any other.
    fn without_critical(&self, h: &Cov3) -> Cov3 {
        let mut worst = *h;
        let mut least = f32::INFINITY;
        for (hi, _) in self
            .s
            .contrib
            .iter()
            .zip(&self.s.trusted)
            .take(self.nc)
            .filter(|(_, &t)| !t)
        {
            let [a, b, c, d, e, f] = *hi;
            let hi = [[a, b, c], [b, d, e], [c, e, f]];
            let mut r = *h;
            for (row, hr) in r.iter_mut().zip(&hi) {
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
#[inline(always)]
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

/// `None` when the segment `ext` (in the previous frame) and `li`'s segment (`sc`: sine and
/// cosine of its α) are farther apart
/// along `li` than `slack`; otherwise the length of their overlap over the shorter one's (1
/// when either has no extent).
#[inline(always)]
fn overlap(ext: Option<([f32; 2], [f32; 2])>, li: &Line, sc: [f32; 2], slack: f32) -> Option<f32> {
    // `f32::min` and `f32::max` (the other one when one is NaN; either of ±0), without a call
    // to the soft `fminf`/`fmaxf` the Cortex-M4F would make.
    let min = |a: f32, b: f32| if a < b || b.is_nan() { a } else { b };
    let max = |a: f32, b: f32| if a > b || b.is_nan() { a } else { b };
    let (Some((s, e)), Some((ps, pe))) = (ext, li.ext) else {
        return Some(1.0);
    };
    let [sa, ca] = sc;
    let along = |p: [f32; 2]| -sa * p[0] + ca * p[1];
    let (a0, a1) = (along(s), along(e));
    let (b0, b1) = (along(ps), along(pe));
    let (alo, ahi) = (min(a0, a1), max(a0, a1));
    let (blo, bhi) = (min(b0, b1), max(b0, b1));
    let gap = max(alo, blo) - min(ahi, bhi);
    if !(gap <= slack) {
        return None;
    }
    let shorter = max(min(ahi - alo, bhi - blo), 1.0);
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

/// Gauss–Newton from `start`, then [`finish`]ed (fully when `full`).
pub(super) fn refine(w: &mut Work, start: Pose, prior: Option<&Prior>, full: bool) -> Refined {
    let pose = converge(w, start, prior, &[]).unwrap_or(start);
    finish(w, pose, prior, full, None)
}

/// A refinement this near a pose already refined (mm, rad) converges onto it: the same
/// solution, not refined again.
const CONVERGED_MM: f32 = 30.0;
const CONVERGED_RAD: f32 = 0.01;

/// The Gauss–Newton of [`refine`] from `start`: the pose it converges to, or `None` as soon
/// as a step lands within [`CONVERGED_MM`] and [`CONVERGED_RAD`] of one of `done` (the
/// poses other hypotheses were refined to: the same solution again).
/// Not inlined (twice) into the registration's frame.
#[inline(never)]
pub(super) fn converge(
    w: &mut Work,
    start: Pose,
    prior: Option<&Prior>,
    done: &[Hyp],
) -> Option<Pose> {
    let mut gn = Converging::new(start);
    loop {
        if let Some(end) = gn.step(w, prior, done) {
            return end;
        }
    }
}

/// A [`converge`] under way: the pose reached and the steps taken.
#[derive(Clone, Copy, Debug)]
pub(super) struct Converging {
    pose: Pose,
    stage: usize,
}

impl Converging {
    pub(super) const fn new(start: Pose) -> Self {
        Self {
            pose: start,
            stage: 0,
        }
    }

    /// One Gauss–Newton step (one association): `None` while it goes on, else what
    /// [`converge`] returns. Inlined: [`converge`]'s frame is all the stack it takes.
    #[inline(always)]
    pub(super) fn step(
        &mut self,
        w: &mut Work,
        prior: Option<&Prior>,
        done: &[Hyp],
    ) -> Option<Option<Pose>> {
        if self.stage >= ITERATIONS {
            return Some(Some(self.pose));
        }
        let cfg = w.cfg;
        let slacks = [1.0, 0.5, 0.25, 0.1, 0.0];
        let limit = 1.0 / (cfg.degenerate_sigma * cfg.degenerate_sigma);
        let pose = self.pose;
        let slack = slacks.get(self.stage).copied().unwrap_or(0.0);
        let mut n = w.associate_step(&pose, slack);
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
            return Some(Some(pose));
        }
        let pose = Pose::new(pose.x + step[0], pose.y + step[1], pose.theta + step_theta);
        self.pose = pose;
        let near = |d: &Hyp| {
            (d.pose.x - pose.x).abs() < CONVERGED_MM
                && (d.pose.y - pose.y).abs() < CONVERGED_MM
                && wrap(d.pose.theta - pose.theta).abs() < CONVERGED_RAD
        };
        if done.iter().any(near) {
            return Some(None);
        }
        let small = crate::geom::hypot(step[0], step[1]) < 0.05 && step_theta.abs() < 5e-5;
        if small && slack == 0.0 {
            return Some(Some(pose));
        }
        self.stage += 1;
        (self.stage >= ITERATIONS).then_some(Some(pose))
    }
}

/// The final association at `pose` (its matches into `out`) and, when `full`, the
/// covariance and status; otherwise only the score, the match counts and the pose (the
/// covariances zero).
pub(super) fn finish(
    w: &mut Work,
    pose: Pose,
    prior: Option<&Prior>,
    full: bool,
    out: Option<&mut Assoc>,
) -> Refined {
    let cfg = w.cfg;
    let limit = 1.0 / (cfg.degenerate_sigma * cfg.degenerate_sigma);
    if !full {
        let n = w.associate_with::<false, false>(&pose, 0.0, out);
        return Refined {
            pose,
            cov: ZERO3,
            cov_scene_pinv: ZERO3,
            score: n.score,
            chi2: 0.0,
            matches: (n.lines, n.pts),
            unobservable: None,
            scene_degenerate: false,
        };
    }
    let mut n = w.associate(&pose, 0.0, out);
    let (vals, vecs) = eigen_sym3(&to_scaled_info(&n.h));
    let scene_degenerate = !(vals[0] > limit);
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
    Refined {
        pose,
        cov,
        cov_scene_pinv: cov_scene,
        score: n.score,
        chi2: n.chi2,
        matches: (n.lines, n.pts),
        unobservable,
        scene_degenerate,
    }
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

#[cfg(test)]
mod index_tests;

#[cfg(test)]
mod converge_tests;
