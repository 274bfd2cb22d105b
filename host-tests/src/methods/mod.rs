//! One interface for every feature extractor compared here (PFE and the baselines), so that
//! one scorer, one benchmark and one CLI serve all of them.

pub mod baselines;
pub mod pfe;

pub use pfe::Pfe;

use pfe_core::{Feature, ScanGeometry};

/// Capacity of the host extractor: any scanner up to 2048 beams, 256 features.
pub const MAX_BEAMS: usize = 2048;
/// Feature capacity of the host extractor.
pub const MAX_FEATURES: usize = 256;

/// What a method found in one scan. Indices count every beam, valid or not.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Extraction {
    /// Mark (boundary) points, increasing.
    pub marks: Vec<usize>,
    /// Features in scan order.
    pub features: Vec<Feature>,
}

/// A feature extractor working on ranges in mm (NaN, 0 or > r_max = no return).
pub trait Method {
    /// Short name for tables ("pfe-paper", "pfe-default", "split-merge", "acf").
    fn name(&self) -> &str;
    /// Extracts one scan.
    fn extract(&mut self, geometry: &ScanGeometry, ranges_mm: &[f32]) -> Extraction;
}
