//! The two baseline extractors the PFE paper compares against, behind the same
//! [`Method`](crate::methods::Method) interface as PFE:
//!
//! - [`SplitMerge`]: adaptive breakpoint detection ([`abd`]) followed by split-and-merge
//!   (iterative end-point fit) inside each segment, with a circle test;
//! - [`Acf`]: adaptive breakpoint detection followed by the adaptive curvature function of
//!   Núñez et al. (2008), the method the PFE paper measures itself against.
//!
//! Both return pfe-core's [`Feature`] with the same covariances as PFE (range noise propagated
//! along each beam: [`LineFit::covariance_range`], [`circle_covariance_range`](pfe_core::circle_covariance_range)). All geometry
//! (fits, covariances, points) is pfe-core's; this module only segments.
//!
//! Conventions shared with PFE: indices count every beam, valid or not; a reading is a point
//! when pfe-core's [`Scan::point`] accepts it (finite, > 0, ≤ r_max); invalid readings break
//! segments; segments of fewer than [`MIN_POINTS`] points are not features; the marks are the
//! first and last index of every final segment (short ones included, as in PFE).

pub mod abd;
pub mod acf;
pub mod split_merge;

pub use abd::Abd;
pub use acf::Acf;
pub use split_merge::SplitMerge;

use crate::methods::Extraction;
use pfe_core::{
    circle_feature, fit_circle, fit_line, line_feature, refine_circle, CircleMethod, Feature,
    LineFit, Point, Scan, ScanGeometry,
};

/// Smallest segment that becomes a feature (the paper's 4 points).
pub const MIN_POINTS: usize = 4;

/// Range noise σ_r assumed by default, mm (LMS200 data sheet, as in the PFE paper).
pub const DEFAULT_SIGMA_R: f32 = 5.0;

/// Geometric refinement steps after the Hyper circle fit (as pfe-core's default config).
const CIRCLE_REFINE: usize = 5;

/// Cartesian points of a scan: `None` for a reading pfe-core treats as no return.
/// An invalid geometry gives no points at all.
pub fn scan_points(geometry: &ScanGeometry, ranges_mm: &[f32]) -> Vec<Option<Point>> {
    if !geometry.is_valid() {
        return vec![None; ranges_mm.len()];
    }
    let scan = Scan::from_mm(*geometry, ranges_mm);
    (0..ranges_mm.len())
        .map(|i| scan.point(i).filter(Point::is_valid))
        .collect()
}

/// Every beam's point ([`scan_points`]), a reading with no return as [`Point::INVALID`].
pub fn beam_points(geometry: &ScanGeometry, ranges_mm: &[f32]) -> Vec<Point> {
    scan_points(geometry, ranges_mm)
        .into_iter()
        .map(|p| p.unwrap_or(Point::INVALID))
        .collect()
}

/// Which model a segment gets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Model {
    Line,
    Circle,
}

/// The points `first..=last` of `pts` (all valid inside an ABD segment), or empty.
pub(crate) fn slice(pts: &[Point], first: usize, last: usize) -> &[Point] {
    pts.get(first..=last).unwrap_or(&[])
}

/// Hyper circle fit refined geometrically (pfe-core), when it succeeds.
pub(crate) fn circle_fit(pts: &[Point]) -> Option<pfe_core::Circle> {
    let c = fit_circle(pts, CircleMethod::Hyper).ok()?;
    refine_circle(pts, c, CIRCLE_REFINE).ok()
}

/// Largest distance of `pts` from the circle `c`.
pub(crate) fn circle_max_residual(pts: &[Point], c: &pfe_core::Circle) -> f32 {
    pts.iter()
        .map(|p| (p.distance(&c.center) - c.radius).abs())
        .fold(0.0, f32::max)
}

/// Largest distance of `pts` from the fitted line `l`.
pub(crate) fn line_max_residual(pts: &[Point], l: &LineFit) -> f32 {
    pts.iter()
        .map(|p| l.signed_distance(p).abs())
        .fold(0.0, f32::max)
}

/// The feature of segment `first..=last` (indices into the whole scan; `pts` are the points
/// of exactly that segment) as `model`, with pfe-core's fits and range-noise covariances
/// (scanner at the origin). A circle that cannot be fitted falls back to a line; `None` when
/// neither can be fitted or the result is not well formed.
pub(crate) fn make_feature(
    pts: &[Point],
    first: usize,
    last: usize,
    model: Model,
    sigma_r: f32,
) -> Option<Feature> {
    let origin = Point::new(0.0, 0.0);
    let circle = (model == Model::Circle)
        .then(|| circle_fit(pts))
        .flatten()
        .and_then(|c| circle_feature(pts, first, last, &c, origin, sigma_r));
    circle.or_else(|| line_feature(pts, first, last, &fit_line(pts).ok()?, origin, sigma_r))
}

/// One final segment of a baseline: beams `first..=last` and its model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Piece {
    pub first: usize,
    pub last: usize,
    pub model: Model,
}

/// Marks and features from the final pieces (in scan order). `pts` holds every beam's point
/// (invalid ones as [`Point::INVALID`]); a piece never spans an invalid beam.
pub(crate) fn assemble(
    pts: &[Point],
    pieces: &[Piece],
    sigma_r: f32,
) -> crate::methods::Extraction {
    let mut marks = Vec::with_capacity(2 * pieces.len());
    let mut features = Vec::new();
    for p in pieces {
        marks.push(p.first);
        if p.last != p.first {
            marks.push(p.last);
        }
        if p.last + 1 - p.first >= MIN_POINTS {
            let seg = slice(pts, p.first, p.last);
            if let Some(f) = make_feature(seg, p.first, p.last, p.model, sigma_r) {
                features.push(f);
            }
        }
    }
    marks.sort_unstable();
    marks.dedup();
    crate::methods::Extraction { marks, features }
}

/// The fits alone of `features` (found in the scan whose points are `pts`, every beam's,
/// invalid ones as [`Point::INVALID`]): each feature's beams fitted again as its model, as the
/// baselines fit their pieces. Their cost is a floor under any method that outputs these
/// features (`pfe bench`'s `fits-only` row).
pub fn refit(pts: &[Point], features: &[Feature], sigma_r: f32) -> crate::methods::Extraction {
    let pieces: Vec<Piece> = features
        .iter()
        .map(|f| {
            let (first, last, model) = match f {
                Feature::Line(l) => (l.first, l.last, Model::Line),
                Feature::Circle(c) => (c.first, c.last, Model::Circle),
                // An object's centre is its points' mean: as cheap as a line's fit.
                f => (
                    u16::try_from(f.first()).unwrap_or(u16::MAX),
                    u16::try_from(f.last()).unwrap_or(u16::MAX),
                    Model::Line,
                ),
            };
            Piece {
                first: usize::from(first),
                last: usize::from(last),
                model,
            }
        })
        .collect();
    assemble(pts, &pieces, sane_sigma(sigma_r))
}

/// The frame of the ABD-based baselines: the scan's points, each ABD segment (inclusive beam
/// indices) cut into pieces by `cut`, piece boundaries settled, the pieces fitted.
pub(crate) fn extract_segments(
    abd: &Abd,
    geometry: &ScanGeometry,
    ranges_mm: &[f32],
    mut cut: impl FnMut(&[Point], usize, usize, &mut Vec<Piece>),
) -> Extraction {
    let opts = scan_points(geometry, ranges_mm);
    let pts: Vec<Point> = opts.iter().map(|p| p.unwrap_or(Point::INVALID)).collect();
    let mut pieces = Vec::new();
    for (s, e) in abd.segments(geometry, &opts) {
        let mut seg_pieces = Vec::new();
        cut(&pts, s, e, &mut seg_pieces);
        settle_boundaries(&pts, &mut seg_pieces);
        pieces.extend(seg_pieces);
    }
    assemble(&pts, &pieces, abd.sigma())
}

/// A sane σ_r: positive and finite, else the default.
pub(crate) fn sane_sigma(sigma_r: f32) -> f32 {
    if sigma_r.is_finite() && sigma_r > 0.0 {
        sigma_r
    } else {
        DEFAULT_SIGMA_R
    }
}

/// Moves each boundary point between two line pieces to the line it is closer to.
pub(crate) fn settle_boundaries(pts: &[Point], pieces: &mut [Piece]) {
    for i in 1..pieces.len() {
        let (Some(l), Some(r)) = (pieces.get(i - 1).copied(), pieces.get(i).copied()) else {
            continue;
        };
        if l.model != Model::Line || r.model != Model::Line || l.last + 1 != r.first {
            continue;
        }
        let (Ok(fl), Ok(fr)) = (
            fit_line(slice(pts, l.first, l.last)),
            fit_line(slice(pts, r.first, r.last)),
        ) else {
            continue;
        };
        let closer_to_right = |p: &Point| fr.signed_distance(p).abs() < fl.signed_distance(p).abs();
        let closer_to_left = |p: &Point| fl.signed_distance(p).abs() < fr.signed_distance(p).abs();
        let (mut last, mut first) = (l.last, r.first);
        if last > l.first + 2 && pts.get(last).is_some_and(closer_to_right) {
            last -= 1;
            first -= 1;
        } else if first + 2 < r.last && pts.get(first).is_some_and(closer_to_left) {
            last += 1;
            first += 1;
        }
        if let Some(p) = pieces.get_mut(i - 1) {
            p.last = last;
        }
        if let Some(p) = pieces.get_mut(i) {
            p.first = first;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::methods::Method;
    use crate::scene::{Scenario, SceneKind};

    /// `refit` fits exactly the beams and models it is given: on split-and-merge's and ACF's
    /// extractions (fitted by the same recipe) it gives back every feature, bit for bit.
    #[test]
    fn refit_gives_back_the_baselines_features() {
        let mut methods: [Box<dyn Method>; 2] = [Box::new(SplitMerge::new()), Box::new(Acf::new())];
        let (mut lines, mut circles) = (0, 0);
        for seed in 0..40 {
            let s = Scenario::new(SceneKind::Mixed, seed).simulate();
            let pts = beam_points(&s.geometry, &s.ranges_mm);
            for m in methods.iter_mut() {
                let out = m.extract(&s.geometry, &s.ranges_mm);
                let again = refit(&pts, &out.features, DEFAULT_SIGMA_R);
                assert_eq!(again.features, out.features, "{} seed {seed}", m.name());
                for f in &out.features {
                    match f {
                        Feature::Line(_) => lines += 1,
                        Feature::Circle(_) => circles += 1,
                        _ => {}
                    }
                }
            }
        }
        assert!(
            lines > 100 && circles > 10,
            "{lines} lines, {circles} circles"
        );
    }
}
