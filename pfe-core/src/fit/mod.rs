//! Least-squares fits of a segment's points (§3.5): a [`mod@line`] in polar form and a [`circle`],
//! each with its covariance.

pub mod circle;
pub mod line;
pub(crate) mod run;
