//! What an extraction gives back besides its features: its statistics ([`Stats`]), and the
//! buffer the features go to ([`FeatureSink`]).

use heapless::Vec;

use crate::feature::Feature;

/// What one extraction did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Stats {
    /// Readings in the scan.
    pub readings: usize,
    /// Valid points.
    pub valid: usize,
    /// Segments (of any length).
    pub segments: usize,
    /// Segments shorter than `min_points`, ignored.
    pub short_segments: usize,
    /// Segments whose fit failed (degenerate), ignored.
    pub degenerate: usize,
    /// Features stored.
    pub features: usize,
    /// Features that did not fit in the buffer.
    pub dropped: usize,
    /// Predictions made (N + M in the paper's count).
    pub predictions: usize,
    /// Interleaved sweeps moved onto sweep 0 by their estimated offset (scans of several
    /// sweeps without motion, default mode).
    pub sweeps_aligned: usize,
    /// The scan's own σ_r in µm, when it scattered well beyond the configured one and the
    /// extraction used it (with [`Config::scrutiny`](crate::Config::scrutiny)); else 0.
    pub scan_sigma_um: u32,
    /// Small objects reported (with [`Config::scrutiny`](crate::Config::scrutiny)).
    pub objects: usize,
    /// Points of lines the scanner cannot see (over 85° incidence at their midpoint, or
    /// shorter than 10 mm: mixed pixels), in no feature (with
    /// [`Config::scrutiny`](crate::Config::scrutiny); `Extractor::is_veil` tells which).
    pub veils: usize,
}

/// Where the segment step puts the features (an extractor's buffer, whatever its capacity).
pub(crate) trait FeatureSink {
    /// Stores `f`; false when there is no room.
    fn push(&mut self, f: Feature) -> bool;
    /// The features stored, in the order pushed.
    fn features_mut(&mut self) -> &mut [Feature];
    /// Keeps only the features `keep` says, in order.
    fn retain(&mut self, keep: &mut dyn FnMut(&Feature) -> bool);
}

impl<const M: usize> FeatureSink for Vec<Feature, M> {
    fn push(&mut self, f: Feature) -> bool {
        Vec::push(self, f).is_ok()
    }
    fn features_mut(&mut self) -> &mut [Feature] {
        self
    }
    fn retain(&mut self, keep: &mut dyn FnMut(&Feature) -> bool) {
        Vec::retain(self, |f| keep(f));
    }
}
