//! Poses, their composition and covariance, and the small matrix algebra the registration needs.

use core::f32::consts::PI;

/// A 3×3 covariance of a pose, in the order (x mm, y mm, θ rad): units mm², mm·rad, rad².
pub type Cov3 = [[f32; 3]; 3];

/// The zero 3×3 matrix.
pub const ZERO3: Cov3 = [[0.0; 3]; 3];

/// A rigid motion in the plane: the pose of a frame B in a frame A.
///
/// A point `p_B` in B is `R(θ) p_B + (x, y)` in A. x, y in mm, θ in rad in (−π, π].
///
/// ```
/// use pfe_pose::Pose;
/// let a = Pose::new(1000.0, 0.0, core::f32::consts::FRAC_PI_2);
/// let p = a.transform_point([1000.0, 0.0]);
/// assert!((p[0] - 1000.0).abs() < 1e-3 && (p[1] - 1000.0).abs() < 1e-3);
/// let back = a.compose(&a.inverse());
/// assert!(back.x.abs() < 1e-3 && back.y.abs() < 1e-3 && back.theta.abs() < 1e-6);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pose {
    /// mm.
    pub x: f32,
    /// mm.
    pub y: f32,
    /// rad, in (−π, π].
    pub theta: f32,
}

impl Pose {
    /// No motion.
    pub const IDENTITY: Pose = Pose {
        x: 0.0,
        y: 0.0,
        theta: 0.0,
    };

    /// The pose (x mm, y mm, θ rad), θ wrapped into (−π, π].
    #[inline(always)]
    pub fn new(x: f32, y: f32, theta: f32) -> Self {
        Self {
            x,
            y,
            theta: wrap(theta),
        }
    }

    /// True when x, y and θ are finite.
    pub fn is_finite(&self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.theta.is_finite()
    }

    /// `self ⊕ other`: with `self` the pose of B in A and `other` the pose of C in B, the pose of
    /// C in A.
    pub fn compose(&self, other: &Pose) -> Pose {
        let (s, c) = sin_cos(self.theta);
        Pose::new(
            self.x + c * other.x - s * other.y,
            self.y + s * other.x + c * other.y,
            self.theta + other.theta,
        )
    }

    /// The pose of A in B, for `self` the pose of B in A.
    pub fn inverse(&self) -> Pose {
        let (s, c) = sin_cos(self.theta);
        Pose::new(
            -(c * self.x + s * self.y),
            s * self.x - c * self.y,
            -self.theta,
        )
    }

    /// A point of B, in A.
    pub fn transform_point(&self, p: [f32; 2]) -> [f32; 2] {
        let (s, c) = sin_cos(self.theta);
        [c * p[0] - s * p[1] + self.x, s * p[0] + c * p[1] + self.y]
    }

    /// [`Pose::transform_point`] with the sine and cosine computed once, for many points.
    pub(crate) fn transformer(&self) -> impl Fn([f32; 2]) -> [f32; 2] + Copy {
        let (s, c) = sin_cos(self.theta);
        let (x, y) = (self.x, self.y);
        move |p: [f32; 2]| [c * p[0] - s * p[1] + x, s * p[0] + c * p[1] + y]
    }

    /// The line `x cos α + y sin α = ρ` of B, in A, with ρ ≥ 0 (α turned by π when needed):
    /// `(α + θ, ρ + x cos(α + θ) + y sin(α + θ))`.
    ///
    /// ```
    /// use pfe_pose::Pose;
    /// // The wall x = 2 m seen from a scanner 0.5 m further along x is at x = 1.5 m.
    /// let (a, r) = Pose::new(500.0, 0.0, 0.0).transform_line(0.0, 1500.0);
    /// assert!(a.abs() < 1e-6 && (r - 2000.0).abs() < 1e-3);
    /// ```
    pub fn transform_line(&self, alpha: f32, rho: f32) -> (f32, f32) {
        let a = alpha + self.theta;
        let (s, c) = sin_cos(a);
        normalise_line(a, rho + self.x * c + self.y * s)
    }

    /// `[x, y, θ]`.
    pub fn to_array(&self) -> [f32; 3] {
        [self.x, self.y, self.theta]
    }
}

/// `(α, ρ)` with ρ ≥ 0 and α in (−π, π].
pub(crate) fn normalise_line(alpha: f32, rho: f32) -> (f32, f32) {
    if rho < 0.0 {
        (wrap(alpha + PI), -rho)
    } else {
        (wrap(alpha), rho)
    }
}

/// The covariance of `a ⊕ b` for independent `a` (covariance `ca`) and `b` (`cb`), to first
/// order.
///
/// ```
/// use pfe_pose::{compose_covariance, Pose};
/// let c = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1e-4]];
/// let a = Pose::IDENTITY;
/// let b = Pose::new(1000.0, 0.0, 0.0);
/// let ab = compose_covariance(&a, &c, &b, &c);
/// // a's heading error of 0.01 rad moves b's end by 10 mm sideways: variance 1 + 100 + 1.
/// assert!((ab[1][1] - 102.0).abs() < 1e-2);
/// ```
pub fn compose_covariance(a: &Pose, ca: &Cov3, b: &Pose, cb: &Cov3) -> Cov3 {
    let (s, c) = sin_cos(a.theta);
    let ja = [
        [1.0, 0.0, -s * b.x - c * b.y],
        [0.0, 1.0, c * b.x - s * b.y],
        [0.0, 0.0, 1.0],
    ];
    let jb = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]];
    add3(&sandwich3(&ja, ca), &sandwich3(&jb, cb))
}

/// Angle wrapped into (−π, π] (NaN stays NaN).
#[inline(always)]
pub fn wrap(a: f32) -> f32 {
    if a > -PI && a <= PI {
        return a;
    }
    wrap_turns(a)
}

/// [`wrap`] of an angle outside (−π, π].
#[inline(never)]
fn wrap_turns(a: f32) -> f32 {
    if !a.is_finite() {
        return f32::NAN;
    }
    let two_pi = 2.0 * PI;
    let mut w = a - two_pi * floor((a + PI) / two_pi);
    if w <= -PI {
        w += two_pi;
    }
    if w > PI {
        w -= two_pi;
    }
    w
}

/// Below this magnitude an `f32` may have a fraction; at and above it every one is whole.
const WHOLE: f32 = 8_388_608.0;

/// `libm::floorf`, bit for bit, without its software loop: the integer part by the FPU's
/// conversion (exact below 2²³, as is `x` less it), the sign of a zero kept.
#[inline(always)]
pub(crate) fn floor(x: f32) -> f32 {
    if !(x.abs() < WHOLE) {
        return libm::floorf(x);
    }
    let t = x as i32 as f32;
    let r = if x - t < 0.0 { t - 1.0 } else { t };
    // −0 stays −0 (a negative `x` gives a negative result or −0, a positive one neither).
    f32::from_bits(r.to_bits() | (x.to_bits() & 0x8000_0000))
}

/// `libm::roundf` (half away from zero), bit for bit, as [`floor`].
#[inline(always)]
pub(crate) fn round(x: f32) -> f32 {
    if !(x.abs() < WHOLE) {
        return libm::roundf(x);
    }
    let t = x as i32 as f32;
    let f = x - t;
    let r = if f >= 0.5 {
        t + 1.0
    } else if f <= -0.5 {
        t - 1.0
    } else {
        t
    };
    f32::from_bits(r.to_bits() | (x.to_bits() & 0x8000_0000))
}

/// Square root to within an ulp or so, in plain `f32` arithmetic (so the same bits on every
/// target): a first guess from the exponent, three Newton steps. libm's `sqrtf` is a
/// bit-by-bit software loop on a Cortex-M4F (a few hundred instructions); this is about
/// twenty. Negative and NaN give NaN, +∞ gives +∞; subnormal inputs go to libm.
#[inline(always)]
pub(crate) fn sqrt(x: f32) -> f32 {
    if !(x >= f32::MIN_POSITIVE) || x == f32::INFINITY {
        return if x == 0.0 { 0.0 } else { libm::sqrtf(x) };
    }
    let mut y = f32::from_bits(0x1fbd_1df5 + (x.to_bits() >> 1));
    for _ in 0..3 {
        y = 0.5 * (y + x / y);
    }
    y
}

/// `sqrt(x² + y²)` with [`sqrt`] (for lengths in mm: no overflow to fear).
#[inline(always)]
pub(crate) fn hypot(x: f32, y: f32) -> f32 {
    sqrt(x * x + y * y)
}

/// `(sin x, cos x)`: pfe-core's f32 kernel ([`pfe_core::sin_cos_f32`]) for |x| ≤ 10⁴,
/// libm beyond (and for NaN, ±∞). libm's `sinf`/`cosf` evaluate in f64, which the Cortex-M4F
/// does in software (about 700 instructions a call); the kernel is about 40, and the same bits
/// on the host and the board.
pub(crate) fn sin_cos(x: f32) -> (f32, f32) {
    pfe_core::sin_cos_f32(x).unwrap_or_else(|| (libm::sinf(x), libm::cosf(x)))
}

/// `J C Jᵀ` for 3×3 matrices.
pub(crate) fn sandwich3(j: &Cov3, c: &Cov3) -> Cov3 {
    let mut jc = ZERO3;
    for (row, jr) in jc.iter_mut().zip(j) {
        for (k, out) in row.iter_mut().enumerate() {
            *out = jr[0] * c[0][k] + jr[1] * c[1][k] + jr[2] * c[2][k];
        }
    }
    let mut r = ZERO3;
    for (row, a) in r.iter_mut().zip(&jc) {
        for (out, b) in row.iter_mut().zip(j) {
            *out = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        }
    }
    r
}

/// `a + b`.
pub(crate) fn add3(a: &Cov3, b: &Cov3) -> Cov3 {
    let mut r = *a;
    for (row, br) in r.iter_mut().zip(b) {
        for (x, y) in row.iter_mut().zip(br) {
            *x += y;
        }
    }
    r
}

/// `(a + aᵀ) / 2`.
pub(crate) fn symmetrise3(a: &Cov3) -> Cov3 {
    let mut r = *a;
    for i in 0..3 {
        for j in 0..3 {
            r[i][j] = 0.5 * (a[i][j] + a[j][i]);
        }
    }
    r
}

/// True when every entry is finite.
pub(crate) fn finite3(a: &Cov3) -> bool {
    a.iter().flatten().all(|x| x.is_finite())
}

/// Eigen-decomposition of a symmetric 3×3 matrix by cyclic Jacobi rotations: the eigenvalues
/// in ascending order and the eigenvectors as the columns' rows (`v[k]` is the k-th
/// eigenvector).
pub(crate) fn eigen_sym3(a: &Cov3) -> ([f32; 3], [[f32; 3]; 3]) {
    let mut m = symmetrise3(a);
    // Columns of `v` accumulate the rotations.
    let mut v = [[1.0f32, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..12 {
        let off = m[0][1] * m[0][1] + m[0][2] * m[0][2] + m[1][2] * m[1][2];
        let diag = m[0][0] * m[0][0] + m[1][1] * m[1][1] + m[2][2] * m[2][2];
        if !(off > 1e-14 * diag) {
            break;
        }
        // The three planes in turn; constant indices, so no bounds check survives.
        jacobi_rotate::<0, 1>(&mut m, &mut v);
        jacobi_rotate::<0, 2>(&mut m, &mut v);
        jacobi_rotate::<1, 2>(&mut m, &mut v);
    }
    let mut vals = [m[0][0], m[1][1], m[2][2]];
    let mut vecs = [
        [v[0][0], v[1][0], v[2][0]],
        [v[0][1], v[1][1], v[2][1]],
        [v[0][2], v[1][2], v[2][2]],
    ];
    // Sort ascending (three elements: a small insertion sort).
    for i in 1..3 {
        let mut j = i;
        while j > 0 && vals[j] < vals[j - 1] {
            vals.swap(j, j - 1);
            vecs.swap(j, j - 1);
            j -= 1;
        }
    }
    (vals, vecs)
}

/// One Jacobi rotation of `m` in the plane (`P`, `Q`) zeroing `m[P][Q]`, accumulated in `v`.
#[inline(always)]
fn jacobi_rotate<const P: usize, const Q: usize>(m: &mut Cov3, v: &mut Cov3) {
    let apq = m[P][Q];
    if apq == 0.0 {
        return;
    }
    let theta = (m[Q][Q] - m[P][P]) / (2.0 * apq);
    let t = if theta.is_finite() {
        let sgn = if theta >= 0.0 { 1.0 } else { -1.0 };
        sgn / (theta.abs() + sqrt(theta * theta + 1.0))
    } else {
        0.0
    };
    let c = 1.0 / sqrt(t * t + 1.0);
    let s = t * c;
    for row in m.iter_mut() {
        let mkp = row[P];
        let mkq = row[Q];
        row[P] = c * mkp - s * mkq;
        row[Q] = s * mkp + c * mkq;
    }
    for k in 0..3 {
        let mpk = m[P][k];
        let mqk = m[Q][k];
        m[P][k] = c * mpk - s * mqk;
        m[Q][k] = s * mpk + c * mqk;
    }
    for row in v.iter_mut() {
        let vkp = row[P];
        let vkq = row[Q];
        row[P] = c * vkp - s * vkq;
        row[Q] = s * vkp + c * vkq;
    }
}

/// Inverse of a symmetric positive definite 3×3 matrix (`None` when not positive definite or
/// not finite). Inverted with unit diagonal (Jacobi scaling), so mixed units (mm², rad²) do
/// not limit it.
pub(crate) fn inverse_spd3(a: &Cov3) -> Option<Cov3> {
    if !(finite3(a) && a[0][0] > 0.0 && a[1][1] > 0.0 && a[2][2] > 0.0) {
        return None;
    }
    let d = [
        1.0 / sqrt(a[0][0]),
        1.0 / sqrt(a[1][1]),
        1.0 / sqrt(a[2][2]),
    ];
    let mut m = ZERO3;
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = a[i][j] * d[i] * d[j];
        }
    }
    let (vals, vecs) = eigen_sym3(&m);
    if !(vals[0] > 1e-6 * vals[2]) {
        return None;
    }
    let mut r = ZERO3;
    for (l, v) in vals.iter().zip(&vecs) {
        for i in 0..3 {
            for j in 0..3 {
                r[i][j] += v[i] * v[j] / l;
            }
        }
    }
    for i in 0..3 {
        for j in 0..3 {
            r[i][j] *= d[i] * d[j];
        }
    }
    finite3(&r).then_some(r)
}

/// A symmetric 2×2 matrix `[a, b; b, c]` stored as `(a, b, c)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Sym2 {
    pub a: f32,
    pub b: f32,
    pub c: f32,
}

impl Sym2 {
    #[inline(always)]
    pub fn add(self, o: Sym2) -> Sym2 {
        Sym2 {
            a: self.a + o.a,
            b: self.b + o.b,
            c: self.c + o.c,
        }
    }

    /// Inverse (`None` when not positive definite).
    #[inline(always)]
    pub fn inverse(self) -> Option<Sym2> {
        let det = self.a * self.c - self.b * self.b;
        if !(self.a > 0.0) || !(self.c > 0.0) || !(det > 1e-12 * self.a * self.c) {
            return None;
        }
        let r = Sym2 {
            a: self.c / det,
            b: -self.b / det,
            c: self.a / det,
        };
        (r.a.is_finite() && r.b.is_finite() && r.c.is_finite()).then_some(r)
    }

    /// `rᵀ M r`.
    #[inline(always)]
    pub fn quad(self, r: [f32; 2]) -> f32 {
        self.a * r[0] * r[0] + 2.0 * self.b * r[0] * r[1] + self.c * r[1] * r[1]
    }

    /// `R M Rᵀ` for the rotation by an angle of sine `s`, cosine `c`.
    #[inline(always)]
    pub fn rotate(self, s: f32, c: f32) -> Sym2 {
        let (a, b, d) = (self.a, self.b, self.c);
        Sym2 {
            a: c * c * a - 2.0 * c * s * b + s * s * d,
            b: c * s * (a - d) + (c * c - s * s) * b,
            c: s * s * a + 2.0 * c * s * b + c * c * d,
        }
    }

    pub fn finite(self) -> bool {
        self.a.is_finite() && self.b.is_finite() && self.c.is_finite()
    }
}

#[cfg(test)]
mod round_tests {
    /// [`super::floor`] and [`super::round`] against libm on every sign, exponent and many
    /// mantissas (all of them near the halves and the integers), NaN and ±∞.
    #[test]
    fn floor_and_round_are_libms() {
        let check = |x: f32| {
            assert_eq!(
                super::floor(x).to_bits(),
                libm::floorf(x).to_bits(),
                "floor {x:e}"
            );
            assert_eq!(
                super::round(x).to_bits(),
                libm::roundf(x).to_bits(),
                "round {x:e}"
            );
        };
        let mut s = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..2_000_000 {
            s ^= s >> 12;
            s ^= s << 25;
            s ^= s >> 27;
            check(f32::from_bits(
                (s.wrapping_mul(0x9e37_79b9_7f4a_7c15) >> 32) as u32,
            ));
        }
        // The neighbours of `x` away from and towards zero (for x ≠ 0).
        let near = |x: f32| {
            [
                f32::from_bits(x.to_bits() + 1),
                f32::from_bits(x.to_bits() - 1),
            ]
        };
        for k in 1i32..70_000 {
            let h = k as f32 * 0.5;
            let [up, down] = near(h);
            for x in [h, up, down, h * 1.0e-3, h * 97.0] {
                check(x);
                check(-x);
            }
        }
        for x in [
            0.0f32,
            -0.0,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            8_388_607.5,
        ] {
            check(x);
        }
        for e in 0..40 {
            let p = (1u64 << e) as f32;
            let [up, down] = near(p);
            for x in [p, up, down, p + 0.5, p - 0.5] {
                check(x);
                check(-x);
            }
        }
    }
}

#[cfg(test)]
mod sqrt_tests {
    #[test]
    fn sqrt_within_an_ulp_of_libm() {
        let mut x = 1e-30f32;
        while x < 1e30 {
            for k in [1.0f32, 1.3, 2.0, 2.7, 3.9] {
                let v = x * k;
                let (a, b) = (super::sqrt(v), libm::sqrtf(v));
                assert!((a - b).abs() <= 2.0 * f32::EPSILON * b, "{v}: {a} vs {b}");
            }
            x *= 7.0;
        }
        assert_eq!(super::sqrt(0.0), 0.0);
        assert!(super::sqrt(-1.0).is_nan() && super::sqrt(f32::NAN).is_nan());
        assert_eq!(super::sqrt(f32::INFINITY), f32::INFINITY);
        assert_eq!(super::hypot(3.0, 4.0), 5.0);
    }

    #[test]
    fn sin_cos_close_to_libm() {
        let mut x = -20.0f32;
        while x < 20.0 {
            let (s, c) = super::sin_cos(x);
            assert!(
                (s - libm::sinf(x)).abs() < 3e-7 && (c - libm::cosf(x)).abs() < 3e-7,
                "{x}"
            );
            x += 0.0137;
        }
        assert!(super::sin_cos(f32::NAN).0.is_nan());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_range() {
        for a in [-10.0f32, -PI, -3.0, 0.0, 3.0, PI, 7.0, 100.0] {
            let w = wrap(a);
            assert!(w > -PI - 1e-6 && w <= PI + 1e-6, "{a} → {w}");
            assert!(libm::sinf(w - a).abs() < 1e-4 && libm::cosf(w - a) > 0.999);
        }
        assert!(wrap(f32::NAN).is_nan() && wrap(f32::INFINITY).is_nan());
    }

    #[test]
    fn eigen_reconstructs() {
        let a = [[4.0, 1.0, 0.5], [1.0, 3.0, -0.2], [0.5, -0.2, 1e-3]];
        let (vals, vecs) = eigen_sym3(&a);
        assert!(vals[0] <= vals[1] && vals[1] <= vals[2]);
        for i in 0..3 {
            for j in 0..3 {
                let r: f32 = (0..3).map(|k| vals[k] * vecs[k][i] * vecs[k][j]).sum();
                assert!((r - a[i][j]).abs() < 1e-4, "{i}{j}: {r} vs {}", a[i][j]);
            }
        }
        let inv = inverse_spd3(&[[2.0, 0.0, 0.0], [0.0, 4.0, 0.0], [0.0, 0.0, 8.0]]);
        assert_eq!(inv.map(|m| m[2][2]), Some(0.125));
        assert!(inverse_spd3(&[[1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 1.0]]).is_none());
        // Mixed units: mm² and rad².
        let inv = inverse_spd3(&[[2500.0, 0.0, 0.0], [0.0, 2500.0, 0.0], [0.0, 0.0, 1e-4]]);
        assert!(inv.is_some_and(|m| (m[2][2] - 1e4).abs() < 1.0));
    }

    #[test]
    fn line_transform_matches_points() {
        let pose = Pose::new(700.0, -300.0, 0.8);
        let (a, r) = (2.5f32, 1200.0f32);
        // Two points of the line in B.
        let (s, c) = sin_cos(a);
        let p = [r * c - 500.0 * s, r * s + 500.0 * c];
        let q = [r * c + 900.0 * s, r * s - 900.0 * c];
        let (a2, r2) = pose.transform_line(a, r);
        for pt in [pose.transform_point(p), pose.transform_point(q)] {
            let d = pt[0] * libm::cosf(a2) + pt[1] * libm::sinf(a2) - r2;
            assert!(d.abs() < 1e-2, "{d}");
        }
        assert!(r2 >= 0.0);
    }
}
