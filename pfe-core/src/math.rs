//! The few f32 functions the extractor needs, from `libm` (exact, default) or `micromath`
//! (fast approximations, feature `micromath`). Everything else in the crate calls these.

#[cfg(feature = "micromath")]
mod imp {
    use micromath::F32Ext;
    pub fn sqrt(x: f32) -> f32 {
        if x <= 0.0 {
            return if x == 0.0 { 0.0 } else { f32::NAN };
        }
        // micromath's sqrt is a bit-trick estimate; one Newton step brings it to ~1e-7.
        let y = F32Ext::sqrt(x);
        0.5 * (y + x / y)
    }
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
    pub fn sqrt(x: f32) -> f32 {
        libm::sqrtf(x)
    }
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

pub(crate) use imp::{atan2, cos, sin, sqrt};

/// `(sin x, cos x)`.
pub(crate) fn sin_cos(x: f32) -> (f32, f32) {
    (sin(x), cos(x))
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

/// Wraps an angle to (-π, π].
pub(crate) fn wrap_pi(a: f32) -> f32 {
    use core::f32::consts::PI;
    let mut a = a;
    if !a.is_finite() {
        return a;
    }
    // Bounded: inputs are sums of a few angles in (-4π, 4π).
    for _ in 0..8 {
        if a > PI {
            a -= 2.0 * PI;
        } else if a <= -PI {
            a += 2.0 * PI;
        } else {
            break;
        }
    }
    a
}
