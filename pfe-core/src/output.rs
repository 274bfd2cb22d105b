//! What an extraction gives back besides its features: its statistics ([`Stats`]), the
//! buffer the features go to ([`FeatureSink`]), and where each step ends for whoever
//! watches ([`Stage`], [`StageObserver`]).

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
    /// [`push`](Self::push) of a copy of `f`: the feature copied once, into its slot.
    fn push_copy(&mut self, f: &Feature) -> bool;
    /// The features stored, in the order pushed.
    fn features_mut(&mut self) -> &mut [Feature];
    /// Keeps only the features `keep` says, in order (it asks each once, in order).
    fn retain(&mut self, keep: &mut dyn FnMut(&Feature) -> bool);
}

impl<const M: usize> FeatureSink for Vec<Feature, M> {
    fn push(&mut self, f: Feature) -> bool {
        Vec::push(self, f).is_ok()
    }
    fn push_copy(&mut self, f: &Feature) -> bool {
        Vec::push(self, *f).is_ok()
    }
    fn features_mut(&mut self) -> &mut [Feature] {
        self
    }
    fn retain(&mut self, keep: &mut dyn FnMut(&Feature) -> bool) {
        Vec::retain(self, |f| keep(f));
    }
}

/// A step of the extraction (`docs/ARCHITECTURE.md`), as a [`StageObserver`] is told of it, in
/// this order. A step the configuration does not take still ends (at once).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Stage {
    /// Readings to points: range correction, motion de-skew.
    Load,
    /// The scan's own σ from its scatter (with [`Config::scrutiny`](crate::Config::scrutiny)).
    Scatter,
    /// Mark points by prediction (the first walk).
    Mark,
    /// Interleaved sweeps out of place moved onto sweep 0 and walked again.
    Sweeps,
    /// The check step.
    Check,
    /// Segments, their types and fits (and what they inherit from moved sweeps).
    Segments,
    /// Line ends reaching over the beams beside them.
    Reach,
    /// No line the scanner cannot see; small objects.
    Sift,
}

impl Stage {
    /// Every stage, in the order they end.
    pub const ALL: [Stage; 8] = [
        Stage::Load,
        Stage::Scatter,
        Stage::Mark,
        Stage::Sweeps,
        Stage::Check,
        Stage::Segments,
        Stage::Reach,
        Stage::Sift,
    ];

    /// Short lower-case name (`"load"`, `"scatter"`, …).
    pub const fn name(self) -> &'static str {
        match self {
            Stage::Load => "load",
            Stage::Scatter => "scatter",
            Stage::Mark => "mark",
            Stage::Sweeps => "sweeps",
            Stage::Check => "check",
            Stage::Segments => "segments",
            Stage::Reach => "reach",
            Stage::Sift => "sift",
        }
    }

    /// Position in [`Stage::ALL`].
    pub const fn index(self) -> usize {
        self as usize
    }
}

/// Told when each [`Stage`] of an extraction ends
/// ([`Extractor::extract_observed`](crate::Extractor::extract_observed)): read a clock or a
/// cycle counter there to time each stage (the first stage starts when the call does). The
/// plain [`Extractor::extract`](crate::Extractor::extract) tells no one and costs nothing for
/// it (a separate copy of the steps' sequence, compiled without the calls).
///
/// ```
/// use pfe_core::{Config, Extractor, Scan, ScanGeometry, Stage, StageObserver};
/// struct Seen(Vec<Stage>);
/// impl StageObserver for Seen {
///     fn ended(&mut self, stage: Stage) {
///         self.0.push(stage);
///     }
/// }
/// let mut ex = Extractor::<361, 32>::new();
/// let scan = Scan::from_mm(ScanGeometry::LMS200_180_050, &[2000.0; 361]);
/// let mut seen = Seen(Vec::new());
/// ex.extract_observed(&scan, &Config::default(), &mut seen)?;
/// assert_eq!(seen.0, Stage::ALL);
/// # Ok::<(), pfe_core::ExtractError>(())
/// ```
pub trait StageObserver {
    /// `stage` has just ended.
    fn ended(&mut self, stage: Stage);
}

/// Nobody watching: [`Extractor::extract`](crate::Extractor::extract)'s observer, whose calls
/// compile to nothing.
pub(crate) struct Unobserved;

impl StageObserver for Unobserved {
    #[inline(always)]
    fn ended(&mut self, _: Stage) {}
}

#[cfg(test)]
mod tests {
    use super::Stage;

    /// The stages' names are an interface (the board bench's per-stage rows read them): one
    /// each, distinct, in [`Stage::ALL`]'s order, and each stage at its own index.
    #[test]
    fn each_stage_has_its_own_name_and_index() {
        let names = Stage::ALL.map(Stage::name);
        assert_eq!(
            names,
            ["load", "scatter", "mark", "sweeps", "check", "segments", "reach", "sift"]
        );
        for (i, s) in Stage::ALL.into_iter().enumerate() {
            assert_eq!(s.index(), i);
        }
    }
}
