//! One interface for every feature extractor compared here (PFE and the baselines), so that
//! one scorer, one benchmark and one CLI serve all of them.

use pfe_core::{Config, Extractor, Feature, Scan, ScanGeometry};

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

/// pfe-core behind the [`Method`] interface.
pub struct Pfe {
    name: String,
    config: Config,
    extractor: Box<Extractor<MAX_BEAMS, MAX_FEATURES>>,
}

impl Pfe {
    /// PFE with `config`, reported as `name`.
    pub fn new(name: &str, config: Config) -> Self {
        Self {
            name: name.to_string(),
            config,
            extractor: Box::new(Extractor::new()),
        }
    }

    /// The paper's configuration.
    pub fn paper() -> Self {
        Self::new("pfe-paper", Config::paper())
    }

    /// The default configuration.
    pub fn default_config() -> Self {
        Self::new("pfe-default", Config::default())
    }

    /// The configuration in use.
    pub fn config(&self) -> &Config {
        &self.config
    }
}

impl Method for Pfe {
    fn name(&self) -> &str {
        &self.name
    }

    fn extract(&mut self, geometry: &ScanGeometry, ranges_mm: &[f32]) -> Extraction {
        // Scans longer than the capacity are an error value: reported as no features.
        let _ = self
            .extractor
            .extract(&Scan::from_mm(*geometry, ranges_mm), &self.config);
        Extraction {
            marks: self.extractor.marks().collect(),
            features: self.extractor.features().to_vec(),
        }
    }
}
