//! Least-squares fits of a segment's points (§3.5): a [`line`] in polar form and a [`circle`],
//! each with its covariance.

pub mod circle;
pub mod line;
