//! The least-squares estimate of one sweep's offset ([`super::estimate`]): the rows of its
//! beams on smooth surfaces, two solutions of their normal equations (the second without the
//! rows beyond 3σ of the first), and the offset with its covariance.

use super::{SweepOffset, MAX_ROWS};
use crate::geometry::Point;
use crate::math;

/// The offset of sweep `sweep` of `sweeps` ([`super::estimate`], whose guards it follows): two
/// solutions, the second without the rows beyond 3σ of the first (their residuals at it kept
/// from its own pass over them).
pub(super) fn offset_of(
    points: &[Point],
    (sweeps, sweep): (usize, usize),
    step: f32,
) -> Option<SweepOffset> {
    let mut rows = Rows {
        points,
        sweeps,
        sweep,
        step,
    }
    .table();
    let mut at = [0.0f32; MAX_ROWS];
    let first = normal(&rows, 0.0, &mut at)?;
    let cut = 3.0 * first.sigma.max(SIGMA_FLOOR);
    // The rows within the cut, in their order (NaN is not within).
    let mut at_first = at.iter();
    rows.rows
        .retain(|_| at_first.next().is_some_and(|r| math::abs(*r) <= cut));
    let sol = normal(&rows, first.x[2] / ROT_SCALE, &mut at)?;
    Some(offset(&sol, first.far))
}

/// One row of the least-squares problem `J·x = −e`, `x = (dx, dy, sin dθ · 1000 mm)`: `J`,
/// `e`, and `n·q` (for the second-order term of the rotation).
type Row = [f32; 5];

/// Residual floor, mm (the 1 mm range quantum's standard deviation, about 0.3 mm).
const SIGMA_FLOOR: f32 = 0.3;
/// Scale of the rotation unknown: `x₃ = dθ · ROT_SCALE` is in mm at 1 m.
const ROT_SCALE: f32 = 1000.0;

/// The equations of sweep `sweep`'s beams on smooth surfaces, evenly subsampled to at most
/// [`MAX_ROWS`] ([`Rows::table`]).
#[derive(Clone, Copy)]
struct Rows<'a> {
    points: &'a [Point],
    sweeps: usize,
    sweep: usize,
    step: f32,
}

/// The rows of a sweep, made once for the passes over them (each solution's sums and
/// residuals; the second solution's are those the first kept), and the largest range of their
/// beams, mm.
struct Table {
    /// Not zeroed first (1.3 KB a sweep).
    rows: heapless::Vec<Row, MAX_ROWS>,
    far: f32,
}

impl Table {
    /// No rows yet.
    fn empty() -> Self {
        Table {
            rows: heapless::Vec::new(),
            far: 0.0,
        }
    }

    /// The rows, in the order they were made.
    fn rows(&self) -> &[Row] {
        &self.rows
    }
}

impl Rows<'_> {
    /// Every row, and the largest range of their beams: [`Self::table_lanes`] where the square
    /// root vectorises (`std`), [`Self::table_each`] elsewhere (the same rows).
    fn table(&self) -> Table {
        #[cfg(feature = "std")]
        {
            self.table_lanes()
        }
        #[cfg(not(feature = "std"))]
        {
            self.table_each()
        }
    }

    /// [`Self::table`] one candidate beam at a time ([`row`]): candidate j's beams are the
    /// first, the `sweep`-th, the `sweeps`-th and the last of the 2·`sweeps` + 1 points from
    /// `sweeps`·j (every one within the scan: [`Rows::plan`]), read from that window without a
    /// test of the scan's end each.
    #[cfg_attr(feature = "std", allow(dead_code))]
    fn table_each(&self) -> Table {
        let mut t = Table::empty();
        let Plan {
            triples,
            stride,
            curve,
            reach,
        } = self.plan();
        let (sweeps, s) = (self.sweeps, self.sweep);
        let candidates = self
            .points
            .windows(2 * sweeps + 1)
            .step_by((sweeps * stride).max(1))
            .take(triples.div_ceil(stride));
        for w in candidates {
            let (Some(&a), Some(&q), Some(&b), Some(&c)) =
                (w.first(), w.get(s), w.get(sweeps), w.last())
            else {
                continue;
            };
            if let Some((row, range)) = row(a, q, b, c, curve, reach) {
                // `range` is positive (a row's chord is shorter than a positive multiple of
                // it), `far` never NaN: the larger without `f32::max`'s NaN tests (a libm call
                // on thumbv7em).
                if t.rows.push(row).is_ok() && range > t.far {
                    t.far = range;
                }
            }
        }
        t
    }

    /// [`Self::table`] [`LANES`] candidate beams at a time, each one's arithmetic without a
    /// branch ([`Block`]), so that LLVM computes a few at once; then the rows of those
    /// that pass, in order: the rows of [`Self::table_each`], bit for bit.
    #[cfg_attr(not(feature = "std"), allow(dead_code))]
    fn table_lanes(&self) -> Table {
        let mut t = Table::empty();
        let Plan {
            triples,
            stride,
            curve,
            reach,
        } = self.plan();
        // Candidate j's beams a, q, b, c are the first, the `sweep`-th, the `sweeps`-th and the
        // last of the 2·`sweeps` + 1 points from `sweeps`·j.
        let (sweeps, s) = (self.sweeps, self.sweep);
        let mut candidates = self
            .points
            .windows(2 * sweeps + 1)
            .step_by(sweeps * stride)
            .take(triples.div_ceil(stride))
            .peekable();
        while candidates.peek().is_some() {
            // The block's beams, coordinate by coordinate: a.x, a.y, q.x, q.y, b.x, b.y, c.x,
            // c.y (invalid past the last candidate).
            let mut xy = [[f32::NAN; LANES]; 8];
            let mut n = 0;
            for (l, w) in candidates.by_ref().take(LANES).enumerate() {
                let at = |k: usize| w.get(k).copied().unwrap_or(Point::INVALID);
                let (a, q, b, c) = (at(0), at(s), at(sweeps), at(2 * sweeps));
                let [ax, ay, qx, qy, bx, by, cx, cy] = &mut xy;
                for (lane, v) in [ax, ay, qx, qy, bx, by, cx, cy]
                    .into_iter()
                    .zip([a.x, a.y, q.x, q.y, b.x, b.y, c.x, c.y])
                {
                    if let Some(slot) = lane.get_mut(l) {
                        *slot = v;
                    }
                }
                n = l + 1;
            }
            let block = Block::of(&xy, curve, reach);
            for l in 0..n {
                if let Some((row, range)) = block.row(l) {
                    if t.rows.push(row).is_ok() {
                        t.far = t.far.max(range);
                    }
                }
            }
        }
        t
    }

    /// The candidate beams of the sweep: every `stride`-th of the `triples`, at most
    /// [`MAX_ROWS`]; `curve`, the sagitta's factor at the sweep's fraction; `reach`, the jump
    /// bound of the chord against the beam's range.
    fn plan(&self) -> Plan {
        let (points, sweeps, s) = (self.points, self.sweeps, self.sweep);
        let pairs = points
            .len()
            .saturating_sub(1)
            .checked_div(sweeps)
            .unwrap_or(0);
        // Sweep-0 triples (a, b, c) need c = S·(j + 2): `pairs − 1` of them.
        let triples = pairs.saturating_sub(1);
        let f_s = s as f32 / sweeps as f32;
        Plan {
            triples,
            stride: triples.div_ceil(MAX_ROWS).max(1),
            curve: f_s * (2.0 - f_s),
            // A chord longer than this many times its length at normal incidence is a jump.
            reach: 16.0 * math::abs(self.step) * sweeps as f32,
        }
    }
}

/// What [`Rows::plan`] gives.
struct Plan {
    triples: usize,
    stride: usize,
    curve: f32,
    reach: f32,
}

/// Candidate beams [`Rows::table_lanes`] takes at a time.
const LANES: usize = 8;

/// The row of beam `q` between sweep-0 beams `a` and `b` (and `c` after `b`), when the
/// surface there is smooth: distances from the chord `ac` (unit normal `n`), `e` of `q` and
/// `e₀` of `b`. On a circle through `a`, `b`, `c`, `q` at fraction `f / 2` of the chord lies
/// `f(2 − f)·e₀` from it, which the row removes.
#[inline]
fn row(a: Point, q: Point, b: Point, c: Point, curve: f32, reach: f32) -> Option<(Row, f32)> {
    let (cx, cy) = (c.x - a.x, c.y - a.y);
    let len = math::hypot(cx, cy);
    let rq = math::hypot(q.x, q.y);
    // NaN (an invalid point) fails every comparison.
    if !(len > 0.0 && len < reach * rq) {
        return None;
    }
    let (nx, ny) = (-cy / len, cx / len);
    let e = (q.x - a.x) * nx + (q.y - a.y) * ny;
    let e0 = (b.x - a.x) * nx + (b.y - a.y) * ny;
    let rhs = e - curve * e0;
    if !(math::abs(e0) < 0.15 * len + 30.0 && math::abs(rhs) < 0.25 * len + 40.0) {
        return None;
    }
    let j3 = (ny * q.x - nx * q.y) / ROT_SCALE;
    Some(([nx, ny, j3, rhs, nx * q.x + ny * q.y], rq))
}

/// [`LANES`] candidates' rows ([`row`]) computed lane by lane without a branch: the same tests
/// and the same arithmetic, so the same bits where a candidate gives a row.
struct Block {
    /// nx, ny, j3, rhs, n·q: a row's columns.
    row: [[f32; LANES]; 5],
    /// The range of `q`.
    range: [f32; LANES],
    /// Whether the candidate gives a row.
    ok: [bool; LANES],
}

impl Block {
    /// The rows of the candidates whose `a`, `q`, `b`, `c` are in `xy` coordinate by coordinate
    /// ([`Rows::table_lanes`]).
    #[inline(always)]
    fn of(xy: &[[f32; LANES]; 8], curve: f32, reach: f32) -> Self {
        let [ax, ay, qx, qy, bx, by, cx, cy] = xy;
        let mut out = Block {
            row: [[0.0; LANES]; 5],
            range: [0.0; LANES],
            ok: [false; LANES],
        };
        let [nxs, nys, j3s, rhss, nqs] = &mut out.row;
        for l in 0..LANES {
            // In bounds (l < LANES): the tests compile away.
            let (Some(&ax), Some(&ay), Some(&qx), Some(&qy)) =
                (ax.get(l), ay.get(l), qx.get(l), qy.get(l))
            else {
                continue;
            };
            let (Some(&bx), Some(&by), Some(&cx), Some(&cy)) =
                (bx.get(l), by.get(l), cx.get(l), cy.get(l))
            else {
                continue;
            };
            let (dx, dy) = (cx - ax, cy - ay);
            let len = math::sqrt_lanes(dx * dx + dy * dy);
            let rq = math::sqrt_lanes(qx * qx + qy * qy);
            let (nx, ny) = (-dy / len, dx / len);
            let e = (qx - ax) * nx + (qy - ay) * ny;
            let e0 = (bx - ax) * nx + (by - ay) * ny;
            let rhs = e - curve * e0;
            let row = [
                nx,
                ny,
                (ny * qx - nx * qy) / ROT_SCALE,
                rhs,
                nx * qx + ny * qy,
            ];
            for (column, v) in [&mut *nxs, &mut *nys, &mut *j3s, &mut *rhss, &mut *nqs]
                .into_iter()
                .zip(row)
            {
                if let Some(slot) = column.get_mut(l) {
                    *slot = v;
                }
            }
            if let (Some(range), Some(ok)) = (out.range.get_mut(l), out.ok.get_mut(l)) {
                *range = rq;
                *ok = (len > 0.0)
                    & (len < reach * rq)
                    & (math::abs(e0) < 0.15 * len + 30.0)
                    & (math::abs(rhs) < 0.25 * len + 40.0);
            }
        }
        out
    }

    /// Candidate `l`'s row and range, when it gives one.
    fn row(&self, l: usize) -> Option<(Row, f32)> {
        let [nx, ny, j3, rhs, nq] = &self.row;
        match self.ok.get(l) {
            Some(true) => Some((
                [
                    *nx.get(l)?,
                    *ny.get(l)?,
                    *j3.get(l)?,
                    *rhs.get(l)?,
                    *nq.get(l)?,
                ],
                *self.range.get(l)?,
            )),
            _ => None,
        }
    }
}

/// The offset of a solution; `far` is the largest range of the sweep's rows, mm.
fn offset(sol: &Solution, far: f32) -> SweepOffset {
    let [dx, dy, t] = sol.x;
    let sigma = sol.sigma.max(SIGMA_FLOOR);
    let [i00, _, _, i11, _, i22] = sol.inv;
    // χ² = xᵀ A x / σ².
    let [a00, a01, a02, a11, a12, a22] = sol.a;
    let quad = dx * (a00 * dx + a01 * dy + a02 * t)
        + dy * (a01 * dx + a11 * dy + a12 * t)
        + t * (a02 * dx + a12 * dy + a22 * t);
    let dtheta = t / ROT_SCALE;
    SweepOffset {
        dx,
        dy,
        dtheta,
        sd: [
            sigma * math::sqrt(i00),
            sigma * math::sqrt(i11),
            sigma * math::sqrt(i22) / ROT_SCALE,
        ],
        sigma,
        chi2: quad / (sigma * sigma),
        rows: u16::try_from(sol.rows).unwrap_or(u16::MAX),
        max_shift: math::hypot(dx, dy) + math::abs(dtheta) * far,
    }
}

/// A least-squares solution: the unknowns, the normal matrix and its inverse (upper
/// triangles, row by row: 00 01 02 11 12 22), the residual standard deviation, the rows used
/// and the farthest beam of all.
struct Solution {
    x: [f32; 3],
    a: [f32; 6],
    inv: [f32; 6],
    sigma: f32,
    rows: usize,
    /// The largest range among the rows' beams, mm (all of them, kept or not).
    far: f32,
}

/// Residual of `row` at `x` (first order).
#[inline]
fn residual(row: &Row, x: &[f32; 3]) -> f32 {
    let [j0, j1, j2, e, _] = *row;
    e + j0 * x[0] + j1 * x[1] + j2 * x[2]
}

/// Solves the normal equations of `rows`, with the second-order term `(cos θ − 1)·n·q` of a
/// rotation by about `theta` moved to `e`; writes each row's first-order residual at the
/// solution into `residuals`.
fn normal(rows: &Table, theta: f32, residuals: &mut [f32; MAX_ROWS]) -> Option<Solution> {
    let bend = -0.5 * theta * theta;
    let mut a = [0.0f32; 6];
    let mut g = [0.0f32; 3];
    for r in rows.rows() {
        let [j0, j1, j2, e, nq] = *r;
        let e = e + bend * nq;
        a = [
            a[0] + j0 * j0,
            a[1] + j0 * j1,
            a[2] + j0 * j2,
            a[3] + j1 * j1,
            a[4] + j1 * j2,
            a[5] + j2 * j2,
        ];
        g = [g[0] - j0 * e, g[1] - j1 * e, g[2] - j2 * e];
    }
    let used = rows.rows().len();
    if used < 6 {
        return None;
    }
    let inv = invert(&a)?;
    let x = [
        inv[0] * g[0] + inv[1] * g[1] + inv[2] * g[2],
        inv[1] * g[0] + inv[3] * g[1] + inv[4] * g[2],
        inv[2] * g[0] + inv[4] * g[1] + inv[5] * g[2],
    ];
    let mut ss = 0.0f32;
    for (r, at) in rows.rows().iter().zip(residuals.iter_mut()) {
        *at = residual(r, &x);
        let res = *at + bend * r[4];
        ss += res * res;
    }
    let sigma = math::sqrt(ss / (used - 3) as f32);
    Some(Solution {
        x,
        a,
        inv,
        sigma,
        rows: used,
        far: rows.far,
    })
}

/// Inverse of the symmetric 3 × 3 matrix `a` (upper triangle, row by row), `None` when it is
/// (nearly) singular: the geometry does not fix all three unknowns.
fn invert(a: &[f32; 6]) -> Option<[f32; 6]> {
    let [a00, a01, a02, a11, a12, a22] = *a;
    let c00 = a11 * a22 - a12 * a12;
    let c01 = a02 * a12 - a01 * a22;
    let c02 = a01 * a12 - a02 * a11;
    let det = a00 * c00 + a01 * c01 + a02 * c02;
    if !(det > 1e-4 * a00 * a11 * a22) {
        return None;
    }
    let c11 = a00 * a22 - a02 * a02;
    let c12 = a01 * a02 - a00 * a12;
    let c22 = a00 * a11 - a01 * a01;
    Some([
        c00 / det,
        c01 / det,
        c02 / det,
        c11 / det,
        c12 / det,
        c22 / det,
    ])
}

#[cfg(test)]
mod tests;
