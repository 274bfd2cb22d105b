//! One interface for every feature extractor compared here (PFE and the baselines), so that
//! one scorer, one benchmark and one CLI serve all of them.

pub mod baselines;
pub mod pfe;

pub use pfe::Pfe;

pub use pfe_formats::{Extraction, MAX_BEAMS, MAX_FEATURES};

use pfe_core::{Motion, ScanGeometry};

/// A feature extractor working on ranges in mm (NaN, 0 or > r_max = no return).
pub trait Method {
    /// Short name for tables ("pfe-paper", "pfe-default", "split-merge", "acf").
    fn name(&self) -> &str;
    /// Extracts one scan.
    fn extract(&mut self, geometry: &ScanGeometry, ranges_mm: &[f32]) -> Extraction;
    /// Extracts one scan knowing more about how it was taken (default: ignores `context`, as
    /// the baselines do).
    fn extract_in(
        &mut self,
        geometry: &ScanGeometry,
        ranges_mm: &[f32],
        context: &ScanContext,
    ) -> Extraction {
        let _ = context;
        self.extract(geometry, ranges_mm)
    }
}

/// What is known about a scan beyond its geometry and ranges.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ScanContext {
    /// The robot's motion during the scan (odometry), when known.
    pub odometry: Option<Motion>,
    /// Number of interleaved sweeps the scan is made of (0 or 1: one).
    pub sweeps: usize,
    /// Grid the ranges lie on, mm (0: unknown; pfe's `Scan::quantum`):
    /// [`range_quantum`](pfe_formats::range_quantum) for recordings.
    pub quantum: f32,
}
