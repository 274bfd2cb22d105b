//! The end of each step of an extraction, reported to a callback (feature `probe`, for
//! benchmarks: [`Extractor::extract_probed`](crate::Extractor::extract_probed)). Without the
//! feature the probe is zero-sized and reports nothing: the steps run as they would without it.

/// A step of the extraction ([`Extractor::extract`](crate::Extractor::extract) runs them in
/// this order), reported when it ends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(not(feature = "probe"), allow(dead_code))]
pub enum Step {
    /// Readings to points (range correction, de-skew).
    Load,
    /// The scan's own σ (with the checks for real scans).
    Scatter,
    /// Mark points by prediction (the walk).
    Mark,
    /// Interleaved sweeps out of place moved onto sweep 0 and marked again (when they are).
    Sweeps,
    /// The check step.
    Check,
    /// Segments, their type and fits (and the sweep offsets' error they inherit).
    Segments,
    /// Line ends over the beams beside them (with the checks for real scans).
    Reach,
    /// No line the scanner cannot see, small objects (with the checks for real scans).
    Sift,
}

/// Where the steps report: a callback, or nothing.
pub(crate) struct Probe<'a> {
    #[cfg(feature = "probe")]
    report: Option<&'a mut dyn FnMut(Step)>,
    #[cfg(not(feature = "probe"))]
    report: core::marker::PhantomData<&'a ()>,
}

impl<'a> Probe<'a> {
    /// Reports nothing.
    pub(crate) const fn none() -> Self {
        Self {
            #[cfg(feature = "probe")]
            report: None,
            #[cfg(not(feature = "probe"))]
            report: core::marker::PhantomData,
        }
    }

    /// Reports to `report`.
    #[cfg(feature = "probe")]
    pub(crate) fn to(report: &'a mut dyn FnMut(Step)) -> Self {
        Self {
            report: Some(report),
        }
    }

    /// `step` has ended.
    #[inline(always)]
    pub(crate) fn at(&mut self, step: Step) {
        #[cfg(feature = "probe")]
        if let Some(report) = self.report.as_mut() {
            report(step);
        }
        #[cfg(not(feature = "probe"))]
        let _ = step;
    }
}
