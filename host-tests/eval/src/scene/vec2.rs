//! 2D vector maths in `f64` (mm, rad).

use std::f64::consts::{PI, TAU};

/// A 2D point or vector.
pub(crate) type V2 = [f64; 2];

pub(crate) fn sub(a: V2, b: V2) -> V2 {
    [a[0] - b[0], a[1] - b[1]]
}
pub(crate) fn add(a: V2, b: V2) -> V2 {
    [a[0] + b[0], a[1] + b[1]]
}
pub(crate) fn scale(a: V2, s: f64) -> V2 {
    [a[0] * s, a[1] * s]
}
pub(crate) fn dot(a: V2, b: V2) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}
pub(crate) fn cross(a: V2, b: V2) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}
pub(crate) fn norm(a: V2) -> f64 {
    a[0].hypot(a[1])
}
pub(crate) fn dir(angle: f64) -> V2 {
    [angle.cos(), angle.sin()]
}
pub(crate) fn wrap_pi(a: f64) -> f64 {
    let mut a = a % TAU;
    if a > PI {
        a -= TAU;
    } else if a <= -PI {
        a += TAU;
    }
    a
}
