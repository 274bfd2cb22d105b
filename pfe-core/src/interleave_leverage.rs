//! [`fit_chunk`]'s outlier test with the leverage of the row: a corner's second difference
//! at the chunk's end, where the fit follows it most.
#![allow(clippy::indexing_slicing)]

use super::*;

/// Row `k` of the model of a chunk of `m` rows starting at `first`: a line, the alternating
/// offset and its change, the period-4 pair.
pub(super) fn model_row(first: usize, m: usize, k: usize) -> [f64; 6] {
    let g = first + 1 + k;
    let t = (g as f64 - (first as f64 + 1.0 + 0.5 * m as f64)) / 32.0;
    let alt = if g % 2 == 0 { 1.0 } else { -1.0 };
    let (c, s) = [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)][g % 4];
    [1.0, t, alt, alt * t, c, s]
}

/// Gauss–Jordan with partial pivoting on `[A | B]` (A 6 × 6): reduced to `[I | A⁻¹ B]`.
pub(super) fn gauss_jordan<const C: usize>(a: &mut [[f64; C]; 6]) {
    for c in 0..6 {
        let piv = (c..6)
            .max_by(|&u, &v| a[u][c].abs().total_cmp(&a[v][c].abs()))
            .unwrap_or(c);
        a.swap(c, piv);
        let d = a[c][c];
        a[c] = a[c].map(|v| v / d);
        for r in (0..6).filter(|&r| r != c) {
            let f = a[r][c];
            let rc = a[c];
            for (v, p) in a[r].iter_mut().zip(rc) {
                *v -= f * p;
            }
        }
    }
}

/// The leverage `h` of row `j` among the `m` rows of a chunk starting at `first`, in f64 by
/// normal equations solved with Gauss–Jordan: `x_jᵀ (XᵀX)⁻¹ x_j` with the rows of the model
/// (a line, the alternating offset and its change, the period-4 pair) written out here.
fn leverage(first: usize, m: usize, j: usize) -> f64 {
    let row = |k: usize| model_row(first, m, k);
    // [XᵀX | x_j], reduced to [I | (XᵀX)⁻¹ x_j].
    let mut a = [[0.0f64; 7]; 6];
    for k in 0..m {
        let x = row(k);
        for p in 0..6 {
            for q in 0..6 {
                a[p][q] += x[p] * x[q];
            }
        }
    }
    let xj = row(j);
    for p in 0..6 {
        a[p][6] = xj[p];
    }
    gauss_jordan(&mut a);
    (0..6).map(|p| xj[p] * a[p][6]).sum()
}

/// Ranges of a chunk along a straight run (all equal: every second difference 0) whose first
/// range is `delta` mm longer: only the first second difference, `a_0 = −delta/2`, is not 0.
fn chunk(delta: f32) -> [f32; 20] {
    let mut r = [3000.0f32; 20];
    r[0] += delta;
    r
}

#[test]
fn the_end_row_has_a_high_leverage() {
    // 18 rows, 6 parameters: 1/3 on average, more at the ends (7/15 at the first).
    let h = leverage(0, 18, 0);
    assert!(h > 0.4 && h < 0.9, "{h}");
}

/// A lone second difference at the chunk's end beyond [`OUTLIER`] standard deviations of its
/// residual (σ_a √(1 − h), σ_a = √1.5 σ) is left out: the other rows are exactly 0, so the
/// fit without it is 0 with no residual. Within them it is kept and leaves a residual.
#[test]
fn an_outlier_at_the_chunks_end_is_judged_by_its_residuals_own_deviation() {
    let sigma = 1.0f32;
    let h = leverage(0, 18, 0);
    let sigma_a = 1.5f64.sqrt() * f64::from(sigma);
    // With all rows in the fit the row's residual is (1 − h) a_0; its deviation σ_a √(1 − h).
    let a0_at = |z: f64| z * sigma_a / (1.0 - h).sqrt();
    for (z, left_out) in [(6.0, true), (7.0, true), (4.0, false)] {
        let a0 = a0_at(z) as f32;
        let Some(fit) = fit_chunk(0, &chunk(-2.0 * a0), sigma) else {
            panic!("z {z}: no fit");
        };
        if left_out {
            assert_eq!(fit.ss, 0.0, "z {z}");
            assert_eq!(fit.est, [0.0; 3], "z {z}");
        } else {
            // Kept: its own residual (1 − h) a_0 is part of the sum.
            let own = (1.0 - h) * f64::from(a0);
            assert!(f64::from(fit.ss) >= 0.99 * own * own, "z {z}: {}", fit.ss);
        }
    }
}
