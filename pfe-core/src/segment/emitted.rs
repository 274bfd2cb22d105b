//! Test helper: segments emitted as the segment step emits them.

use heapless::Vec;

use super::join::join_collinear;
use super::{emit, JOINS_MAX};
use crate::config::Config;
use crate::extractor::Extractor;
use crate::feature::Feature;
use crate::pass::Pass;
use crate::scan::{Scan, ScanGeometry};

/// The features of the scan `ranges` (geometry `g`, the default configuration) after the
/// `segments` are emitted in order as the segment step does, each followed by
/// [`join_collinear`].
pub(super) fn emitted<const N: usize>(
    g: ScanGeometry,
    ranges: &[f32; N],
    segments: [(usize, usize); 2],
) -> Vec<Feature, 8> {
    emitted_after(g, ranges, segments, |_| {})
}

/// [`emitted`] after `prepare` has set flags of the loaded pass (a walk's marks).
pub(super) fn emitted_after<const N: usize>(
    g: ScanGeometry,
    ranges: &[f32; N],
    segments: [(usize, usize); 2],
    prepare: impl FnOnce(&mut Pass<'_>),
) -> Vec<Feature, 8> {
    let config = Config::default();
    let mut ex = Extractor::<N, 8>::new();
    ex.with_pass(&Scan::from_mm(g, ranges), &config, |pass, rule| {
        let Some(noise) = rule.noise() else {
            panic!("the default rule")
        };
        prepare(pass);
        let mut out: Vec<Feature, 8> = Vec::new();
        let mut joins = JOINS_MAX;
        for (s, e) in segments {
            emit::<true>(pass, s, e, None, &config, &mut out);
            join_collinear(pass, noise, &config, &mut out, &mut joins);
        }
        out
    })
}
