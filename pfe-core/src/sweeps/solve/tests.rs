//! The estimate's tests: its parts worked out by hand, and the fast paths held to the code
//! they replaced.

extern crate std;

use super::{
    invert, math, offset, residual, row, Block, Row, Rows, Solution, SweepOffset, Table, LANES,
    ROT_SCALE, SIGMA_FLOOR,
};
use crate::geometry::Point;
use std::vec::Vec;

/// An offset's χ² is `xᵀ A x / σ²` with the full symmetric normal matrix A (every
/// off-diagonal term counted twice), its standard errors `σ √(A⁻¹)ᵢᵢ` (the rotation's in
/// rad), and its largest shift `|(dx, dy)| + |dθ| · far`: worked out in f64.
#[test]
fn an_offsets_chi2_is_the_quadratic_form_of_its_normal_matrix() {
    let a = [4.0f32, 1.0, 0.5, 3.0, -0.25, 2.0];
    let inv = invert(&a).unwrap_or([f32::NAN; 6]);
    let sol = Solution {
        x: [2.0, -3.0, 1.5],
        a,
        inv,
        sigma: 2.0,
        rows: 100,
        far: 5000.0,
    };
    let off = offset(&sol, 5000.0);
    let m = [[4.0, 1.0, 0.5], [1.0, 3.0, -0.25], [0.5, -0.25, 2.0f64]];
    let x = [2.0, -3.0, 1.5f64];
    let quad: f64 = (0..3)
        .map(|i| (0..3).map(|j| x[i] * m[i][j] * x[j]).sum::<f64>())
        .sum();
    assert!(
        (f64::from(off.chi2) - quad / 4.0).abs() < 1e-4,
        "{} vs {}",
        off.chi2,
        quad / 4.0
    );
    let sd2 = 2.0 * f64::from(inv[5]).sqrt() / f64::from(ROT_SCALE);
    assert!((f64::from(off.sd[2]) - sd2).abs() < 1e-9, "{:?}", off.sd);
    assert!((f64::from(off.sd[0]) - 2.0 * f64::from(inv[0]).sqrt()).abs() < 1e-5);
    assert!((f64::from(off.sd[1]) - 2.0 * f64::from(inv[3]).sqrt()).abs() < 1e-5);
    let shift = 13f64.sqrt() + 1.5 / f64::from(ROT_SCALE) * 5000.0;
    assert!(
        (f64::from(off.max_shift) - shift).abs() < 1e-4,
        "{}",
        off.max_shift
    );
    assert_eq!((off.dx, off.dy, off.rows), (2.0, -3.0, 100));
}

/// The inverse of a symmetric 3 × 3 matrix, times the matrix, is the identity; a matrix
/// whose determinant is below 10⁻⁴ of its diagonal's product (unknowns 0 and 1 nearly the
/// same) has none. Diagonal 100, 100, 4: the bound is 4.
#[test]
fn invert_refuses_a_nearly_singular_matrix() {
    let full = |u: &[f32; 6]| {
        let [a, b, c, d, e, f] = *u;
        [[a, b, c], [b, d, e], [c, e, f]]
    };
    let a = [4.0f32, 1.0, 0.5, 3.0, -0.25, 2.0];
    let inv = invert(&a).unwrap_or([f32::NAN; 6]);
    let (m, n) = (full(&a), full(&inv));
    for (i, row) in m.iter().enumerate() {
        for j in 0..3 {
            let p: f32 = row.iter().zip(&n).map(|(a, col)| a * col[j]).sum();
            let want = if i == j { 1.0 } else { 0.0 };
            assert!((p - want).abs() < 1e-5, "({i}, {j}): {p}");
        }
    }
    // det = 4 · 10⁴ (1 − ρ²) against the bound 4: 1 − ρ² = 5·10⁻⁵ gives 2, 2·10⁻⁴ gives 8.
    let near = |one_minus_rho2: f32| {
        let rho = (1.0 - one_minus_rho2).sqrt();
        [100.0, 100.0 * rho, 0.0, 100.0, 0.0, 4.0]
    };
    assert!(invert(&near(5e-5)).is_none());
    assert!(invert(&near(2e-4)).is_some());
}

/// The normal equations as solved before the first solution's residuals were kept: solves those of `rows` (those within `cut` of the solution `x` when given),
/// with the second-order term `(cos θ − 1)·n·q` of a rotation by about `theta` moved to `e`.
fn normal_reference(rows: &Table, keep: Option<(&[f32; 3], f32)>, theta: f32) -> Option<Solution> {
    let bend = -0.5 * theta * theta;
    let kept = |r: &Row| keep.is_none_or(|(x, cut)| math::abs(residual(r, x)) <= cut);
    let mut a = [0.0f32; 6];
    let mut g = [0.0f32; 3];
    let mut used = 0usize;
    for r in rows.rows() {
        if !kept(r) {
            continue;
        }
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
        used += 1;
    }
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
    for r in rows.rows() {
        if kept(r) {
            let res = residual(r, &x) + bend * r[4];
            ss += res * res;
        }
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

/// The estimate as it was made before: each solution tests every row against the first
/// solution's cut itself.
fn reference(points: &[Point], sweeps: usize, sweep: usize, step: f32) -> Option<SweepOffset> {
    let rows = Rows {
        points,
        sweeps,
        sweep,
        step,
    }
    .table();
    let first = normal_reference(&rows, None, 0.0)?;
    let cut = 3.0 * first.sigma.max(SIGMA_FLOOR);
    let sol = normal_reference(&rows, Some((&first.x, cut)), first.x[2] / ROT_SCALE)?;
    Some(offset(&sol, first.far))
}

/// Every field of an offset, bit for bit (NaN and −0 included).
fn bits(o: &SweepOffset) -> [u32; 11] {
    let [s0, s1, s2] = o.sd;
    [
        o.dx.to_bits(),
        o.dy.to_bits(),
        o.dtheta.to_bits(),
        s0.to_bits(),
        s1.to_bits(),
        s2.to_bits(),
        o.sigma.to_bits(),
        o.chi2.to_bits(),
        u32::from(o.rows),
        o.max_shift.to_bits(),
        0,
    ]
}

fn lcg(seed: &mut u32) -> f32 {
    *seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
    (*seed >> 8) as f32 / (1u32 << 24) as f32
}

/// A scan of `seed`: a room (front wall, two side walls, a pillar) seen by `sweeps`
/// interleaved sweeps, sweep `s` from the pose `s · (dx, dy, dθ)` of a moving scanner; beams
/// unevenly spaced in some scans, range noise (quantised to mm in some), outliers and
/// invalid returns. Returns the points, the sweeps and the nominal bearing step.
fn scan(seed: u32) -> (Vec<Point>, usize, f32) {
    let mut r = seed.wrapping_mul(2_654_435_761).wrapping_add(12_345);
    let mut u = |lo: f32, hi: f32| lo + (hi - lo) * lcg(&mut r);
    let sweeps = [2usize, 2, 3, 4][(u(0.0, 4.0) as usize).min(3)];
    let n = [91usize, 181, 361, 401, 721][(u(0.0, 5.0) as usize).min(4)];
    let fov = if u(0.0, 1.0) < 0.5 { 180.0f32 } else { 100.0 }.to_radians();
    let step = fov / (n - 1) as f32;
    let jitter = if u(0.0, 1.0) < 0.35 {
        u(0.0, 0.45)
    } else {
        0.0
    };
    let (front, left, right) = (u(1500.0, 8000.0), u(800.0, 5000.0), u(800.0, 5000.0));
    let pillar = (
        Point::new(u(800.0, 4000.0), u(-1500.0, 1500.0)),
        u(60.0, 400.0),
    );
    let (dx, dy, dt) = (u(-25.0, 25.0), u(-25.0, 25.0), u(-0.012, 0.012));
    let sigma = u(0.0, 12.0);
    let quantised = u(0.0, 1.0) < 0.4;
    let (outliers, invalid) = (u(0.0, 0.12), u(0.0, 0.25));
    let mut points = Vec::with_capacity(n);
    for i in 0..n {
        let s = (i % sweeps) as f32;
        let bearing = -fov / 2.0 + (i as f32 + u(-jitter, jitter)) * step;
        let (ox, oy, th) = (s * dx, s * dy, s * dt);
        let (sn, cs) = (bearing + th).sin_cos();
        // Walls x = front, y = left, y = −right (world), from (ox, oy) along (cs, sn).
        let mut range = f32::INFINITY;
        if cs > 1e-6 {
            range = range.min((front - ox) / cs);
        }
        if sn > 1e-6 {
            range = range.min((left - oy) / sn);
        }
        if sn < -1e-6 {
            range = range.min((-right - oy) / sn);
        }
        let (c, rad) = pillar;
        let (px, py) = (c.x - ox, c.y - oy);
        let along = px * cs + py * sn;
        let off2 = px * px + py * py - along * along;
        if along > 0.0 && off2 < rad * rad {
            range = range.min(along - (rad * rad - off2).sqrt());
        }
        let mut range = range + (u(0.0, 1.0) + u(0.0, 1.0) + u(0.0, 1.0) - 1.5) * 2.0 * sigma;
        if quantised {
            range = range.round();
        }
        if u(0.0, 1.0) < outliers {
            range = u(100.0, 8000.0);
        }
        let (bs, bc) = (-fov / 2.0 + i as f32 * step).sin_cos();
        let p = match u(0.0, 1.0) < invalid || !(range > 0.0 && range < 30_000.0) {
            true => Point::INVALID,
            false => Point::new(range * bc, range * bs),
        };
        points.push(p);
    }
    (points, sweeps, step)
}

/// The estimate keeps the first solution's residuals for the second's cut: bit for bit the
/// estimate that tests every row again, over 3 000 scans of 2 to 4 sweeps (uneven beams,
/// outliers, invalid returns), where most sweeps are estimated, some without the rows of
/// their outliers and some not at all.
#[test]
fn the_kept_residuals_give_the_estimate_bit_for_bit() {
    let (mut some, mut none, mut cut) = (0, 0, 0);
    for seed in 0..3_000 {
        let (points, sweeps, step) = scan(seed);
        for sweep in 1..sweeps {
            let got = super::offset_of(&points, (sweeps, sweep), step);
            let want = reference(&points, sweeps, sweep, step);
            assert_eq!(got.map(|o| bits(&o)), want.map(|o| bits(&o)), "scan {seed}");
            match want {
                Some(o) => {
                    some += 1;
                    let rows = Rows {
                        points: &points,
                        sweeps,
                        sweep,
                        step,
                    }
                    .table();
                    cut += usize::from(usize::from(o.rows) < rows.rows().len());
                }
                None => none += 1,
            }
        }
    }
    assert!(
        some > 3_000 && none > 100 && cut > 1_000,
        "{some} {none} {cut}"
    );
}

/// The rows taken eight candidate beams at a time are those taken one at a time, bit for
/// bit, with the same farthest range, over 3 000 scans of 2 to 4 sweeps (uneven beams,
/// outliers, invalid returns) and scans cut short of a block of eight.
#[test]
fn the_rows_in_lanes_are_the_rows_one_at_a_time() {
    let bits =
        |t: &Table| -> Vec<[u32; 5]> { t.rows().iter().map(|r| r.map(f32::to_bits)).collect() };
    let (mut rows, mut tables) = (0, 0);
    for seed in 0..3_000 {
        let (points, sweeps, step) = scan(seed);
        let cut = points.len() - (seed as usize % 40);
        for points in [&points[..], &points[..cut]] {
            for sweep in 1..sweeps {
                let r = Rows {
                    points,
                    sweeps,
                    sweep,
                    step,
                };
                let (lanes, each) = (r.table_lanes(), r.table_each());
                assert_eq!(bits(&lanes), bits(&each), "scan {seed}, sweep {sweep}");
                assert_eq!(lanes.far.to_bits(), each.far.to_bits(), "scan {seed}");
                rows += each.rows().len();
                tables += 1;
            }
        }
    }
    assert!(rows > 15 * tables, "{rows} rows in {tables} tables");
}

/// At the reach's bound a candidate gives no row, in lanes as one at a time: a chord `ac`
/// exactly `reach` times the range of `q` long (`q` and `b` on it, so its other tests pass)
/// gives none; a bit shorter at each end, both give the same row.
#[test]
fn a_chord_as_long_as_the_reach_gives_no_row_in_either_path() {
    let reach = 16.0 * 0.5f32.to_radians() * 2.0;
    let (q, b) = (Point::new(0.0, 3000.0), Point::new(0.0, 3000.0));
    let half = 0.5 * reach * 3000.0;
    for (h, at_bound) in [(half, true), (f32::from_bits(half.to_bits() - 1), false)] {
        let (a, c) = (Point::new(-h, 3000.0), Point::new(h, 3000.0));
        let len = math::hypot(c.x - a.x, c.y - a.y);
        assert_eq!(len == reach * 3000.0, at_bound, "{len}");
        assert!(len <= reach * 3000.0, "{len}");
        let one = row(a, q, b, c, 0.25, reach);
        let mut xy = [[0.0f32; LANES]; 8];
        for (column, v) in xy.iter_mut().zip([a.x, a.y, q.x, q.y, b.x, b.y, c.x, c.y]) {
            column[3] = v;
        }
        let lanes = Block::of(&xy, 0.25, reach).row(3);
        let bits = |r: Option<(Row, f32)>| r.map(|(r, q)| (r.map(f32::to_bits), q.to_bits()));
        assert_eq!(one.is_none(), at_bound, "{one:?}");
        assert_eq!(bits(lanes), bits(one), "{lanes:?} {one:?}");
    }
}
