//! The local map: its entries, their fusion with a scan's features and their replacement.

use core::f32::consts::PI;

use super::Odometry;
use crate::geom::{sin_cos, wrap, Pose, Sym2};
use crate::register::{Assoc, NONE};
use crate::set::{Set, MAX_OBS};

/// One feature of the map, in the odometry frame. A line is kept as its normal angle α and an
/// anchor point on it (near the segment's middle) with the covariance of (α, d), d the
/// normal offset at the anchor: unlike (α, ρ) about a far origin, well conditioned in f32
/// wherever the robot is.
#[derive(Clone, Copy, Debug)]
pub(super) struct Entry {
    /// Point (x, y), or a line's anchor point.
    pub(super) v: [f32; 2],
    /// A line's normal angle.
    pub(super) alpha: f32,
    /// Point: (x, y); line: (α, d).
    pub(super) cov: Sym2,
    /// Segment ends of a line (NaN: none).
    pub(super) ext: ([f32; 2], [f32; 2]),
    pub(super) line: bool,
    pub(super) seen: u16,
    pub(super) last: u32,
}

/// An unused map slot (never read: only the first `n` entries are), all zero bytes so that an
/// [`Odometry`] in a `static` goes to `.bss`.
pub(super) const EMPTY: Entry = Entry {
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

impl<const MAP: usize, const PTS: usize> Odometry<MAP, PTS> {
    /// The map in the frame of `predicted`, as the "previous scan" of a registration, with the
    /// map index of each of its lines and points.
    pub(super) fn map_in(
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
    pub(super) fn insert_all(&mut self, curr: &Set, ids: &Assoc, pose: &Pose, scan: u32) {
        self.insert_with(curr, ids, pose, scan, false);
    }

    /// [`Odometry::insert_all`], or with `replace` the matched map entries replaced by the
    /// scan's features rather than fused with them (the map's answer was refuted: what it
    /// matched is suspect).
    pub(super) fn insert_with(
        &mut self,
        curr: &Set,
        ids: &Assoc,
        pose: &Pose,
        scan: u32,
        replace: bool,
    ) {
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
                Some(e) if e.line && usize::from(id) < self.n && replace => *e = new,
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
                Some(e) if !e.line && usize::from(id) < self.n && replace => *e = new,
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

/// The line through `anchor` with normal angle `alpha` and covariance `cov` of (α, d) as
/// (α, ρ) with ρ ≥ 0 and the covariance of (α, ρ), in the frame the anchor is given in.
pub(super) fn anchor_to_line(alpha: f32, anchor: [f32; 2], cov: Sym2) -> (f32, f32, Sym2) {
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
