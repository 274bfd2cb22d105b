//! A scan's observations in fixed-capacity arrays, checked and with the model noise floor
//! added: what the registration works on.

use crate::geom::Sym2;
use crate::obs::Observation;
use crate::Config;

/// Most lines, and most points, of one scan (or of the odometry's map) the registration uses;
/// further ones are counted in [`crate::Registration::dropped`].
pub const MAX_OBS: usize = 64;

/// A line ready for matching.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Line {
    pub a: f32,
    pub r: f32,
    /// Covariance of (α, ρ), floor included.
    pub cov: Sym2,
    /// Segment ends (`None`: infinite line).
    pub ext: Option<([f32; 2], [f32; 2])>,
    /// Distance of the segment's middle (or of the line) from the scanner, mm.
    pub reach: f32,
    /// Preference for building hypotheses (higher first): the segment's length.
    pub rank: f32,
}

/// A point ready for matching.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Pt {
    pub p: [f32; 2],
    pub cov: Sym2,
    pub rank: f32,
}

/// An unused slot (never read: only the first `nl` are), all zero bytes (a `static`
/// odometry goes to `.bss`).
const NO_LINE: Line = Line {
    a: 0.0,
    r: 0.0,
    cov: Sym2 {
        a: 0.0,
        b: 0.0,
        c: 0.0,
    },
    ext: None,
    reach: 0.0,
    rank: 0.0,
};

/// An unused slot, all zero bytes (as [`NO_LINE`]).
const NO_PT: Pt = Pt {
    p: [0.0; 2],
    cov: Sym2 {
        a: 0.0,
        b: 0.0,
        c: 0.0,
    },
    rank: 0.0,
};

/// The observations of one scan.
#[derive(Clone, Debug)]
pub(crate) struct Set {
    lines: [Line; MAX_OBS],
    nl: usize,
    pts: [Pt; MAX_OBS],
    np: usize,
    /// Valid observations left out for want of room.
    pub dropped: u16,
    /// Invalid observations ignored.
    pub invalid: u16,
}

impl Set {
    pub const fn new() -> Self {
        Self {
            lines: [NO_LINE; MAX_OBS],
            nl: 0,
            pts: [NO_PT; MAX_OBS],
            np: 0,
            dropped: 0,
            invalid: 0,
        }
    }

    /// Empties the set (its slots are overwritten as observations are pushed).
    pub fn clear(&mut self) {
        self.nl = 0;
        self.np = 0;
        self.dropped = 0;
        self.invalid = 0;
    }

    pub fn lines(&self) -> &[Line] {
        self.lines.get(..self.nl).unwrap_or(&[])
    }

    pub fn pts(&self) -> &[Pt] {
        self.pts.get(..self.np).unwrap_or(&[])
    }

    pub fn len(&self) -> usize {
        self.nl + self.np
    }

    /// The valid observations of `obs` with the floor of `cfg` added.
    pub fn from_obs(obs: impl IntoIterator<Item = Observation>, cfg: &Config) -> Self {
        let mut s = Self::new();
        for o in obs {
            if !o.is_valid() {
                s.invalid = s.invalid.saturating_add(1);
                continue;
            }
            match o {
                Observation::Line(l) => {
                    let ext = l.has_extent().then_some((l.start, l.end));
                    let cov = Sym2 {
                        a: l.cov[0][0],
                        b: 0.5 * (l.cov[0][1] + l.cov[1][0]),
                        c: l.cov[1][1],
                    };
                    s.push_line(l.alpha, l.rho, cov, ext, l.length(), Some(cfg));
                }
                Observation::Point(p) => {
                    let cov = Sym2 {
                        a: p.cov[0][0],
                        b: 0.5 * (p.cov[0][1] + p.cov[1][0]),
                        c: p.cov[1][1],
                    };
                    s.push_pt([p.x, p.y], cov, 1.0, Some(cfg));
                }
            }
        }
        s
    }

    /// Adds a line (with the floor of `floor`, if given); false (and counted) when full.
    pub fn push_line(
        &mut self,
        a: f32,
        r: f32,
        cov: Sym2,
        ext: Option<([f32; 2], [f32; 2])>,
        rank: f32,
        floor: Option<&Config>,
    ) -> bool {
        let (a, r) = crate::geom::normalise_line(a, r);
        let cov = match floor {
            Some(cfg) => cov.add(Sym2 {
                a: cfg.line_floor[0] * cfg.line_floor[0],
                b: 0.0,
                c: cfg.line_floor[1] * cfg.line_floor[1],
            }),
            None => cov,
        };
        let reach = match ext {
            Some((s, e)) => crate::geom::hypot(0.5 * (s[0] + e[0]), 0.5 * (s[1] + e[1])),
            None => r,
        };
        let Some(slot) = self.lines.get_mut(self.nl) else {
            self.dropped = self.dropped.saturating_add(1);
            return false;
        };
        *slot = Line {
            a,
            r,
            cov,
            ext,
            reach,
            rank,
        };
        self.nl += 1;
        true
    }

    /// Adds a point (with the floor of `floor`, if given); false (and counted) when full.
    pub fn push_pt(&mut self, p: [f32; 2], cov: Sym2, rank: f32, floor: Option<&Config>) -> bool {
        let cov = match floor {
            Some(cfg) => {
                let f = cfg.point_floor * cfg.point_floor;
                cov.add(Sym2 { a: f, b: 0.0, c: f })
            }
            None => cov,
        };
        let Some(slot) = self.pts.get_mut(self.np) else {
            self.dropped = self.dropped.saturating_add(1);
            return false;
        };
        *slot = Pt { p, cov, rank };
        self.np += 1;
        true
    }
}

/// The indices of the (at most `K`) highest-ranked items, in decreasing rank.
pub(crate) fn top_k<const K: usize>(ranks: impl Iterator<Item = f32>) -> ([u8; K], usize) {
    let mut idx = [0u8; K];
    let mut val = [f32::NEG_INFINITY; K];
    let mut n = 0usize;
    for (i, r) in ranks.enumerate() {
        let Ok(i) = u8::try_from(i) else { break };
        let r = if r.is_finite() { r } else { 0.0 };
        // Insertion into the sorted prefix.
        let mut pos = n.min(K);
        while pos > 0 && val.get(pos - 1).is_some_and(|&v| v < r) {
            pos -= 1;
        }
        if pos >= K {
            continue;
        }
        let mut j = n.min(K - 1);
        while j > pos {
            if let (Some(&vi), Some(&ii)) = (val.get(j - 1), idx.get(j - 1)) {
                if let (Some(v), Some(x)) = (val.get_mut(j), idx.get_mut(j)) {
                    *v = vi;
                    *x = ii;
                }
            }
            j -= 1;
        }
        if let (Some(v), Some(x)) = (val.get_mut(pos), idx.get_mut(pos)) {
            *v = r;
            *x = i;
        }
        n = (n + 1).min(K);
    }
    (idx, n)
}

#[cfg(test)]
mod tests {
    use super::top_k;

    #[test]
    fn top_k_sorted() {
        let (idx, n) = top_k::<3>([1.0, 5.0, 3.0, 4.0, f32::NAN, 2.0].into_iter());
        assert_eq!((n, idx), (3, [1, 3, 2]));
        let (idx, n) = top_k::<4>([1.0, 2.0].into_iter());
        assert_eq!((n, &idx[..2]), (2, &[1u8, 0][..]));
    }
}

#[cfg(test)]
mod size {
    /// The stack a registration needs is dominated by two sets and one set of per-match
    /// informations (see the crate's README): keep them small.
    #[test]
    fn sets_stay_small() {
        let set = core::mem::size_of::<super::Set>();
        let work = 2 * super::MAX_OBS * core::mem::size_of::<crate::Cov3>();
        assert!(set <= 5 * 1024, "{set}");
        assert!(work <= 5 * 1024, "{work}");
    }
}
