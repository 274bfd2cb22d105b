//! Point-to-line ICP (Censi, "An ICP variant using a point-to-line metric", ICRA 2008): the
//! baseline of the pose benchmark ([`crate::posebench`]), on raw points in f64.
//!
//! Each iteration transforms the current scan's points by the estimate, pairs each with the
//! two nearest points of the reference scan that are neighbours in it (the nearest, and of its
//! two neighbours in scan order the nearer one), i.e. with the segment between them, and
//! solves for the pose minimising the squared point-to-line distances (one Gauss–Newton step
//! on the exact residual, as the correspondences change each iteration anyway). As in CSM's
//! usual parameters: pairs farther than `max_correspondence_dist` (0.3 m) are dropped, and only
//! the best `outliers_max_perc` (90 %) of the rest kept; it stops when the step is below
//! 0.1 mm and 0.001°, or after 50 iterations. The search for the nearest point looks at
//! beams within `window` of the transformed point's bearing (scan order, as Censi's tables
//! do). Its covariance is σ²(JᵀJ)⁻¹ at the solution with σ = the range noise: the
//! "least-squares" estimate that, like CSM's, ignores the correspondences' own error.
//!
//! ```
//! use pfe_eval::plicp::{plicp, Params};
//! // The corner of a room seen from the origin and from 0.1 m further along x.
//! let scan = |dx: f64| -> Vec<[f64; 2]> {
//!     (0..181).map(|i| {
//!         let b = (-90.0 + i as f64).to_radians();
//!         let (s, c) = b.sin_cos();
//!         let r = ((3000.0 - dx) / c.max(1e-9)).min(if s > 0.0 { 2000.0 / s } else { -2500.0 / s.min(-1e-9) });
//!         [r * c, r * s]
//!     }).collect()
//! };
//! let r = plicp(&scan(0.0), &scan(100.0), [0.0; 3], &Params::default()).unwrap();
//! assert!((r.pose[0] - 100.0).abs() < 1.0 && r.pose[1].abs() < 1.0 && r.pose[2].abs() < 1e-3);
//! ```
// 3×3 matrix algebra reads best with row and column indices.
#![allow(clippy::needless_range_loop)]

/// PL-ICP's settings (mm, rad).
#[derive(Clone, Copy, Debug)]
pub struct Params {
    /// Correspondences farther than this are dropped, mm (CSM: 0.3 m).
    pub max_correspondence_dist: f64,
    /// The fraction of the correspondences kept, the nearest (CSM: 0.9).
    pub outliers_max_perc: f64,
    /// Iterations at most.
    pub max_iterations: usize,
    /// Range noise, mm, for the covariance.
    pub sigma: f64,
    /// Beams either side of the projected bearing searched for the nearest point.
    pub window: usize,
    /// Fewest correspondences for an answer.
    pub min_correspondences: usize,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            max_correspondence_dist: 300.0,
            outliers_max_perc: 0.9,
            max_iterations: 50,
            sigma: 10.0,
            window: 40,
            min_correspondences: 20,
        }
    }
}

/// PL-ICP's answer.
#[derive(Clone, Copy, Debug)]
pub struct Answer {
    /// The current scan's pose in the reference scan's frame (x mm, y mm, θ rad).
    pub pose: [f64; 3],
    /// Its covariance.
    pub cov: [[f64; 3]; 3],
    /// Iterations run.
    pub iterations: usize,
    /// Whether the step fell below the tolerance (else it ran out of iterations).
    pub converged: bool,
}

/// Registers `current`'s points (mm, in scan order, in its frame) against `reference`'s
/// (in scan order) from the first guess `guess` (x mm, y mm, θ rad); `None` when too few
/// correspondences are found or the normal equations are singular.
pub fn plicp(
    reference: &[[f64; 2]],
    current: &[[f64; 2]],
    guess: [f64; 3],
    p: &Params,
) -> Option<Answer> {
    if reference.len() < 2 || current.is_empty() {
        return None;
    }
    // The reference's bearings (scan order: non-decreasing, up to noise).
    let bearings: Vec<f64> = reference.iter().map(|q| q[1].atan2(q[0])).collect();
    let mut x = guess;
    let mut corr: Vec<(usize, [f64; 2], [f64; 2], f64)> = Vec::new();
    for it in 1..=p.max_iterations {
        let (s, c) = x[2].sin_cos();
        corr.clear();
        for (i, q) in current.iter().enumerate() {
            let w = [c * q[0] - s * q[1] + x[0], s * q[0] + c * q[1] + x[1]];
            let b = w[1].atan2(w[0]);
            let k = bearings.partition_point(|&v| v < b);
            let lo = k.saturating_sub(p.window);
            let hi = (k + p.window).min(reference.len());
            let mut best = (f64::INFINITY, 0usize);
            for (j, r) in reference.iter().enumerate().take(hi).skip(lo) {
                let d = (r[0] - w[0]).powi(2) + (r[1] - w[1]).powi(2);
                if d < best.0 {
                    best = (d, j);
                }
            }
            if !best.0.is_finite() || best.0.sqrt() > p.max_correspondence_dist {
                continue;
            }
            let j1 = best.1;
            let d2 = |j: usize| {
                reference.get(j).map_or(f64::INFINITY, |r| {
                    (r[0] - w[0]).powi(2) + (r[1] - w[1]).powi(2)
                })
            };
            let j2 = if j1 == 0 {
                1
            } else if d2(j1 - 1) < d2(j1 + 1) {
                j1 - 1
            } else {
                j1 + 1
            };
            let (Some(a), Some(b2)) = (reference.get(j1), reference.get(j2)) else {
                continue;
            };
            let (tx, ty) = (b2[0] - a[0], b2[1] - a[1]);
            let len = tx.hypot(ty);
            if len.is_nan() || len <= 1e-9 || len > 2.0 * p.max_correspondence_dist {
                continue;
            }
            let n = [-ty / len, tx / len];
            let e = n[0] * (w[0] - a[0]) + n[1] * (w[1] - a[1]);
            corr.push((i, n, *a, e));
        }
        if corr.len() < p.min_correspondences {
            return None;
        }
        // Keep the best fraction.
        corr.sort_by(|u, v| u.3.abs().total_cmp(&v.3.abs()));
        let keep =
            ((corr.len() as f64 * p.outliers_max_perc).ceil() as usize).max(p.min_correspondences);
        corr.truncate(keep);
        let (h, g) = normal_equations(current, &corr, x);
        let step = solve3(&h, &g)?;
        x = [x[0] - step[0], x[1] - step[1], x[2] - step[2]];
        x[2] = x[2].sin().atan2(x[2].cos());
        if step[0].hypot(step[1]) < 0.1 && step[2].abs() < 0.001f64.to_radians() {
            let (h, _) = normal_equations(current, &corr, x);
            return Some(Answer {
                pose: x,
                cov: inverse3(&h)?.map(|r| r.map(|v| v * p.sigma * p.sigma)),
                iterations: it,
                converged: true,
            });
        }
    }
    let (h, _) = normal_equations(current, &corr, x);
    Some(Answer {
        pose: x,
        cov: inverse3(&h)?.map(|r| r.map(|v| v * p.sigma * p.sigma)),
        iterations: p.max_iterations,
        converged: false,
    })
}

/// JᵀJ and Jᵀr of the point-to-line residuals at `x`.
fn normal_equations(
    current: &[[f64; 2]],
    corr: &[(usize, [f64; 2], [f64; 2], f64)],
    x: [f64; 3],
) -> ([[f64; 3]; 3], [f64; 3]) {
    let (s, c) = x[2].sin_cos();
    let mut h = [[0.0; 3]; 3];
    let mut g = [0.0; 3];
    for &(i, n, a, _) in corr {
        let Some(q) = current.get(i) else { continue };
        let w = [c * q[0] - s * q[1] + x[0], s * q[0] + c * q[1] + x[1]];
        let r = n[0] * (w[0] - a[0]) + n[1] * (w[1] - a[1]);
        let dw = [-s * q[0] - c * q[1], c * q[0] - s * q[1]];
        let j = [n[0], n[1], n[0] * dw[0] + n[1] * dw[1]];
        for u in 0..3 {
            for v in 0..3 {
                h[u][v] += j[u] * j[v];
            }
            g[u] += j[u] * r;
        }
    }
    (h, g)
}

/// The inverse of a 3×3 matrix (`None` when singular).
fn inverse3(m: &[[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    if !det.is_finite() || det.abs() <= 1e-300 {
        return None;
    }
    let mut inv = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let (a, b) = ((j + 1) % 3, (j + 2) % 3);
            let (c1, d) = ((i + 1) % 3, (i + 2) % 3);
            inv[i][j] = (m[a][c1] * m[b][d] - m[a][d] * m[b][c1]) / det;
        }
    }
    Some(inv)
}

/// Solves `m s = g`.
fn solve3(m: &[[f64; 3]; 3], g: &[f64; 3]) -> Option<[f64; 3]> {
    let inv = inverse3(m)?;
    let s = [0, 1, 2].map(|i| inv[i][0] * g[0] + inv[i][1] * g[1] + inv[i][2] * g[2]);
    s.iter().all(|v| v.is_finite()).then_some(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A room (the walls of a 10 m × 7 m rectangle with a 1 m × 1 m box inside) seen over 360
    /// beams of 0.5° from pose `p` (mm, rad), noise-free.
    fn room(p: [f64; 3]) -> Vec<[f64; 2]> {
        let segs = [
            ([-4000.0, -3000.0], [6000.0, -3000.0]),
            ([6000.0, -3000.0], [6000.0, 4000.0]),
            ([6000.0, 4000.0], [-4000.0, 4000.0]),
            ([-4000.0, 4000.0], [-4000.0, -3000.0]),
            ([2000.0, 1000.0], [3000.0, 1000.0]),
            ([3000.0, 1000.0], [3000.0, 2000.0]),
            ([3000.0, 2000.0], [2000.0, 2000.0]),
            ([2000.0, 2000.0], [2000.0, 1000.0]),
        ];
        (0..361)
            .filter_map(|i| {
                let b = (-90.0 + 0.5 * i as f64).to_radians();
                let (dx, dy) = ((p[2] + b).cos(), (p[2] + b).sin());
                let mut best = f64::INFINITY;
                for (a0, a1) in segs {
                    let (ex, ey) = (a1[0] - a0[0], a1[1] - a0[1]);
                    let den = dx * ey - dy * ex;
                    if den.abs() < 1e-12 {
                        continue;
                    }
                    let (wx, wy) = (a0[0] - p[0], a0[1] - p[1]);
                    let t = (wx * ey - wy * ex) / den;
                    let u = (wx * dy - wy * dx) / den;
                    if t > 0.0 && (0.0..=1.0).contains(&u) {
                        best = best.min(t);
                    }
                }
                best.is_finite().then(|| [best * b.cos(), best * b.sin()])
            })
            .collect()
    }

    fn err(a: &Answer, t: [f64; 3]) -> (f64, f64) {
        (
            (a.pose[0] - t[0]).hypot(a.pose[1] - t[1]),
            (a.pose[2] - t[2]).abs(),
        )
    }

    /// Censi's behaviour: from a first guess within some cm and a few degrees of the truth it
    /// converges to it (to well under a mm, in few iterations); from a guess a metre and 30°
    /// off it does not (wrong correspondences: a local minimum, or none found).
    #[test]
    fn converges_from_small_errors_and_fails_from_large_ones() {
        let truth = [300.0, -150.0, 0.1];
        let reference = room([0.0; 3]);
        let current = room(truth);
        for off in [
            [0.0, 0.0, 0.0],
            [100.0, -80.0, 0.05],
            [-150.0, 100.0, -0.08],
        ] {
            let guess = [truth[0] + off[0], truth[1] + off[1], truth[2] + off[2]];
            let a = plicp(&reference, &current, guess, &Params::default()).unwrap();
            let (t, r) = err(&a, truth);
            assert!(a.converged && t < 1.0 && r < 1e-4, "{off:?}: {a:?}");
            assert!(a.iterations < 30, "{a:?}");
        }
        // From 1.2 m and 29° off it does not.
        let far = [truth[0] - 1000.0, truth[1] + 600.0, truth[2] + 0.5];
        let bad = plicp(&reference, &current, far, &Params::default());
        assert!(
            bad.is_none_or(|a| {
                let (t, r) = err(&a, truth);
                t > 50.0 || r > 0.01
            }),
            "{bad:?}"
        );
    }

    /// Too few points, or coincident ones: no answer rather than a guess.
    #[test]
    fn degenerate_input_gives_none() {
        assert!(plicp(
            &[[1000.0, 0.0]],
            &[[1000.0, 0.0]],
            [0.0; 3],
            &Params::default()
        )
        .is_none());
        let same = vec![[1000.0, 0.0]; 50];
        assert!(plicp(&same, &same, [0.0; 3], &Params::default()).is_none());
    }
}
