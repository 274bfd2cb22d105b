//! Moving features from scan k's frame into scan k+1's, with their covariances, and the
//! normalised innovation squared (NIS) of a matched pair.
//!
//! Poses are `[x mm, y mm, θ rad]` of the scanner in the world. A point `p` of frame k is
//! `R(θ_k) p + t_k` in the world and `p' = R(θ_k − θ_{k+1}) p + R(−θ_{k+1}) (t_k − t_{k+1})`
//! in frame k+1. A line `x cos α + y sin α = ρ` of frame k has world normal angle
//! `α_w = α + θ_k`, so in frame k+1
//!
//! ```text
//! α' = α + θ_k − θ_{k+1},    ρ' = ρ + (t_k − t_{k+1}) · (cos α_w, sin α_w)
//! ```
//!
//! with Jacobian `∂(α', ρ')/∂(α, ρ) = [[1, 0], [(t_k − t_{k+1}) · (−sin α_w, cos α_w), 1]]`
//! (the pose taken as exact). A negative ρ' is turned into (α' + π, −ρ'), which negates the
//! second row. A circle's centre moves as a point; its covariance turns with `R(θ_k − θ_{k+1})`.

/// Scanner pose in the world: x mm, y mm, θ rad.
pub type Pose = [f64; 3];

/// A 2×2 covariance.
pub type Cov2 = [[f64; 2]; 2];

/// A line as seen in one frame: `x cos α + y sin α = ρ` between `start` and `end`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineObs {
    /// Normal angle, rad.
    pub alpha: f64,
    /// Distance from the scanner, mm.
    pub rho: f64,
    /// Covariance of (α, ρ), rad and mm.
    pub cov: Cov2,
    /// First point projected on the line, mm.
    pub start: [f64; 2],
    /// Last point projected on the line, mm.
    pub end: [f64; 2],
    /// Valid points fitted.
    pub points: usize,
    /// First and last beam of its span.
    pub beams: [usize; 2],
}

impl LineObs {
    /// The same line written as (α + π, −ρ).
    pub fn flipped(&self) -> Self {
        Self {
            alpha: wrap(self.alpha + std::f64::consts::PI),
            rho: -self.rho,
            cov: [
                [self.cov[0][0], -self.cov[0][1]],
                [-self.cov[1][0], self.cov[1][1]],
            ],
            ..*self
        }
    }

    /// (Δα, Δρ) of `self − other` in the representation of `self` closest to `other` (so a line
    /// through the scanner compares well either way), the sum of both covariances, and the
    /// normal angle of `self` in that representation.
    pub fn difference(&self, other: &LineObs) -> ([f64; 2], Cov2, f64) {
        let a = if wrap(self.alpha - other.alpha).abs() > std::f64::consts::FRAC_PI_2 {
            self.flipped()
        } else {
            *self
        };
        let d = [wrap(a.alpha - other.alpha), a.rho - other.rho];
        (d, add(&a.cov, &other.cov), a.alpha)
    }

    /// Interval of the line's extent along `other`'s direction, mm.
    pub fn extent_along(&self, other: &LineObs) -> (f64, f64) {
        let u = [-other.alpha.sin(), other.alpha.cos()];
        let s = self.start[0] * u[0] + self.start[1] * u[1];
        let e = self.end[0] * u[0] + self.end[1] * u[1];
        (s.min(e), s.max(e))
    }
}

/// A circle's centre as seen in one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CircleObs {
    /// Centre, mm.
    pub center: [f64; 2],
    /// Covariance of the centre, mm².
    pub cov: Cov2,
    /// Radius, mm.
    pub radius: f64,
}

/// The corrected poses' own scatter between two scans, per axis, mm (a SLAM solution's few
/// cm; the pose benchmark adds the same).
pub const REFERENCE_SIGMA_MM: f64 = 15.0;
/// …and in heading, rad (0.4°).
pub const REFERENCE_SIGMA_RAD: f64 = 0.4 * std::f64::consts::PI / 180.0;

/// The rigid motion taking frame k's coordinates into frame k+1's: `p' = R(rot) p + shift`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameChange {
    /// θ_k − θ_{k+1}, rad.
    pub rot: f64,
    /// R(−θ_{k+1}) (t_k − t_{k+1}), mm.
    pub shift: [f64; 2],
}

impl FrameChange {
    /// From the frame of a scanner at `from` into that of one at `to`.
    pub fn between(from: Pose, to: Pose) -> Self {
        let d = [from[0] - to[0], from[1] - to[1]];
        let (s, c) = to[2].sin_cos();
        Self {
            rot: wrap(from[2] - to[2]),
            shift: [c * d[0] + s * d[1], -s * d[0] + c * d[1]],
        }
    }

    /// A point of frame k in frame k+1.
    pub fn point(&self, p: [f64; 2]) -> [f64; 2] {
        let (s, c) = self.rot.sin_cos();
        [
            c * p[0] - s * p[1] + self.shift[0],
            s * p[0] + c * p[1] + self.shift[1],
        ]
    }

    /// The Jacobian of (α', ρ') with respect to (α, ρ) at normal angle `alpha` (before the
    /// sign normalisation).
    pub fn line_jacobian(&self, alpha: f64) -> Cov2 {
        let a = alpha + self.rot;
        let drho_dalpha = -self.shift[0] * a.sin() + self.shift[1] * a.cos();
        [[1.0, 0.0], [drho_dalpha, 1.0]]
    }

    /// A line of frame k in frame k+1, covariance carried by the Jacobian, ρ' ≥ 0.
    pub fn line(&self, l: &LineObs) -> LineObs {
        let alpha = wrap(l.alpha + self.rot);
        let rho = l.rho + self.shift[0] * alpha.cos() + self.shift[1] * alpha.sin();
        let moved = LineObs {
            alpha,
            rho,
            cov: sandwich(&self.line_jacobian(l.alpha), &l.cov),
            start: self.point(l.start),
            end: self.point(l.end),
            points: l.points,
            beams: l.beams,
        };
        if rho < 0.0 {
            moved.flipped()
        } else {
            moved
        }
    }

    /// A circle of frame k in frame k+1, centre covariance turned with the frame.
    pub fn circle(&self, c: &CircleObs) -> CircleObs {
        let (s, co) = self.rot.sin_cos();
        CircleObs {
            center: self.point(c.center),
            cov: sandwich(&[[co, -s], [s, co]], &c.cov),
            radius: c.radius,
        }
    }
}

/// Angle wrapped into (−π, π].
pub fn wrap(a: f64) -> f64 {
    let tau = std::f64::consts::TAU;
    let w = a - tau * (a / tau).round();
    if w <= -std::f64::consts::PI {
        w + tau
    } else {
        w
    }
}

/// `a + b`.
pub fn add(a: &Cov2, b: &Cov2) -> Cov2 {
    [
        [a[0][0] + b[0][0], a[0][1] + b[0][1]],
        [a[1][0] + b[1][0], a[1][1] + b[1][1]],
    ]
}

/// `J C Jᵀ`.
pub fn sandwich(j: &Cov2, c: &Cov2) -> Cov2 {
    let jc = [
        [
            j[0][0] * c[0][0] + j[0][1] * c[1][0],
            j[0][0] * c[0][1] + j[0][1] * c[1][1],
        ],
        [
            j[1][0] * c[0][0] + j[1][1] * c[1][0],
            j[1][0] * c[0][1] + j[1][1] * c[1][1],
        ],
    ];
    let mut out = [[0.0; 2]; 2];
    for (r, row) in out.iter_mut().enumerate() {
        for (k, v) in row.iter_mut().enumerate() {
            *v = jc[r][0] * j[k][0] + jc[r][1] * j[k][1];
        }
    }
    out
}

/// `dᵀ S⁻¹ d`, `None` when S is not positive definite.
pub fn nis(d: [f64; 2], s: &Cov2) -> Option<f64> {
    let det = s[0][0] * s[1][1] - s[0][1] * s[1][0];
    if !(det > 0.0 && s[0][0] > 0.0) {
        return None;
    }
    let v =
        (s[1][1] * d[0] * d[0] - (s[0][1] + s[1][0]) * d[0] * d[1] + s[0][0] * d[1] * d[1]) / det;
    v.is_finite().then_some(v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, PI};

    fn line(alpha: f64, rho: f64, cov: Cov2) -> LineObs {
        LineObs {
            alpha,
            rho,
            cov,
            start: [0.0; 2],
            end: [0.0; 2],
            points: 10,
            beams: [0, 9],
        }
    }

    #[test]
    fn a_wall_ahead_seen_after_a_step_and_a_left_turn() {
        // Wall x = 2000 seen from the origin; the scanner then moves 500 mm forward and turns
        // left by 90°: the wall is 1500 mm away on its right (y' = −1500).
        let f = FrameChange::between([0.0, 0.0, 0.0], [500.0, 0.0, FRAC_PI_2]);
        let l = f.line(&line(0.0, 2000.0, [[0.0; 2]; 2]));
        assert!((l.alpha + FRAC_PI_2).abs() < 1e-12 && (l.rho - 1500.0).abs() < 1e-9);
        let p = f.point([2000.0, 300.0]);
        assert!((p[0] - 300.0).abs() < 1e-9 && (p[1] + 1500.0).abs() < 1e-9);
    }

    #[test]
    fn a_wall_behind_the_new_pose_flips_its_normal() {
        // Wall x = 1000 from a scanner that then stands at x = 3000 facing the same way.
        let f = FrameChange::between([0.0, 0.0, 0.0], [3000.0, 0.0, 0.0]);
        let l = f.line(&line(0.0, 1000.0, [[1e-4, 0.01], [0.01, 4.0]]));
        assert!((l.alpha.abs() - PI).abs() < 1e-12 && (l.rho - 2000.0).abs() < 1e-9);
        // Every point of the moved line satisfies its equation.
        let p = f.point([1000.0, 700.0]);
        assert!((p[0] * l.alpha.cos() + p[1] * l.alpha.sin() - l.rho).abs() < 1e-9);
    }

    #[test]
    fn the_jacobian_matches_finite_differences() {
        let f = FrameChange::between([300.0, -200.0, 0.4], [-150.0, 900.0, -1.1]);
        let (a, r) = (0.7, 2500.0);
        let j = f.line_jacobian(a);
        let at = |a: f64, r: f64| {
            let l = f.line(&line(a, r, [[0.0; 2]; 2]));
            // Unflipped (α', ρ') in this test's geometry.
            assert!(l.rho > 0.0);
            [l.alpha, l.rho]
        };
        let h = 1e-6;
        let (p, m) = (at(a + h, r), at(a - h, r));
        assert!(((p[0] - m[0]) / (2.0 * h) - j[0][0]).abs() < 1e-6);
        assert!(((p[1] - m[1]) / (2.0 * h) - j[1][0]).abs() < 1e-4);
        let (p, m) = (at(a, r + 1.0), at(a, r - 1.0));
        assert!(((p[1] - m[1]) / 2.0 - j[1][1]).abs() < 1e-9);
        // The covariance is carried as J C Jᵀ.
        let c = [[1e-4, 0.02], [0.02, 9.0]];
        let moved = f.line(&line(a, r, c)).cov;
        let expect = sandwich(&j, &c);
        for (x, y) in moved.iter().flatten().zip(expect.iter().flatten()) {
            assert!((x - y).abs() < 1e-12);
        }
    }

    #[test]
    fn the_world_route_agrees_with_the_relative_one() {
        // α_w = α + θ_k, ρ_w = ρ + t_k·n(α_w), then into frame k+1.
        let (k, k1) = ([1200.0, -300.0, 0.3], [1500.0, 100.0, 0.45]);
        let (a, r): (f64, f64) = (-0.2, 3000.0);
        let aw = a + k[2];
        let rw = r + k[0] * aw.cos() + k[1] * aw.sin();
        let a1 = wrap(aw - k1[2]);
        let r1 = rw - k1[0] * aw.cos() - k1[1] * aw.sin();
        let l = FrameChange::between(k, k1).line(&line(a, r, [[0.0; 2]; 2]));
        assert!((l.alpha - a1).abs() < 1e-12 && (l.rho - r1).abs() < 1e-9);
    }

    #[test]
    fn circles_turn_their_covariance() {
        let f = FrameChange::between([0.0, 0.0, FRAC_PI_2], [0.0, 0.0, 0.0]);
        let c = f.circle(&CircleObs {
            center: [1000.0, 0.0],
            cov: [[4.0, 0.0], [0.0, 1.0]],
            radius: 100.0,
        });
        assert!(c.center[0].abs() < 1e-9 && (c.center[1] - 1000.0).abs() < 1e-9);
        assert!((c.cov[0][0] - 1.0).abs() < 1e-12 && (c.cov[1][1] - 4.0).abs() < 1e-12);
    }

    #[test]
    fn nis_of_a_known_case() {
        let s = [[4.0, 0.0], [0.0, 1.0]];
        assert_eq!(nis([2.0, 1.0], &s), Some(2.0));
        assert_eq!(nis([1.0, 1.0], &[[1.0, 1.0], [1.0, 1.0]]), None);
        // Correlation: d along the long axis of the ellipse costs less.
        let c = [[2.0, 1.9], [1.9, 2.0]];
        assert!(nis([1.0, 1.0], &c) < nis([1.0, -1.0], &c));
    }

    #[test]
    fn difference_uses_the_nearer_representation() {
        let a = line(PI - 0.01, 5.0, [[1.0, 0.5], [0.5, 1.0]]);
        let b = line(-0.005, -5.0 + 2.0, [[0.0; 2]; 2]);
        let (d, s, alpha) = a.difference(&b);
        assert!((d[0] + 0.005).abs() < 1e-12 && (d[1] + 2.0).abs() < 1e-12);
        assert!((alpha + 0.01).abs() < 1e-12 && s[0][1] == -0.5);
    }
}
