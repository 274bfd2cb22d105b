//! Systematic range correction (paper §2, after Borges & Aldon): a sixth-order polynomial
//! `p(r_m) ≈ r_m − r_t`, calibrated by least squares from (measured, true) pairs and subtracted
//! from every reading. Evaluated by Horner's rule in f32 on `t = r_m / scale` so that the powers
//! stay well conditioned.

use crate::error::FitError;

/// Polynomial degree.
pub const DEGREE: usize = 6;

/// `r_corrected = r_m − Σ c_k (r_m / scale)^k`, k = 0..=6.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RangeCorrection {
    /// Coefficients, constant term first, in mm.
    pub coeffs: [f32; DEGREE + 1],
    /// Normalising range, mm (the largest calibration range).
    pub scale: f32,
}

impl RangeCorrection {
    /// No correction.
    pub const IDENTITY: RangeCorrection = RangeCorrection {
        coeffs: [0.0; DEGREE + 1],
        scale: 1.0,
    };

    /// The systematic error `p(r_m)` in mm.
    pub fn error(&self, r_m: f32) -> f32 {
        let t = r_m / self.scale;
        self.coeffs.iter().rev().fold(0.0, |acc, c| acc * t + c)
    }

    /// The corrected range `r_m − p(r_m)`.
    ///
    /// ```
    /// use pfe_core::RangeCorrection;
    /// let c = RangeCorrection { coeffs: [10.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], scale: 8000.0 };
    /// assert_eq!(c.apply(1010.0), 1000.0);
    /// ```
    pub fn apply(&self, r_m: f32) -> f32 {
        r_m - self.error(r_m)
    }

    /// Least-squares calibration from `(measured, true)` pairs, in mm. Needs at least 7 pairs
    /// with distinct measured ranges; pairs with a non-finite value are an error.
    /// Solved in f64 (normal equations on normalised ranges, Cholesky).
    ///
    /// ```
    /// use pfe_core::RangeCorrection;
    /// let pairs: Vec<(f32, f32)> = (1..=40).map(|i| {
    ///     let t = i as f32 * 200.0;
    ///     (t + 5.0 + 0.002 * t, t)
    /// }).collect();
    /// let c = RangeCorrection::calibrate(&pairs)?;
    /// assert!((c.apply(4005.0 + 8.0) - 4000.0).abs() < 0.1);
    /// # Ok::<(), pfe_core::FitError>(())
    /// ```
    pub fn calibrate(pairs: &[(f32, f32)]) -> Result<Self, FitError> {
        const K: usize = DEGREE + 1;
        if pairs.len() < K {
            return Err(FitError::TooFewPoints {
                got: pairs.len(),
                need: K,
            });
        }
        let mut scale = 0.0f64;
        for &(m, t) in pairs {
            if !m.is_finite() || !t.is_finite() {
                return Err(FitError::NonFinite);
            }
            scale = scale.max(f64::from(m).abs());
        }
        if scale <= 0.0 {
            return Err(FitError::Degenerate);
        }
        let mut ata = [[0.0f64; K]; K];
        let mut atb = [0.0f64; K];
        for &(m, t) in pairs {
            let x = f64::from(m) / scale;
            let e = f64::from(m) - f64::from(t);
            let mut pw = [1.0f64; K];
            let mut acc = 1.0f64;
            for v in pw.iter_mut() {
                *v = acc;
                acc *= x;
            }
            for ((row, b), pi) in ata.iter_mut().zip(atb.iter_mut()).zip(pw.iter()) {
                for (v, pj) in row.iter_mut().zip(pw.iter()) {
                    *v += pi * pj;
                }
                *b += pi * e;
            }
        }
        let sol = cholesky_solve(ata, atb).ok_or(FitError::Degenerate)?;
        let mut coeffs = [0.0f32; K];
        for (c, s) in coeffs.iter_mut().zip(sol.iter()) {
            *c = *s as f32;
        }
        if coeffs.iter().any(|c| !c.is_finite()) {
            return Err(FitError::Degenerate);
        }
        Ok(Self {
            coeffs,
            scale: scale as f32,
        })
    }
}

/// Solves `A x = b` for a symmetric positive definite `A` (fixed size, no indexing panics:
/// all indices are loop bounds over the fixed arrays).
#[allow(clippy::indexing_slicing, clippy::needless_range_loop)]
fn cholesky_solve<const K: usize>(a: [[f64; K]; K], b: [f64; K]) -> Option<[f64; K]> {
    let mut l = [[0.0f64; K]; K];
    let mut diag_max = 0.0f64;
    for i in 0..K {
        diag_max = diag_max.max(a[i][i]);
    }
    for i in 0..K {
        for j in 0..=i {
            let mut s = a[i][j];
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            if i == j {
                if s <= diag_max * 1e-15 {
                    return None;
                }
                l[i][i] = libm::sqrt(s);
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    let mut y = [0.0f64; K];
    for i in 0..K {
        let mut s = b[i];
        for k in 0..i {
            s -= l[i][k] * y[k];
        }
        y[i] = s / l[i][i];
    }
    let mut x = [0.0f64; K];
    for i in (0..K).rev() {
        let mut s = y[i];
        for k in i + 1..K {
            s -= l[k][i] * x[k];
        }
        x[i] = s / l[i][i];
    }
    Some(x)
}
