//! Ground truth: the exact parameters of the features a scan sees and their Cramér–Rao
//! bounds.

use std::f64::consts::{FRAC_PI_2, PI};

use super::vec2::{dir, dot, scale, sub, wrap_pi};
use super::Shape;

/// Smallest run of beams on one primitive that is a ground-truth feature (the paper's 4).
pub const MIN_RUN: usize = 4;

/// The true parameters of a ground-truth feature, in the scanner frame (pfe-core conventions).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TruthKind {
    /// `x cos α + y sin α = ρ`, ρ ≥ 0, α in (−π, π].
    Line {
        /// Normal angle, rad.
        alpha: f64,
        /// Distance from the scanner, mm.
        rho: f64,
    },
    /// A circle.
    Circle {
        /// Centre, mm.
        center: [f64; 2],
        /// Radius, mm.
        radius: f64,
    },
}

impl TruthKind {
    /// True for a line.
    pub fn is_line(&self) -> bool {
        matches!(self, TruthKind::Line { .. })
    }

    /// The parameters of `shape` (in the scanner frame).
    pub fn of(shape: &Shape) -> TruthKind {
        match *shape {
            Shape::Segment { a, b } => {
                let e = sub(b, a);
                let mut alpha = e[1].atan2(e[0]) + FRAC_PI_2;
                let mut rho = dot(a, dir(alpha));
                if rho < 0.0 {
                    rho = -rho;
                    alpha += PI;
                }
                TruthKind::Line {
                    alpha: wrap_pi(alpha),
                    rho,
                }
            }
            Shape::Circle { center, radius } => TruthKind::Circle { center, radius },
        }
    }
}

/// Cramér–Rao bound (standard deviations) of a feature's parameters from its beams.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Crb {
    /// Line: σ_ρ, mm. Circle: RMS centre error `sqrt(σ_a² + σ_b²)`, mm.
    pub position: f64,
    /// Line: σ_α, rad. Circle: σ_R, mm.
    pub shape: f64,
}

/// A ground-truth feature: beams `first..=last` all hit primitive `primitive`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TruthFeature {
    /// Index of the primitive in [`SimScan::shapes`](super::SimScan::shapes).
    pub primitive: usize,
    /// First beam.
    pub first: usize,
    /// Last beam.
    pub last: usize,
    /// True parameters.
    pub kind: TruthKind,
    /// Cramér–Rao bound of the parameters for these beams and the scan's range noise.
    pub crb: Crb,
}

/// Cramér–Rao bound for estimating `kind` from ranges along `bearings` with independent
/// Gaussian range noise `sigma` (mm): Fisher information `Σ g_i g_iᵀ / σ²`, `g_i` the
/// derivative of beam i's true range with respect to the parameters. Line (ρ, α):
/// `r = ρ / cos(φ − α)`. Circle (a, b, R): with `n` the outward normal at the hit and `u` the
/// beam, `∂r/∂(a, b) = n / (n·u)`, `∂r/∂R = 1 / (n·u)`. `None` when singular.
///
/// ```
/// use pfe_eval::scene::{crb, TruthKind};
/// let wall = TruthKind::Line { alpha: 0.0, rho: 2000.0 };
/// let bearings: Vec<f64> = (0..41).map(|i| (i as f64 - 20.0).to_radians()).collect();
/// let b = crb(&wall, &bearings, 5.0).unwrap();
/// assert!(b.position < 5.0 / (41f64).sqrt() * 1.01); // ~σ/√n at normal incidence
/// ```
pub fn crb(kind: &TruthKind, bearings: &[f64], sigma: f64) -> Option<Crb> {
    let s2 = sigma * sigma;
    if s2.is_nan() || s2 <= 0.0 {
        return None;
    }
    match *kind {
        TruthKind::Line { alpha, rho } => {
            let mut f = [[0.0f64; 2]; 2];
            for &phi in bearings {
                let c = (phi - alpha).cos();
                if c.abs() < 1e-9 {
                    continue;
                }
                let g = [1.0 / c, rho * (phi - alpha).sin() / (c * c)];
                for (i, row) in f.iter_mut().enumerate() {
                    for (j, v) in row.iter_mut().enumerate() {
                        *v += g[i] * g[j] / s2;
                    }
                }
            }
            let det = f[0][0] * f[1][1] - f[0][1] * f[1][0];
            if det.is_nan() || det.abs() <= 1e-300 {
                return None;
            }
            let (vr, va) = (f[1][1] / det, f[0][0] / det);
            (vr > 0.0 && va > 0.0).then(|| Crb {
                position: vr.sqrt(),
                shape: va.sqrt(),
            })
        }
        TruthKind::Circle { center, radius } => {
            let mut f = [[0.0f64; 3]; 3];
            for &phi in bearings {
                let u = dir(phi);
                let shape = Shape::Circle { center, radius };
                let Some(t) = shape.ray_hit([0.0, 0.0], u) else {
                    continue;
                };
                let n = scale(sub(scale(u, t), center), 1.0 / radius);
                let nu = dot(n, u);
                if nu.abs() < 1e-9 {
                    continue;
                }
                let g = [n[0] / nu, n[1] / nu, 1.0 / nu];
                for (i, row) in f.iter_mut().enumerate() {
                    for (j, v) in row.iter_mut().enumerate() {
                        *v += g[i] * g[j] / s2;
                    }
                }
            }
            let inv = invert3(&f)?;
            let (va, vb, vr) = (inv[0][0], inv[1][1], inv[2][2]);
            (va > 0.0 && vb > 0.0 && vr > 0.0).then(|| Crb {
                position: (va + vb).sqrt(),
                shape: vr.sqrt(),
            })
        }
    }
}

fn invert3(m: &[[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let c = |r: usize, k: usize| -> f64 {
        let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
        let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
        m[r1][k1] * m[r2][k2] - m[r1][k2] * m[r2][k1]
    };
    let det = m[0][0] * c(0, 0) + m[0][1] * c(0, 1) + m[0][2] * c(0, 2);
    if !det.is_finite() || det.abs() <= 1e-300 {
        return None;
    }
    let mut out = [[0.0; 3]; 3];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = c(j, i) / det; // adjugate = transposed cofactors
        }
    }
    Some(out)
}
