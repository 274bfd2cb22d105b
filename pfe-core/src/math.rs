//! The few f32 functions the extractor needs, from `libm` (exact, default) or `micromath`
//! (fast approximations, feature `micromath`). Everything else in the crate calls these.

#[cfg(feature = "micromath")]
mod imp {
    use micromath::F32Ext;
    pub fn atan2(y: f32, x: f32) -> f32 {
        F32Ext::atan2(y, x)
    }
    pub fn sin(x: f32) -> f32 {
        F32Ext::sin(x)
    }
    pub fn cos(x: f32) -> f32 {
        F32Ext::cos(x)
    }
}

#[cfg(not(feature = "micromath"))]
mod imp {
    pub fn atan2(y: f32, x: f32) -> f32 {
        libm::atan2f(y, x)
    }
    pub fn sin(x: f32) -> f32 {
        libm::sinf(x)
    }
    pub fn cos(x: f32) -> f32 {
        libm::cosf(x)
    }
}

pub(crate) use imp::{atan2, cos, sin};

/// Square root by a bit-level estimate and three Newton steps (within an ulp or two of the
/// correctly rounded result). libm's `sqrtf` is a bit-by-bit software loop costing a few
/// hundred instructions on a Cortex-M4F; this is a dozen, with the FPU's divide. The same code
/// runs on the host, so host and target results stay bit-identical. NaN and negative inputs
/// give NaN, +inf gives +inf, 0 gives 0.
pub(crate) fn sqrt(x: f32) -> f32 {
    if !(x > 0.0) {
        return if x == 0.0 { 0.0 } else { f32::NAN };
    }
    if x == f32::INFINITY {
        return x;
    }
    // Keep the estimate in the normal range: scale tiny inputs by 2^64 (result by 2^-32).
    let (x, scale) = if x < 1e-30 {
        (x * 18_446_744_073_709_551_616.0, 1.0 / 4_294_967_296.0)
    } else {
        (x, 1.0)
    };
    let mut y = f32::from_bits(0x1fbd_1df5 + (x.to_bits() >> 1));
    for _ in 0..3 {
        y = 0.5 * (y + x / y);
    }
    y * scale
}

/// `(sin x, cos x)`.
pub(crate) fn sin_cos(x: f32) -> (f32, f32) {
    (sin(x), cos(x))
}

/// True when `x` is neither infinite nor NaN. `x − x` is exactly 0 for every finite `x` and
/// NaN otherwise: two FPU instructions, where `f32::is_finite` becomes a dozen integer ones
/// on thumbv7em (the hot loops call this once or twice per point).
#[inline]
#[allow(clippy::eq_op)] // x − x is the point: 0 or NaN.
pub(crate) fn finite(x: f32) -> bool {
    x - x == 0.0
}

/// Absolute value without std.
pub(crate) fn abs(x: f32) -> f32 {
    if x < 0.0 {
        -x
    } else {
        x
    }
}

/// Hypotenuse.
pub(crate) fn hypot(x: f32, y: f32) -> f32 {
    sqrt(x * x + y * y)
}

#[cfg(test)]
mod tests {
    extern crate std;

    #[test]
    fn finite_agrees_with_the_standard_test() {
        let specials = [
            0.0f32,
            -0.0,
            1.0,
            -1.0,
            f32::MIN_POSITIVE,
            1e-45,
            -1e-45,
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
        ];
        for x in specials {
            assert_eq!(super::finite(x), x.is_finite(), "{x}");
        }
        let mut bits = 0u32;
        loop {
            let x = f32::from_bits(bits);
            assert_eq!(super::finite(x), x.is_finite(), "{bits:#x}");
            match bits.checked_add(0x0001_0003) {
                Some(b) => bits = b,
                None => break,
            }
        }
    }

    #[test]
    fn sqrt_is_within_two_ulp_everywhere() {
        let mut x = 1e-38f32;
        while x < 1e38 {
            for k in [1.0f32, 1.3, 1.7, 2.9, 7.1] {
                let v = x * k;
                let exact = (f64::from(v)).sqrt() as f32;
                let got = super::sqrt(v);
                let ulps = (got.to_bits() as i64 - exact.to_bits() as i64).abs();
                assert!(ulps <= 2, "sqrt({v}) = {got}, exact {exact}");
            }
            x *= 3.7;
        }
        assert_eq!(super::sqrt(0.0), 0.0);
        assert!(super::sqrt(-1.0).is_nan() && super::sqrt(f32::NAN).is_nan());
        assert_eq!(super::sqrt(f32::INFINITY), f32::INFINITY);
    }
}
