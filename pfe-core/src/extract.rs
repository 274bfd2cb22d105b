//! The extractor: points → mark points (§3.1–3.2, §3.6) → check step and pairing (§3.3) →
//! segments (§3.4) → type and parameters (§3.5), in one pass over the points plus one
//! prediction per check and one fit per segment: O(N + M), no recursion, no allocation.

use heapless::Vec;

use crate::config::{Config, NoiseModel, Threshold, Typing, NP};
use crate::error::ExtractError;
use crate::feature::{circle_feature, line_feature, line_feature_with, Feature};
use crate::fit::circle::{
    fit_circle, refine_circle, refine_from, ArcSums, Circle, NormalEquations,
};
use crate::fit::line::{fill_spreads, fit_axis, fit_line, BeamSpan};
use crate::geometry::{ray_circle_intersection, Point};
use crate::math;
use crate::predict::{paper_threshold, Prediction, WindowLine};
use crate::preprocess::deskew::Motion;
use crate::scan::{max_code, valid_mm, Ranges, Scan, ScanGeometry};

const VALID: u8 = 1;
/// First point of a segment (a mark point in the paper's sense).
const START: u8 = 2;
/// Last point of a segment (the paired mark point).
const END: u8 = 4;
/// A segment start caused by a jump (never inside one surface, so never merged).
const JUMP: u8 = 8;
/// Most neighbouring segment starts the default mode's walk notes for its check step.
const NEIGHBOURS: usize = 16;
/// Sizes of the union of two neighbouring segments tested for being one arc after
/// segmentation (fewer points do not show an arc above the noise).
const MERGE_SIZES: core::ops::RangeInclusive<usize> = 6..=64;
/// Points of the new segment seen before its boundary is refined (its line in the refinement
/// is fitted to the points after the candidates).
const REFINE_AFTER: usize = 6;
/// Points each side used to refine a boundary.
const REFINE_SPAN: usize = 6;
/// Size of a new segment at which it is tested for being the same arc as the one before (a
/// second test at 16 points changed no measured score and cost 4.6 instructions a point).
const MERGE_AT: usize = 8;

/// The default mode's per-point limits: the jump limit (`gap_factor` × the previous range +
/// `jump_add`, mm) and the line test's (k σ_r)² and floor.
struct Limits {
    gap_factor: f32,
    jump_add: f32,
    k_sigma2: f32,
    floor: f32,
}

/// The default mode's state while it walks the scan.
#[derive(Clone, Copy, Default)]
struct Walk {
    /// Start of the current segment.
    seg: Option<usize>,
    /// The last fresh window's line and the last point it may test.
    cache: Option<(WindowLine, usize)>,
    /// Boundary awaiting refinement: (its index, the start of the segment before it).
    pending: Option<(usize, usize)>,
    /// Last boundary that was not a jump and the start of the segment before it (a jump is
    /// never inside one surface, so never merged).
    joinable: Option<(usize, usize)>,
}

impl Walk {
    /// The first point from `k` (before `limit`) where a boundary is refined or a merge is
    /// tested.
    fn next_check(&self, k: usize, limit: usize) -> usize {
        let refine = self.pending.map(|(b, _)| b + REFINE_AFTER);
        let merge = self.joinable.map(|(b, _)| b + MERGE_AT - 1);
        [refine, merge]
            .into_iter()
            .flatten()
            .filter(|&at| at >= k)
            .fold(limit, usize::min)
    }
}

/// What [`Extractor::next_flag`] looks for.
#[derive(Clone, Copy)]
enum Seek {
    /// A valid point that starts a segment.
    Mark,
    /// A point that is not a valid segment start.
    NotMark,
    /// A valid point.
    Valid,
    /// The end of a segment's points: a start or an invalid point.
    SegmentEnd,
}

impl Seek {
    const MARK: u8 = VALID | START;
    /// `VALID` / `VALID | START` in each byte of a word of four flags.
    const V4: u32 = u32::from_le_bytes([VALID; 4]);
    const M4: u32 = u32::from_le_bytes([Self::MARK; 4]);

    fn hit(self, f: u8) -> bool {
        match self {
            Seek::Mark => f & Self::MARK == Self::MARK,
            Seek::NotMark => f & Self::MARK != Self::MARK,
            Seek::Valid => f & VALID != 0,
            Seek::SegmentEnd => f & Self::MARK != VALID,
        }
    }

    /// True when none of the four flags in `word` is a hit.
    fn none_in(self, word: u32) -> bool {
        match self {
            Seek::Mark => word & (Self::M4 & !Self::V4) == 0,
            Seek::NotMark => word & Self::M4 == Self::M4,
            Seek::Valid => word & Self::V4 == 0,
            Seek::SegmentEnd => word & Self::M4 == Self::V4,
        }
    }
}

/// What one extraction did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
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
}

/// Feature extractor with room for `N` readings and `M` features. About `25·N + 64·M` bytes:
/// put it in a `static` on a microcontroller.
///
/// ```
/// use pfe_core::{Config, Extractor, Feature, Scan, ScanGeometry};
/// // A wall 2 m ahead, seen by an LMS200 (180°, 0.5°): r = 2000 / cos(bearing).
/// let g = ScanGeometry::LMS200_180_050;
/// let ranges: Vec<f32> = (0..361)
///     .map(|i| {
///         let b = g.bearing(i);
///         if b.abs() < 1.0 { 2000.0 / b.cos() } else { f32::NAN }
///     })
///     .collect();
/// let mut ex = Extractor::<361, 32>::new();
/// ex.extract(&Scan::from_mm(g, &ranges), &Config::default())?;
/// assert_eq!(ex.features().len(), 1);
/// assert!(matches!(ex.features().first(),
///     Some(Feature::Line(l)) if (l.rho - 2000.0).abs() < 0.5 && l.alpha.abs() < 1e-3));
/// # Ok::<(), pfe_core::ExtractError>(())
/// ```
pub struct Extractor<const N: usize, const M: usize> {
    points: [Point; N],
    /// Beam directions (cos, sin) of the geometry `dirs_of` (start angle and step, as bits;
    /// a step of 0, never valid, for none yet).
    dirs: [Point; N],
    /// The [`BeamSpan::spread`] of `k + 1` beams of that geometry at `k`, and the direction
    /// of half a step (cos, sin).
    spreads: [f32; N],
    half_step: Point,
    /// Largest gap between consecutive points of one surface per mm of range (see
    /// `directions`).
    gap_factor: f32,
    dirs_of: (u32, u32),
    /// Corrected measured range of each valid point, mm (its distance from the scanner).
    ranges: [f32; N],
    flags: [u8; N],
    /// Segment starts the default mode's walk set right after another one, in increasing
    /// order: the only places where its check step can act. `None` when not known (the
    /// paper's mode, or more than [`NEIGHBOURS`]): the check step then reads every flag.
    neighbours: Option<Vec<u16, NEIGHBOURS>>,
    len: usize,
    motion: Option<Motion>,
    features: Vec<Feature, M>,
    stats: Stats,
}

impl<const N: usize, const M: usize> Default for Extractor<N, M> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize, const M: usize> Extractor<N, M> {
    /// An empty extractor (`const`, so it can live in a `static`).
    pub const fn new() -> Self {
        // All zero bytes (points past `len` are never read), so that a `static` extractor
        // goes to .bss rather than being copied from flash as well.
        Self {
            points: [Point::new(0.0, 0.0); N],
            dirs: [Point::new(0.0, 0.0); N],
            spreads: [0.0; N],
            half_step: Point::new(0.0, 0.0),
            gap_factor: 0.0,
            dirs_of: (0, 0),
            ranges: [0.0; N],
            flags: [0; N],
            neighbours: None,
            len: 0,
            motion: None,
            features: Vec::new(),
            stats: Stats {
                readings: 0,
                valid: 0,
                segments: 0,
                short_segments: 0,
                degenerate: 0,
                features: 0,
                dropped: 0,
                predictions: 0,
            },
        }
    }

    /// Extracts the features of `scan`. On `Err(FeatureCapacity)` the first `M` features are
    /// still available from [`features`](Self::features).
    pub fn extract(&mut self, scan: &Scan<'_>, config: &Config) -> Result<Stats, ExtractError> {
        // An `LmsExtractor` runs the copy compiled in this crate (the test folds away).
        match (self as &mut dyn core::any::Any).downcast_mut::<LmsExtractor>() {
            Some(lms) => extract_lms(lms, scan, config),
            None => self.extract_here(scan, config),
        }
    }

    /// [`Self::extract`], compiled where `N` and `M` are named.
    fn extract_here(&mut self, scan: &Scan<'_>, config: &Config) -> Result<Stats, ExtractError> {
        self.len = 0;
        self.features.clear();
        self.stats = Stats::default();
        if !scan.geometry.is_valid() {
            return Err(ExtractError::InvalidGeometry);
        }
        if !config.is_valid() {
            return Err(ExtractError::InvalidConfig);
        }
        let n = scan.ranges.len();
        if n > N || n > usize::from(u16::MAX) {
            return Err(ExtractError::TooManyReadings {
                got: n,
                capacity: N.min(usize::from(u16::MAX)),
            });
        }
        self.len = n;
        self.motion = scan.motion.filter(|m| m.is_valid());
        self.load_points(scan, config);
        self.mark(config, scan.geometry.r_max);
        if config.check_step {
            self.check_step(config, scan.geometry.r_max);
        }
        self.build_features(config);
        self.stats.features = self.features.len();
        if self.stats.dropped > 0 {
            Err(ExtractError::FeatureCapacity {
                dropped: self.stats.dropped,
            })
        } else {
            Ok(self.stats)
        }
    }

    /// Features of the last extraction, in scan order.
    pub fn features(&self) -> &[Feature] {
        &self.features
    }

    /// Statistics of the last extraction.
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// Points of the last scan (after correction and de-skew); invalid readings are
    /// [`Point::INVALID`].
    pub fn points(&self) -> &[Point] {
        self.points.get(..self.len).unwrap_or(&[])
    }

    /// Mark points of the last extraction: the first and last point of every segment (after
    /// the check step and pairing), in increasing order.
    pub fn marks(&self) -> impl Iterator<Item = usize> + '_ {
        self.flags
            .iter()
            .take(self.len)
            .enumerate()
            .filter(|(_, f)| **f & (START | END) != 0)
            .map(|(i, _)| i)
    }

    /// True when point `i` is a mark point.
    pub fn is_mark(&self, i: usize) -> bool {
        i < self.len && self.flag(i) & (START | END) != 0
    }

    /// The first index from `from` whose flags `seek` finds, four flags at a time where it can
    /// tell from their word that none of them is one.
    #[inline(always)]
    fn next_flag(&self, from: usize, seek: Seek) -> Option<usize> {
        let flags = self.flags.get(from..self.len)?;
        let mut chunks = flags.chunks_exact(4);
        let mut base = from;
        for chunk in chunks.by_ref() {
            if let [a, b, c, d] = *chunk {
                if !seek.none_in(u32::from_le_bytes([a, b, c, d])) {
                    if let Some(i) = chunk.iter().position(|&f| seek.hit(f)) {
                        return Some(base + i);
                    }
                }
            }
            base += 4;
        }
        let rest = chunks.remainder();
        Some(base + rest.iter().position(|&f| seek.hit(f))?)
    }

    fn flag(&self, i: usize) -> u8 {
        self.flags.get(i).copied().unwrap_or(0)
    }

    fn set(&mut self, i: usize, bit: u8) {
        if let Some(f) = self.flags.get_mut(i) {
            *f |= bit;
        }
    }

    fn clear(&mut self, i: usize, bit: u8) {
        if let Some(f) = self.flags.get_mut(i) {
            *f &= !bit;
        }
    }

    fn valid(&self, i: usize) -> bool {
        self.flag(i) & VALID != 0
    }

    fn point(&self, i: usize) -> Point {
        point_at(&self.points, i)
    }

    /// Scanner position when beam `i` was taken (origin unless de-skewing).
    fn origin(&self, i: usize) -> Point {
        match self.motion {
            Some(m) => m.pose(i).origin,
            None => Point::new(0.0, 0.0),
        }
    }

    fn range(&self, i: usize) -> f32 {
        self.ranges.get(i).copied().unwrap_or(f32::NAN)
    }

    /// Converts the readings to points.
    fn load_points(&mut self, scan: &Scan<'_>, config: &Config) {
        let g = scan.geometry;
        self.directions(g);
        let n = self.len;
        // Every slice cut to `n` up front: one loop counter.
        let slots = (
            self.points.get_mut(..n),
            self.ranges.get_mut(..n),
            self.flags.get_mut(..n),
            self.dirs.get(..n),
        );
        let (Some(points), Some(ranges), Some(flags), Some(dirs)) = slots else {
            // Not reached (`extract` checked `n`): an empty scan rather than stale points.
            self.len = 0;
            return;
        };
        // One loop per kind of reading, without a correction or de-skewing.
        let invalid = match scan.ranges {
            Ranges::Raw {
                values,
                mm_per_unit,
                max_valid,
            } => {
                let max_code = max_code(mm_per_unit, max_valid, g.r_max);
                place_codes((points, ranges, flags, dirs), values, mm_per_unit, max_code)
            }
            Ranges::Mm(mm) => place_mm((points, ranges, flags, dirs), mm, g.r_max),
        };
        self.stats.readings = self.len;
        self.stats.valid = self.len - invalid;
        if config.correction.is_some() || self.motion.is_some() {
            self.adjust_points(g, config);
        }
    }

    /// Beam directions (cos, sin) of `g` for the first `N` beams, unless already there: an
    /// exact sine and cosine every 64 beams and a rotation recurrence in between (error
    /// < 1e-5 rad: 0.1 mm at 8 m); and the spreads of runs of them.
    fn directions(&mut self, g: ScanGeometry) {
        const EXACT_EVERY: usize = 64;
        let key = (g.start_angle.to_bits(), g.angle_step.to_bits());
        if self.dirs_of == key {
            return;
        }
        let (rs, rc) = math::sin_cos(g.angle_step);
        let (mut s, mut c) = (0.0f32, 1.0f32);
        for (i, d) in self.dirs.iter_mut().enumerate() {
            if i % EXACT_EVERY == 0 {
                (s, c) = math::sin_cos(g.bearing(i));
            } else {
                (s, c) = (s * rc + c * rs, c * rc - s * rs);
            }
            *d = Point::new(c, s);
        }
        fill_spreads(&mut self.spreads, g.angle_step);
        let (s, c) = math::sin_cos(0.5 * g.angle_step);
        self.half_step = Point::new(c, s);
        // Largest gap between consecutive points of one surface: seen at down to 10°
        // incidence (Borges & Aldon's λ); the default mode adds the noise of two readings.
        let (step, lam) = (math::abs(g.angle_step), 10.0f32.to_radians());
        let below = math::sin(lam - step);
        self.gap_factor = math::sin(step) / if below > 1e-3 { below } else { 1e-3 };
        self.dirs_of = key;
    }

    /// Applies the range correction and de-skewing to the valid points; a point they make
    /// invalid is dropped.
    fn adjust_points(&mut self, g: ScanGeometry, config: &Config) {
        let (correction, motion) = (config.correction, self.motion);
        let slots = self
            .points
            .iter_mut()
            .zip(self.ranges.iter_mut())
            .zip(self.flags.iter_mut())
            .zip(self.dirs.iter());
        let mut dropped = 0usize;
        for (i, (((point, range), flag), d)) in slots.take(self.len).enumerate() {
            if *flag & VALID == 0 {
                continue;
            }
            let mut r = *range;
            if let Some(k) = correction {
                r = k.apply(r);
            }
            let p = match motion {
                Some(m) => m.deskew(i, r, g.bearing(i)).0,
                None => Point::new(r * d.x, r * d.y),
            };
            if math::finite(r) && r > 0.0 && p.is_valid() {
                (*point, *range) = (p, r);
            } else {
                dropped += 1;
                (*point, *range, *flag) = (Point::INVALID, 0.0, 0);
            }
        }
        self.stats.valid -= dropped;
    }

    /// Predicts point `k` from points `from..to` (all valid).
    fn predict(&mut self, from: usize, to: usize, k: usize) -> Option<Prediction> {
        let line = self.window_line(from, to, k)?;
        self.predict_with(&line, k)
    }

    /// The line of points `from..to`, seen from the origin of beam `k`.
    fn window_line(&mut self, from: usize, to: usize, k: usize) -> Option<WindowLine> {
        self.stats.predictions += 1;
        WindowLine::fit(self.points.get(from..to)?, self.origin(k))
    }

    /// Predicts point `k` from a window's line.
    fn predict_with(&self, line: &WindowLine, k: usize) -> Option<Prediction> {
        let (p, o, r) = (self.point(k), self.origin(k), self.range(k));
        if !(r > 0.0) {
            return None;
        }
        Some(line.predict(o, p.x - o.x, p.y - o.y, r))
    }

    /// Whether a prediction says "mark" under the configured threshold.
    fn exceeds(&self, pred: Option<Prediction>, k: usize, config: &Config, r_max: f32) -> bool {
        let Some(p) = pred else { return true };
        match config.threshold {
            Threshold::Paper { d0, lambda } => {
                p.error > paper_threshold(d0, lambda, self.range(k), r_max, p.phi())
            }
            Threshold::Noise(m) => p.exceeds(m.k, config.sigma_r, m.floor),
        }
    }

    /// Mark points under the configured threshold (the paper's, or the default mode's walk).
    #[inline(always)]
    fn mark(&mut self, config: &Config, r_max: f32) {
        self.neighbours = None;
        match config.threshold {
            Threshold::Paper { d0, lambda } => self.mark_paper(d0, lambda, r_max),
            Threshold::Noise(model) => self.mark_noise(&model, config.sigma_r),
        }
    }

    /// Paper §3.2: every point with `Np` valid predecessors is predicted from them; the first
    /// point after a gap (or at the start) opens a segment.
    fn mark_paper(&mut self, d0: f32, lambda: f32, r_max: f32) {
        let mut run = 0usize;
        for k in 0..self.len {
            if !self.valid(k) {
                run = 0;
                continue;
            }
            if run == 0 {
                self.set(k, START);
            } else if run >= NP {
                let pred = self.predict(k - NP, k, k);
                let mark = match pred {
                    None => true,
                    Some(p) => p.error > paper_threshold(d0, lambda, self.range(k), r_max, p.phi()),
                };
                if mark {
                    self.set(k, START);
                }
            }
            run += 1;
        }
    }

    /// Default mode: predict only from points of the current segment (so no window straddles
    /// a boundary), threshold `k σ_D + floor`, arc continuation, then move the boundary back
    /// over the points that already left the old segment's line (boundary localisation).
    fn mark_noise(&mut self, m: &NoiseModel, sigma_r: f32) {
        let limits = Limits {
            gap_factor: self.gap_factor,
            jump_add: m.k * sigma_r * core::f32::consts::SQRT_2 + m.floor,
            k_sigma2: (m.k * sigma_r) * (m.k * sigma_r),
            floor: m.floor,
        };
        // The fast path: no de-skewing (the scanner at the origin) and a floor small enough
        // for its test (`WindowLine::accepts_within`); otherwise every point takes the slow
        // path, with the same outcome.
        let fast = self.motion.is_none()
            && limits.floor * limits.floor <= WindowLine::FLOOR2_WITHIN * limits.k_sigma2;
        self.neighbours = Some(Vec::new());
        let mut walk = Walk::default();
        let mut k = 0usize;
        while k < self.len {
            let mut stale_failed = false;
            // Fast path: the points the cached line accepts, up to the next point where a
            // boundary awaits refinement or a merge test is due.
            let cached = walk.cache.as_ref().filter(|_| walk.seg.is_some());
            if let (Some((line, until)), true) = (cached, fast) {
                let stop = walk.next_check(k, until + 1).min(self.len);
                let next = accepted_run(&self.points, &self.ranges, k, stop, line, &limits);
                self.stats.predictions += next - k;
                stale_failed = next < stop;
                k = next;
                if k >= self.len {
                    break;
                }
            }
            self.noise_step(k, &mut walk, stale_failed, m, sigma_r, &limits);
            k += 1;
        }
    }

    /// The default mode at point `k`, with everything the fast path does not do: segment
    /// starts, jumps, fresh windows, arc continuation, boundary placement, refinement and
    /// merges. `stale_failed`: the fast path just saw the cached line reject `k`.
    fn noise_step(
        &mut self,
        k: usize,
        walk: &mut Walk,
        stale_failed: bool,
        m: &NoiseModel,
        sigma_r: f32,
        limits: &Limits,
    ) {
        if !self.valid(k) {
            *walk = Walk::default();
            return;
        }
        let Some(s) = walk.seg else {
            self.start(k);
            walk.seg = Some(k);
            walk.cache = None;
            return;
        };
        let c = k - s;
        let (p, prev) = (self.point(k), self.point(k - 1));
        let limit = self.range(k - 1) * limits.gap_factor + limits.jump_add;
        let (ex, ey) = (p.x - prev.x, p.y - prev.y);
        let jump = ex * ex + ey * ey > limit * limit;
        let boundary = if jump {
            // A jump no surface explains (also where the window's line runs along the
            // beam and the prediction says nothing).
            Some(k)
        } else if c == 1 {
            None
        } else {
            // A recent window's line first (unless the fast path just saw it fail here).
            let stale_ok = !stale_failed
                && walk.cache.as_ref().is_some_and(|(line, until)| {
                    k <= *until && self.line_accepts(line, k, m, sigma_r)
                });
            if stale_ok {
                None
            } else {
                let w = self.window(k, c, m, sigma_r);
                let (first, last) = (self.point(k - w), self.point(k - 1));
                // It may test the next 8w points while they fit it, no more loosely than a
                // fresh line (`WindowLine::accepts`); a point it rejects gets a fresh window.
                walk.cache = self
                    .window_line(k - w, k, k)
                    .map(|l| (l.capped(&first, &last, w), k + 8 * w));
                let line = walk.cache.as_ref().map(|(l, _)| l);
                let over = !line.is_some_and(|l| self.line_accepts(l, k, m, sigma_r));
                (over && !self.continues_arc(s, k, m, sigma_r)).then(|| {
                    let pred = line.and_then(|l| self.predict_with(l, k));
                    self.locate(s, k, pred, m, sigma_r)
                })
            }
        };
        if let Some(b) = boundary {
            self.start(b);
            if jump {
                self.set(b, JUMP);
            }
            walk.seg = Some(b);
            walk.cache = None;
            walk.pending = (!jump).then_some((b, s));
            walk.joinable = (!jump).then_some((b, s));
        } else if let Some((b, old)) = walk.joinable.filter(|(b, _)| k + 1 - b == MERGE_AT) {
            // An arc's edge seen at grazing incidence curves away from a short line window:
            // when the two segments together are one arc, they are one segment.
            let from = old.max(b.saturating_sub(m.arc_window));
            if m.arc_window >= 5 && self.arc_fit(from, k + 1, m, sigma_r).is_some() {
                self.clear(b, START);
                *walk = Walk {
                    seg: Some(old),
                    ..Walk::default()
                };
            }
        }
        if let (None, Some((b, old))) = (boundary, walk.pending) {
            if k == b + REFINE_AFTER {
                let best = refine_boundary(&self.points, old, b, k + 1);
                if best != b {
                    self.clear(b, START);
                    self.set(best, START);
                    walk.seg = Some(best);
                    // A line of the points from b on is still one of the segment's when it
                    // starts earlier.
                    if best > b {
                        walk.cache = None;
                    }
                    walk.joinable = Some((best, old));
                }
                walk.pending = None;
            }
        }
    }

    /// Starts a segment at `i` in the default mode's walk (which sets starts in increasing
    /// order), noting it when point `i − 1` starts one too.
    fn start(&mut self, i: usize) {
        self.set(i, START);
        if i.checked_sub(1).is_some_and(|j| self.flag(j) & START != 0) {
            let noted = match (&mut self.neighbours, u16::try_from(i)) {
                (Some(list), Ok(i)) => list.push(i).is_ok(),
                _ => false,
            };
            if !noted {
                self.neighbours = None;
            }
        }
    }

    /// Whether `line` accepts point `k` under the noise model (the inverse of
    /// `Prediction::exceeds`, without building the prediction when not de-skewing).
    fn line_accepts(&self, line: &WindowLine, k: usize, m: &NoiseModel, sigma_r: f32) -> bool {
        match self.motion {
            None => {
                let (p, ks) = (self.point(k), m.k * sigma_r);
                line.accepts(p.x, p.y, self.range(k), ks * ks, m.floor)
            }
            Some(_) => self
                .predict_with(line, k)
                .is_some_and(|p| !p.exceeds(m.k, sigma_r, m.floor)),
        }
    }

    /// Prediction window for point `k` with `c` points of its segment before it: `window`
    /// points, grown (up to `max_window`) until it spans `min_span · σ_r`, so that close to
    /// the scanner, where beams are a few mm apart, the window still sees a line's direction
    /// above the noise.
    fn window(&self, k: usize, c: usize, m: &NoiseModel, sigma_r: f32) -> usize {
        let mut w = c.min(m.window);
        let limit = c.min(m.max_window.max(m.window));
        let span = m.min_span * sigma_r;
        let last = self.point(k - 1);
        while w < limit {
            let p = self.point(k - w);
            let (dx, dy) = (p.x - last.x, p.y - last.y);
            if dx * dx + dy * dy >= span * span {
                break;
            }
            w += 1;
        }
        w
    }

    /// Arc continuation test for point `k` of the segment starting at `s` (see
    /// [`NoiseModel::arc_window`]): the circle through the segment's last points must explain
    /// them significantly better than a line and predict `k` along its beam.
    fn continues_arc(&mut self, s: usize, k: usize, m: &NoiseModel, sigma_r: f32) -> bool {
        let c = k - s;
        if m.arc_window < 5 || c < 5 {
            return false;
        }
        let Some(circle) = self.arc_fit(k - c.min(m.arc_window), k, m, sigma_r) else {
            return false;
        };
        self.stats.predictions += 1;
        let (target, origin) = (self.point(k), self.origin(k));
        let (bx, by) = (target.x - origin.x, target.y - origin.y);
        let r = math::hypot(bx, by);
        if !(r > 0.0) {
            return false;
        }
        let (dx, dy) = (bx / r, by / r);
        match ray_circle_intersection(origin, dx, dy, circle.center, circle.radius) {
            Some(t) => {
                // The circle's position error (about σ_r across it) is stretched along the
                // beam by 1/cos γ, γ between the beam and the circle's normal there.
                let hit = Point::new(origin.x + dx * t, origin.y + dy * t);
                let (nx, ny) = (hit.x - circle.center.x, hit.y - circle.center.y);
                let cos_g = math::abs(nx * dx + ny * dy) / circle.radius;
                let f = math::sqrt(1.0 + 1.0 / cos_g.max(0.1) / cos_g.max(0.1));
                math::abs(r - t) <= m.k * sigma_r * f + m.floor
            }
            // The beam passes just outside the fitted circle (a point at the very edge).
            None => {
                math::abs(target.distance(&circle.center) - circle.radius)
                    <= m.k * sigma_r + m.floor
            }
        }
    }

    /// [`arc_fit`] of points `from..to`.
    fn arc_fit(&self, from: usize, to: usize, m: &NoiseModel, sigma_r: f32) -> Option<Circle> {
        arc_fit(self.points.get(from..to)?, m, sigma_r)
    }

    /// The earliest of the (up to 4) points before `k` that, with `k`, deviate on the same
    /// side from the line through the segment's points before them.
    fn locate(
        &mut self,
        s: usize,
        k: usize,
        at_k: Option<Prediction>,
        m: &NoiseModel,
        sigma_r: f32,
    ) -> usize {
        const BACK: usize = 4;
        let c = k - s;
        let back = BACK.min(c.saturating_sub(NP));
        if back == 0 {
            return k;
        }
        let ref_end = k - back;
        let ref_start = ref_end.saturating_sub(m.window).max(s);
        let Some(side) = at_k.map(|p| p.signed) else {
            return k;
        };
        // Predictions from the reference line. Without de-skewing every beam sees it from
        // the same origin: k's fit serves them all (each still counts as a prediction).
        let fixed = self
            .motion
            .is_none()
            .then(|| self.window_line(ref_start, ref_end, k));
        let k_from_ref = match fixed {
            Some(line) => line.and_then(|l| self.predict_with(&l, k)),
            None => self.predict(ref_start, ref_end, k),
        };
        let predict = |ex: &mut Self, j: usize| match fixed {
            Some(line) => {
                ex.stats.predictions += 1;
                line.and_then(|l| ex.predict_with(&l, j))
            }
            None => ex.predict(ref_start, ref_end, j),
        };
        // Sign of k's deviation from the reference line (not from its own window).
        let side = match k_from_ref {
            Some(p) if math::finite(p.signed) => p.signed,
            _ => side,
        };
        let mut b = k;
        for j in (ref_end..k).rev() {
            match predict(self, j) {
                Some(p) if p.signed * side > 0.0 && p.exceeds(m.k_locate, sigma_r, m.floor) => {
                    b = j
                }
                _ => break,
            }
        }
        // Each point moved to the new segment must lie on the line through the ones after it
        // (a reference line through an arc's end also "sees" the arc's own last points
        // deviate).
        while b + 2 <= k {
            let tol = m.k * sigma_r + m.floor;
            let consistent = match (self.points.get(b + 1..=k), self.points.get(b)) {
                (Some(rest), Some(p)) => {
                    fit_axis(rest).is_ok_and(|l| math::abs(l.signed_distance(p)) <= tol)
                }
                _ => true,
            };
            if consistent {
                break;
            }
            b += 1;
        }
        b
    }

    /// Paper §3.3: wherever `Np` mark points follow each other, predict the next point from
    /// them; when it fits, the marks after the first were caused by a window straddling the
    /// boundary and are removed. Runs of 2..Np marks (a straddling window can fit by chance,
    /// e.g. when the boundary point lies on both surfaces, as at a corner) get the same test
    /// with the run's own points as the window; a run longer than `Np` is tested at its last
    /// `Np` points, so its first marks stay. Runs at the end of a valid stretch are left alone.
    fn check_step(&mut self, config: &Config, r_max: f32) {
        match self.neighbours.take() {
            // The default mode's walk noted every start next to another (in increasing
            // order): the runs of marks are where they are.
            Some(list) => {
                let mut done = 0usize;
                for i in list.iter().map(|&i| usize::from(i)) {
                    if i < done || self.flag(i) & Seek::MARK != Seek::MARK {
                        continue;
                    }
                    let mut j = i;
                    while j > done && self.flag(j - 1) & Seek::MARK == Seek::MARK {
                        j -= 1;
                    }
                    done = self.check_run(j, config, r_max);
                }
            }
            None => {
                let mut j = 0usize;
                while let Some(start) = self.next_flag(j, Seek::Mark) {
                    j = self.check_run(start, config, r_max);
                }
            }
        }
    }

    /// The check step for the run of marks starting at `j`; returns the point after it.
    #[inline(always)]
    fn check_run(&mut self, j: usize, config: &Config, r_max: f32) -> usize {
        let next = self.next_flag(j + 1, Seek::NotMark).unwrap_or(self.len);
        let e = next - 1;
        if e > j && next < self.len && self.valid(next) {
            let from = (e + 1).saturating_sub(NP).max(j);
            let pred = self.predict(from, next, next);
            if !self.exceeds(pred, next, config, r_max) {
                for i in from + 1..next {
                    self.clear(i, START);
                }
            }
        }
        next
    }

    /// §3.4–3.5: every segment's last point is paired with the next segment's first; segments
    /// of at least `min_points` points are typed and fitted. In the default mode, neighbouring
    /// segments (no gap, no jump between them) that together are one arc are merged first: a
    /// small or distant pillar, seen over a few beams at growing incidence, can fail the line
    /// prediction every few points before an arc window has formed.
    fn build_features(&mut self, config: &Config) {
        let merge = match config.threshold {
            Threshold::Noise(m) if m.arc_window >= 5 => Some(m),
            _ => None,
        };
        let mut pending: Option<(usize, usize)> = None;
        let mut k = 0usize;
        while let Some(s) = self.next_flag(k, Seek::Valid) {
            k = s;
            // The segment runs to the next start or invalid point.
            k = self.next_flag(k + 1, Seek::SegmentEnd).unwrap_or(self.len);
            let e = k - 1;
            if let (Some((ps, pe)), Some(m)) = (pending, merge) {
                if pe + 1 == s
                    && self.flag(s) & JUMP == 0
                    && MERGE_SIZES.contains(&(e + 1 - ps))
                    && self.arc_fit(ps, e + 1, &m, config.sigma_r).is_some()
                {
                    self.clear(s, START);
                    pending = Some((ps, e));
                    continue;
                }
            }
            if let Some((ps, pe)) = pending {
                self.emit_segment(ps, pe, config);
            }
            pending = Some((s, e));
        }
        if let Some((ps, pe)) = pending {
            self.emit_segment(ps, pe, config);
        }
    }

    /// Marks, types and fits (when long enough) the segment `s..=e`.
    fn emit_segment(&mut self, s: usize, e: usize, config: &Config) {
        self.set(s, START);
        self.set(e, END);
        self.stats.segments += 1;
        if e + 1 - s >= config.min_points {
            match self.fit_segment(s, e, config) {
                Some(f) => {
                    if self.features.push(f).is_err() {
                        self.stats.dropped += 1;
                    }
                }
                None => self.stats.degenerate += 1,
            }
        } else {
            self.stats.short_segments += 1;
        }
    }

    /// The beams `s..=e` (a segment's: all valid, consecutive).
    fn beam_span(&self, s: usize, e: usize) -> Option<BeamSpan> {
        let count = (e + 1).checked_sub(s).filter(|&c| c > 0)?;
        let d = *self.dirs.get(s + (count - 1) / 2)?;
        // An even count's middle lies half a step past the lower middle beam.
        let h = self.half_step;
        let mid = if count % 2 == 1 {
            d
        } else {
            Point::new(d.x * h.x - d.y * h.y, d.y * h.x + d.x * h.y)
        };
        Some(BeamSpan {
            count,
            mid,
            ends: [*self.dirs.get(s)?, *self.dirs.get(e)?],
            spread: *self.spreads.get(count.checked_sub(1)?)?,
        })
    }

    fn fit_segment(&self, s: usize, e: usize, config: &Config) -> Option<Feature> {
        let pts = self.points.get(s..=e)?;
        let origin = self.origin((s + e) / 2);
        let line = fit_line(pts).ok();
        let circle = || {
            let c = fit_circle(pts, config.circle_method).ok()?;
            if config.circle_refine > 0 {
                refine_circle(pts, c, config.circle_refine).ok()
            } else {
                Some(c)
            }
        };
        let as_circle = match (config.typing, line) {
            (_, None) => circle(),
            (Typing::MeanDistance { d_f }, Some(l)) => {
                if l.mean_abs_distance(pts) <= d_f {
                    None
                } else {
                    circle()
                }
            }
            (
                Typing::CompareFits {
                    chi2,
                    ratio,
                    max_radius,
                },
                Some(l),
            ) => {
                let sse_l = l.sse();
                let var = config.sigma_r * config.sigma_r;
                // A circle must beat the line by chi2·σ_r²: not possible when the line's own
                // residual is smaller. Then the cheap algebraic fit screens the candidates
                // before the geometric refinement.
                let algebraic = (sse_l > chi2 * var && sse_l > 1.5 * var * pts.len() as f32)
                    .then(|| fit_circle(pts, config.circle_method).ok())
                    .flatten()
                    .map(|c| (c, NormalEquations::at(pts, &c)))
                    .filter(|(c, eq)| c.radius <= 1.5 * max_radius && eq.sse < 2.0 * ratio * sse_l);
                algebraic
                    .and_then(|(c, eq)| {
                        if config.circle_refine > 0 {
                            refine_from(pts, c, eq, config.circle_refine).ok()
                        } else {
                            Some((c, eq.sse))
                        }
                    })
                    .filter(|(c, sse_c)| {
                        // The circle must also explain the points (RMS residual ≤ 2σ_r): an
                        // undetected corner fits neither model and stays a line.
                        c.radius <= max_radius
                            && sse_l - sse_c > chi2 * var
                            && *sse_c < ratio * sse_l
                            && *sse_c <= 4.0 * var * pts.len() as f32
                    })
                    .map(|(c, _)| c)
            }
        };
        match as_circle {
            Some(c) => circle_feature(pts, s, e, &c, origin, config.sigma_r),
            None => {
                let line = line?;
                let ends = [pts.first()?, pts.last()?];
                let cov = self
                    .beam_span(s, e)
                    .filter(|_| self.motion.is_none())
                    .and_then(|beams| line.covariance_beams(&beams, ends, config.sigma_r));
                match cov {
                    Some(cov) => line_feature_with(pts, s, e, &line, cov),
                    None => line_feature(pts, s, e, &line, origin, config.sigma_r),
                }
            }
        }
    }
}

/// Readings an [`LmsExtractor`] has room for: every LMS2xx scan (100° at 0.25°: 401 values).
pub const LMS_READINGS: usize = 401;
/// Features an [`LmsExtractor`] has room for.
pub const LMS_FEATURES: usize = 48;

/// The extractor the firmware runs. Generic code is compiled in the crate that names its
/// parameters (the firmware builds at opt-level "s"); this one's extraction is compiled once
/// here, at this crate's level (`cargo xtask bench-mcu`: 3.6 instructions a point less for the
/// pipeline, 0.6 KB more flash). Any other capacity works the same, compiled where it is named.
///
/// ```
/// use pfe_core::{Config, Feature, LmsExtractor, Scan, ScanGeometry};
/// // A wall 3 m ahead, across the middle 100 beams of a 180°/0.5° scan.
/// let g = ScanGeometry::LMS200_180_050;
/// let ranges: Vec<f32> = (0..361)
///     .map(|i| if (130..230).contains(&i) { 3000.0 / g.bearing(i).cos() } else { f32::NAN })
///     .collect();
/// let mut ex = LmsExtractor::new(); // ~13 KB: a `static` on a microcontroller
/// ex.extract(&Scan::from_mm(g, &ranges), &Config::default())?;
/// assert!(matches!(ex.features(), [Feature::Line(l)] if (l.rho - 3000.0).abs() < 0.5));
/// # Ok::<(), pfe_core::ExtractError>(())
/// ```
pub type LmsExtractor = Extractor<LMS_READINGS, LMS_FEATURES>;

/// [`Extractor::extract`] of an [`LmsExtractor`]: not generic, so compiled here.
#[inline(never)]
fn extract_lms(
    ex: &mut LmsExtractor,
    scan: &Scan<'_>,
    config: &Config,
) -> Result<Stats, ExtractError> {
    ex.extract_here(scan, config)
}

// The loops over many points, as functions of slices that are not generic, so they are
// compiled once, here, at this crate's optimisation level (3), whatever `N` and `M` (the
// extractor's own methods are compiled where its capacities are named, at "s" in a firmware
// that names any other than `LmsExtractor`'s). `cargo xtask bench-mcu`: 5 instructions a point
// less for the pipeline, measured before `LmsExtractor`.

/// Point `i` of `points` ([`Point::INVALID`] past their end).
fn point_at(points: &[Point], i: usize) -> Point {
    points.get(i).copied().unwrap_or(Point::INVALID)
}

/// The slots of a scan's beams (points, ranges, flags) and their directions, all of one length.
type Slots<'a> = (&'a mut [Point], &'a mut [f32], &'a mut [u8], &'a [Point]);

/// [`place`] for LMS range codes: `1 ..= max_code` are returns, in (0, r_max] mm. Not inlined
/// (nor is [`place_mm`]): the loop then keeps one pointer a slice in registers.
#[inline(never)]
fn place_codes(slots: Slots<'_>, codes: &[u16], mm_per_unit: f32, max_code: u16) -> usize {
    place(slots, codes, |v| {
        (u32::from(v).wrapping_sub(1) < u32::from(max_code)).then(|| f32::from(v) * mm_per_unit)
    })
}

/// [`place`] for ranges in mm.
#[inline(never)]
fn place_mm(slots: Slots<'_>, mm: &[f32], r_max: f32) -> usize {
    place(slots, mm, |r| valid_mm(r, r_max))
}

/// Points, ranges and flags from `readings` and `range(reading)`, the range in mm of a return
/// (`None`: no return). Returns the number of invalid readings (counting them keeps the common
/// path short).
#[inline(always)]
fn place<T: Copy>(slots: Slots<'_>, readings: &[T], range: impl Fn(T) -> Option<f32>) -> usize {
    let (points, ranges, flags, dirs) = slots;
    let mut invalid = 0usize;
    let slots = points
        .iter_mut()
        .zip(ranges.iter_mut())
        .zip(flags.iter_mut())
        .zip(dirs.iter().zip(readings));
    for (((point, slot), flag), (d, &v)) in slots {
        (*point, *slot, *flag) = match range(v) {
            Some(r) => (Point::new(r * d.x, r * d.y), r, VALID),
            None => {
                invalid += 1;
                (Point::INVALID, 0.0, 0)
            }
        };
    }
    invalid
}

/// Circle through `pts` when it explains them significantly better than a line (by
/// `arc_chi2 σ_r²`), with every radial residual within `k σ_r + floor` and a radius of at most
/// `arc_max_radius`.
fn arc_fit(pts: &[Point], m: &NoiseModel, sigma_r: f32) -> Option<Circle> {
    let var = sigma_r * sigma_r;
    // One pass for both fits. The circle's residual sum is ≥ 0, so a line this good
    // cannot be beaten by enough.
    let sums = ArcSums::of(pts)?;
    let line_sse = sums.line_sse();
    if !(line_sse >= m.arc_chi2 * var) {
        return None;
    }
    let circle = sums.kasa()?;
    if !(circle.radius <= m.arc_max_radius) {
        return None;
    }
    let tol = m.k * sigma_r + m.floor;
    // One pass: every radial residual within `tol`, and their sum of squares.
    let mut sse = 0.0f32;
    for p in pts {
        let r = p.distance(&circle.center) - circle.radius;
        if !(math::abs(r) <= tol) {
            return None;
        }
        sse += r * r;
    }
    // An arc explains its points to the noise (RMS ≤ 1.5 σ_r); the rounded-off view of a
    // corner does not.
    (sse <= 2.25 * var * pts.len() as f32 && line_sse - sse >= m.arc_chi2 * var).then_some(circle)
}

/// Best split between a segment starting at `old` and one starting near `b` and running to
/// `end` (exclusive): the candidate in `b − 3 ..= b + 1` that puts the points between them on
/// the nearer of two fixed lines, the left one fitted to up to `REFINE_SPAN` points before the
/// candidates (the old segment's), the right one to up to `REFINE_SPAN` from the last candidate
/// on (the new segment's): least sum of squared distances, one fit each side, not two fits
/// per candidate.
#[inline(never)]
fn refine_boundary(points: &[Point], old: usize, b: usize, end: usize) -> usize {
    let lo = b.saturating_sub(3).max(old + NP);
    let hi = (b + 1).min(end.saturating_sub(NP));
    if lo >= hi {
        return b;
    }
    let left = points.get(lo.saturating_sub(REFINE_SPAN).max(old)..lo);
    let right = points.get(hi..end.min(hi + REFINE_SPAN));
    let (Some(Ok(left)), Some(Ok(right))) = (left.map(fit_axis), right.map(fit_axis)) else {
        return b;
    };
    let Some(contested) = points.get(lo..hi) else {
        return b;
    };
    // Split j: points lo..j on the left line, j..hi on the right one.
    let mut sse: f32 = contested.iter().map(|p| sq(right.signed_distance(p))).sum();
    let (mut best, mut best_sse) = (lo, sse);
    for (j, p) in (lo + 1..).zip(contested) {
        sse += sq(left.signed_distance(p)) - sq(right.signed_distance(p));
        // Ties keep the detected boundary.
        if sse < best_sse || (sse == best_sse && j == b) {
            best = j;
            best_sse = sse;
        }
    }
    best
}

/// `x²`.
fn sq(x: f32) -> f32 {
    x * x
}

/// The first point from `from` (up to `to`, exclusive) that is not valid, jumps from its
/// predecessor, or is not accepted by `line`: the default mode's test for most points, as a
/// tight loop (no de-skewing: the scanner is at the origin).
fn accepted_run(
    points: &[Point],
    ranges: &[f32],
    from: usize,
    to: usize,
    line: &WindowLine,
    limits: &Limits,
) -> usize {
    let (Some(pts), Some(rs)) = (points.get(from..to), ranges.get(from..to)) else {
        return from;
    };
    let Some(before) = from.checked_sub(1) else {
        return from;
    };
    let (Some(mut prev), Some(mut prev_r)) =
        (points.get(before).copied(), ranges.get(before).copied())
    else {
        return from;
    };
    // Point `p` at range `r` after `prev` at `prev_r`: no jump, and on the line. An
    // invalid point is NaN (`Point::INVALID`): it fails the jump test.
    let fits = |prev: &Point, prev_r: f32, p: &Point, r: f32| {
        let limit = prev_r * limits.gap_factor + limits.jump_add;
        let (ex, ey) = (p.x - prev.x, p.y - prev.y);
        ex * ex + ey * ey <= limit * limit
            && line.accepts_within(p.x, p.y, r, limits.k_sigma2, limits.floor)
    };
    // Two points an iteration: the second one's predecessor is still in registers, and
    // the loop's counting is shared.
    let mut pairs = pts.chunks_exact(2).zip(rs.chunks_exact(2));
    let mut at = from;
    for (p2, r2) in pairs.by_ref() {
        if let ([a, b], &[ra, rb]) = (p2, r2) {
            if !fits(&prev, prev_r, a, ra) {
                return at;
            }
            if !fits(a, ra, b, rb) {
                return at + 1;
            }
            (prev, prev_r) = (*b, rb);
        }
        at += 2;
    }
    match (pts.get(at - from), rs.get(at - from)) {
        (Some(p), Some(&r)) if !fits(&prev, prev_r, p, r) => at,
        _ => to,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The default mode's check step, run over the starts its walk noted, changes the same
    /// marks as the check step reading every flag: a corridor (side walls seen at grazing
    /// incidence, where every point jumps from the one before: runs of starts the check step
    /// joins) with random spikes and dropouts, with few and with more runs than are noted.
    #[test]
    fn noted_neighbours_give_the_full_check_step() {
        let g = ScanGeometry::LMS200_180_050;
        let config = Config::default();
        let (mut seed, mut noted, mut overflowed, mut joined) = (7u32, 0, 0, 0);
        let (mut a, mut b) = (Extractor::<361, 32>::new(), Extractor::<361, 32>::new());
        for t in 0..200u32 {
            let ranges = corridor(t, &mut seed);
            let scan = Scan::from_mm(g, &ranges);
            let mut flags = [[0u8; 361]; 2];
            for (ex, all) in [(&mut a, false), (&mut b, true)] {
                ex.len = ranges.len();
                ex.motion = None;
                ex.load_points(&scan, &config);
                ex.mark(&config, g.r_max);
                let before = ex.flags;
                match (&ex.neighbours, all) {
                    (_, true) => ex.neighbours = None,
                    (Some(_), false) => noted += 1,
                    (None, false) => overflowed += 1,
                }
                ex.check_step(&config, g.r_max);
                joined += usize::from(!all && ex.flags != before);
                flags[usize::from(all)] = ex.flags;
            }
            assert_eq!(flags[0], flags[1], "scan {t}");
        }
        assert!(
            noted > 20 && overflowed > 20 && joined > 20,
            "{noted} noted, {overflowed} overflowed, {joined} joined"
        );
    }

    /// A corridor scan (LMS200, 180° at 0.5°): side walls 300 mm + 40 mm × (`t` mod 30) away,
    /// an end wall at 7 m, `t` mod 40 random spikes and 4 dropouts in 256.
    fn corridor(t: u32, seed: &mut u32) -> [f32; 361] {
        let g = ScanGeometry::LMS200_180_050;
        let (spikes, side) = (t % 40, 300.0 + 40.0 * (t % 30) as f32);
        core::array::from_fn(|i| {
            *seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let u = *seed >> 24;
            let (sin, cos) = math::sin_cos(g.bearing(i));
            if u < spikes {
                500.0 + 7.0 * u as f32
            } else if u < spikes + 4 {
                f32::NAN
            } else {
                let to_side = side / math::abs(sin);
                let to_end = if cos > 0.0 {
                    7000.0 / cos
                } else {
                    f32::INFINITY
                };
                let r = if to_side < to_end { to_side } else { to_end };
                if r < 7900.0 {
                    r
                } else {
                    f32::NAN
                }
            }
        })
    }

    /// An [`LmsExtractor`] (its extraction compiled in this crate) gives what any other
    /// capacity gives: marks, features and statistics, in both modes.
    #[test]
    fn lms_extractor_is_the_generic_one() {
        let g = ScanGeometry::LMS200_180_050;
        let (mut lms, mut other) = (LmsExtractor::new(), Extractor::<361, 48>::new());
        let mut seed = 11u32;
        for t in 0..60u32 {
            let ranges = corridor(t, &mut seed);
            let scan = Scan::from_mm(g, &ranges);
            for config in [Config::default(), Config::paper()] {
                let got = (lms.extract(&scan, &config), other.extract(&scan, &config));
                assert_eq!(got.0, got.1, "scan {t}");
                assert_eq!(lms.features(), other.features(), "scan {t}");
                assert!(lms.marks().eq(other.marks()), "scan {t}");
            }
        }
    }

    /// `Seek::none_in` never skips a word with a hit: every word of four flags made of the
    /// five flag bits.
    #[test]
    fn seek_skips_only_words_without_hits() {
        for seek in [Seek::Mark, Seek::NotMark, Seek::Valid, Seek::SegmentEnd] {
            for w in 0u32..1 << 20 {
                let bytes = [0u32, 5, 10, 15].map(|s| ((w >> s) & 0x1f) as u8);
                let word = u32::from_le_bytes(bytes);
                if seek.none_in(word) {
                    assert!(!bytes.iter().any(|&f| seek.hit(f)), "{word:#010x}");
                }
            }
        }
    }
}
