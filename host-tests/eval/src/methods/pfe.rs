//! pfe-core behind the [`Method`] interface.

use pfe_core::{Config, ExtractError, Extractor, Scan, ScanGeometry};

use super::{Extraction, Method, ScanContext, MAX_BEAMS, MAX_FEATURES};

/// pfe-core behind the [`Method`] interface.
pub struct Pfe {
    name: String,
    config: Config,
    extractor: Box<Extractor<MAX_BEAMS, MAX_FEATURES>>,
    last: Result<(), ExtractError>,
}

impl Pfe {
    /// PFE with `config`, reported as `name`.
    pub fn new(name: &str, config: Config) -> Self {
        Self {
            name: name.to_string(),
            config,
            extractor: Box::new(Extractor::new()),
            last: Ok(()),
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

    /// How the last [`Method::extract`] went (an error value means no features or, for
    /// `FeatureCapacity`, the first ones only).
    pub fn last_result(&self) -> Result<(), ExtractError> {
        self.last
    }

    /// The mixed pixels of the last extraction: points of lines the scanner cannot see, in no
    /// feature ([`Extractor::is_veil`]).
    pub fn veils(&self) -> Vec<usize> {
        let n = self.extractor.points().len();
        (0..n).filter(|&i| self.extractor.is_veil(i)).collect()
    }
}

impl Method for Pfe {
    fn name(&self) -> &str {
        &self.name
    }

    fn extract(&mut self, geometry: &ScanGeometry, ranges_mm: &[f32]) -> Extraction {
        self.extract_in(geometry, ranges_mm, &ScanContext::default())
    }

    fn extract_in(
        &mut self,
        geometry: &ScanGeometry,
        ranges_mm: &[f32],
        context: &ScanContext,
    ) -> Extraction {
        let mut scan = Scan::from_mm(*geometry, ranges_mm);
        if let Some(odometry) = context.odometry {
            scan = scan.with_motion(odometry);
        }
        scan = scan
            .with_sweeps(u8::try_from(context.sweeps).unwrap_or(u8::MAX))
            .with_quantum(context.quantum);
        // Scans longer than the capacity are an error value: no features, kept for
        // `last_result`.
        self.last = self.extractor.extract(&scan, &self.config).map(|_| ());
        Extraction {
            marks: self.extractor.marks().collect(),
            features: self.extractor.features().to_vec(),
        }
    }
}
