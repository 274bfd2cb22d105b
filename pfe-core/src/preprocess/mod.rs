//! Pre-processing (§2): the systematic range [`correction`] and motion de-skewing ([`deskew`]).

pub mod correction;
pub mod deskew;
