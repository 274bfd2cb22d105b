//! The scan's own range scatter: a robust estimate of σ_r from how far each point lies from
//! the chord of its neighbours, measured along its beam.
//!
//! Real surfaces (rough walls, glass, foliage) and interleaved sweeps out of place scatter
//! beyond the configured σ_r; with [`Config::scrutiny`](crate::Config::scrutiny) the extractor
//! then uses the scan's own σ for its marks, fits and covariances. The estimate comes from the
//! residuals |r_i − r̂_i|, where r̂_i is where beam i meets the chord of points i − s and i + s:
//! on any straight surface, at any incidence, that residual is noise only, with variance about
//! 1.5 σ_r² (the point's own and half of each neighbour's). Corners, edges and clutter make
//! large residuals: a first σ from the residuals' lower quartile sets a 3σ cut, and the median
//! of the residuals within it gives σ (twice). A scan whose residuals are mostly beyond the cut
//! (clutter) has no estimate. It is taken at s = 1 and s = 2, the larger: real roughness is
//! correlated over neighbouring beams (so it shows more at two beams), an offset between two
//! interleaved sweeps shows at one beam only (the walk's predictions see both).
//!
//! ```
//! use pfe_core::geometry::Point;
//! use pfe_core::preprocess::scatter;
//! // A wall 2 m ahead at 0.5° steps, its ranges off by `off(i)` mm.
//! let wall = |off: &dyn Fn(usize) -> f32| -> Vec<Point> {
//!     (0..181)
//!         .map(|i| {
//!             let b = (i as f32 - 90.0).to_radians() * 0.5;
//!             let r = 2000.0 / b.cos() + off(i);
//!             Point::new(r * b.cos(), r * b.sin())
//!         })
//!         .collect()
//! };
//! // Rough: ±30 mm, uniform (σ 17 mm), well above the configured 5 mm.
//! let mut seed = 7u32;
//! let off: Vec<f32> = (0..181)
//!     .map(|_| {
//!         seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
//!         (seed >> 8) as f32 / 16_777_216.0 * 60.0 - 30.0
//!     })
//!     .collect();
//! let sigma = scatter::sigma(&wall(&|i| off[i]), 5.0).unwrap();
//! assert!(sigma > 12.0 && sigma < 25.0, "{sigma}");
//! // Within the configured noise: the configured σ_r stands.
//! assert_eq!(scatter::sigma(&wall(&|i| off[i] / 10.0), 5.0), None);
//! ```

use crate::geometry::Point;
use crate::math;

/// Histogram bins per σ_r of |residual|.
const PER_SIGMA: f32 = 16.0;
/// Bins of the histogram: residuals up to 32 σ_r; larger ones count in the last (never an
/// inlier).
const BINS: usize = 512;
/// Fewest chord residuals for an estimate.
pub(crate) const MIN_SAMPLES: usize = 24;
/// The estimate replaces σ_r only above `1 + SIGNIFICANT / √n` times it, n the residuals it
/// came from. Over 1 000 walls of 181 points with normal noise at σ_r, the estimate was at
/// most 1.53 σ_r (n ≈ 177: the bound is 1.75), with 361 points at most 1.41 (bound 1.53);
/// a pillar of 25 beams gives the median of few residuals, curvature included (bound 3).
pub(crate) const SIGNIFICANT: f32 = 10.0;
/// The largest σ the scan may claim, as a multiple of σ_r (a scan of clutter is not a wall
/// with a large noise).
pub(crate) const MAX_FACTOR: f32 = 8.0;
/// Residual σ per σ_r: √1.5.
const RESIDUAL_PER_SIGMA: f32 = 1.224_745;
/// σ_r from the lower quartile of |residual|: a normal residual has |e| below 0.3186 σ a
/// quarter of the time.
const QUARTILE_TO_SIGMA: f32 = 1.0 / (0.318_64 * RESIDUAL_PER_SIGMA);
/// σ_r from the median |residual| (0.6745 σ).
const MEDIAN_TO_SIGMA: f32 = 1.0 / (0.674_49 * RESIDUAL_PER_SIGMA);
/// Inliers: residuals within this many residual σ.
const INLIER: f32 = 3.0;
/// Beams meeting the chord at this sine of the angle between them or less (grazing beyond
/// about 84°) give no residual: the intersection is ill-conditioned.
const MIN_SINE: f32 = 0.1;

/// The scan's σ_r, mm, when it is significantly above `sigma_r` (at most [`MAX_FACTOR`] times
/// it); `None` when the scan is consistent with `sigma_r` or has fewer than [`MIN_SAMPLES`]
/// residuals. `points` are one per beam, [`Point::INVALID`] (or any non-finite point) where a
/// beam has no return; only triples of valid points count. `sweeps`: the scan's interleaved
/// sweeps ([`crate::Scan::sweeps`]); the chords span 4 beams either side for 3 or more, else 2.
// The extractor asks [`Scatter`]; this is the integration tests' and doctests' entry.
#[cfg_attr(not(feature = "internals"), allow(dead_code))]
pub fn sigma(points: &[Point], sigma_r: f32) -> Option<f32> {
    Scatter::of(points, sigma_r).sigma()
}

/// The scatter of a scan at the scale of one beam and of two ([`at_span`] 1 and 2, from one
/// pass over the points): what [`sigma`] and [`sweeps_apart`] read, kept so that the
/// extractor asks the same points once.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Scatter {
    /// At one beam.
    one: Option<f32>,
    /// At two beams.
    two: Option<f32>,
}

impl Scatter {
    /// The scatter of `points` (see [`sigma`]) at spans 1 and 2: [`Self::of_blocks`] where
    /// the square root vectorises (`std`), [`Self::of_stream`] elsewhere (the same counts).
    pub(crate) fn of(points: &[Point], sigma_r: f32) -> Self {
        #[cfg(feature = "std")]
        {
            Self::of_blocks(points, sigma_r)
        }
        #[cfg(not(feature = "std"))]
        {
            Self::of_windows(points, sigma_r)
        }
    }

    /// [`Self::of`] in one pass over the windows of five points, each residual counted as it
    /// comes (the board's: no vector unit): the five points loaded afresh for each, where
    /// [`Self::of_stream`] shifts a window in registers (ten register moves a point on a
    /// Cortex-M4F) and tests the scan's end for each point it loads.
    #[cfg_attr(feature = "std", allow(dead_code))]
    fn of_windows(points: &[Point], sigma_r: f32) -> Self {
        let n = points.len();
        let scale = PER_SIGMA / sigma_r;
        // Up to `u16::MAX` points the count of no residual does not saturate.
        if !(scale > 0.0 && math::finite(scale)) || n > usize::from(u16::MAX) {
            return Self::of_stream(points, sigma_r);
        }
        // One bin more than [`count`] fills, where the windows that give no residual count.
        let (mut one, mut two) = ([0u16; BINS + 1], [0u16; BINS + 1]);
        // The middle of every window of five.
        for w in points.windows(5) {
            let &[a, b, m, c, d] = w else {
                continue;
            };
            // The point's range and both chords' lengths, in one call ([`math::sqrt3`]).
            let (one_x, one_y) = chord(b, c);
            let (two_x, two_y) = chord(a, d);
            let [r, one_len, two_len] = math::sqrt3(
                m.x * m.x + m.y * m.y,
                one_x * one_x + one_y * one_y,
                two_x * two_x + two_y * two_y,
            );
            let bin = residual_of_chord(b, m, c, r, one_len).and_then(|e| bin_finite(e, scale));
            add_or_none(&mut one, bin);
            let bin = residual_of_chord(a, m, d, r, two_len).and_then(|e| bin_finite(e, scale));
            add_or_none(&mut two, bin);
        }
        // Every window gave a bin or none (below `u16::MAX` points the count is exact).
        let windows = n.saturating_sub(4);
        let residuals =
            |h: &[u16; BINS + 1]| windows - usize::from(h.get(BINS).copied().unwrap_or(0));
        let (mut n1, n2) = (residuals(&one), residuals(&two));
        let (Some(one), Some(two)) = (one.first_chunk_mut::<BINS>(), two.first_chunk::<BINS>())
        else {
            // Not reached: both have BINS + 1 bins.
            return Self::of_stream(points, sigma_r);
        };
        // Then the one-beam residuals of the second and the last but one point (one point
        // when they are the same, none below three points).
        let mut edge = |i: usize| {
            if let (Some(&a), Some(&m), Some(&b)) =
                (points.get(i - 1), points.get(i), points.get(i + 1))
            {
                if let Some(e) = chord_residual(a, m, b) {
                    count(one, &mut n1, e, scale);
                }
            }
        };
        edge(1);
        if n >= 4 {
            edge(n - 2);
        }
        Self {
            one: estimate(one, n1, sigma_r),
            two: estimate(two, n2, sigma_r),
        }
    }

    /// [`Self::of`] in one pass, a sliding window of five points in registers (for fewer than
    /// five points on the host, and the reference the tests hold the others to).
    #[cfg_attr(not(any(test, feature = "std")), allow(dead_code))]
    fn of_stream(points: &[Point], sigma_r: f32) -> Self {
        let (mut one, mut two) = ([0u16; BINS], [0u16; BINS]);
        let (mut n1, mut n2) = (0usize, 0usize);
        let scale = PER_SIGMA / sigma_r;
        // No validity test: a triple with a point that is not finite (invalid, or beyond the
        // scan's ends) has no residual anyway ([`residual_at`]).
        let at = |i: usize| points.get(i).copied().unwrap_or(Point::INVALID);
        // Points i − 2 ..= i + 2.
        let mut w = [Point::INVALID, Point::INVALID, at(0), at(1), at(2)];
        for i in 0..points.len() {
            let [w0, w1, m, w3, w4] = w;
            // The point's range, shared by both chords (as `chord_residual` computes it).
            let r = math::sqrt(m.x * m.x + m.y * m.y);
            if let Some(e) = residual_at(w1, m, w3, r) {
                count(&mut one, &mut n1, e, scale);
            }
            if let Some(e) = residual_at(w0, m, w4, r) {
                count(&mut two, &mut n2, e, scale);
            }
            w = [w1, m, w3, w4, at(i + 3)];
        }
        Self {
            one: estimate(&one, n1, sigma_r),
            two: estimate(&two, n2, sigma_r),
        }
    }

    /// [`Self::of`] by blocks of [`BLOCK`] points: their residuals' bins first, branch-free
    /// ([`residual_bins`]: the loop vectorises, square roots and divisions included), then
    /// counted. The same residuals (the same arithmetic, point by point) in the same
    /// histograms: the counts do not depend on the order.
    #[cfg_attr(not(feature = "std"), allow(dead_code))]
    fn of_blocks(points: &[Point], sigma_r: f32) -> Self {
        let n = points.len();
        // Up to `u16::MAX` points no bin saturates, so the counts need no saturating add.
        if n < 5 || n > usize::from(u16::MAX) {
            return Self::of_stream(points, sigma_r);
        }
        // Twice the bins [`count`] fills, so that a bin masked to them needs no bounds test:
        // [`NONE`], where no residual goes, is the first past them.
        let (mut one, mut two) = ([0u16; 2 * BINS], [0u16; 2 * BINS]);
        let mut n1 = 0usize;
        let scale = PER_SIGMA / sigma_r;
        let (head, _) = one.split_at_mut(BINS);
        if let Ok(head) = <&mut [u16; BINS]>::try_from(head) {
            // The one-beam residuals of the second and the last but one point (their two-beam
            // chords reach beyond the scan); every other one is the middle of a window of five.
            for i in [1, n - 2] {
                if let (Some(&a), Some(&m), Some(&b)) =
                    (points.get(i - 1), points.get(i), points.get(i + 1))
                {
                    if let Some(e) = chord_residual(a, m, b) {
                        count(head, &mut n1, e, scale);
                    }
                }
            }
        }
        let mut bins = ([NONE; BLOCK], [NONE; BLOCK]);
        let mut from = 0;
        while from + 5 <= n {
            let block = points
                .get(from..(from + BLOCK + 4).min(n))
                .unwrap_or_default();
            residual_bins(block, scale, (&mut bins.0, &mut bins.1));
            let windows = block.len() - 4;
            let (b1, b2) = (
                bins.0.get(..windows).unwrap_or_default(),
                bins.1.get(..windows).unwrap_or_default(),
            );
            // As `count` counts (below `u16::MAX` points it never saturates), into `NONE`
            // where there is no residual.
            for (&a, &b) in b1.iter().zip(b2) {
                // The mask keeps every bin (and `NONE`) and proves the index in bounds.
                if let Some(h) = one.get_mut(usize::from(a) & (2 * BINS - 1)) {
                    *h = h.wrapping_add(1);
                }
                if let Some(h) = two.get_mut(usize::from(b) & (2 * BINS - 1)) {
                    *h = h.wrapping_add(1);
                }
            }
            from += BLOCK;
        }
        // Every window of five gave a bin or `NONE`.
        let windows = n - 4;
        let none =
            |hist: &[u16; 2 * BINS]| usize::from(hist.get(usize::from(NONE)).copied().unwrap_or(0));
        let (n1, n2) = (n1 + windows - none(&one), windows - none(&two));
        let at = |hist: &[u16; 2 * BINS], n| {
            let (head, _) = hist.split_at(BINS);
            <&[u16; BINS]>::try_from(head)
                .ok()
                .and_then(|head| estimate(head, n, sigma_r))
        };
        Self {
            one: at(&one, n1),
            two: at(&two, n2),
        }
    }

    /// [`sigma`]: the larger of the two scales (real roughness is correlated over
    /// neighbouring beams; interleaved sweeps' offsets show at one beam only).
    pub(crate) fn sigma(&self) -> Option<f32> {
        match (self.one, self.two) {
            (Some(a), Some(b)) => Some(if a > b { a } else { b }),
            (a, b) => a.or(b),
        }
    }

    /// [`sweeps_apart`] for the same `points` and `sigma_r` this scatter was taken of.
    pub(crate) fn sweeps_apart(&self, points: &[Point], sweeps: usize, sigma_r: f32) -> bool {
        // The largest scatter at spans 1 up to 2, below `sweeps`.
        let across = match sweeps {
            0 | 1 => None,
            2 => self.one,
            _ => match (self.one, self.two) {
                (Some(a), Some(b)) => Some(a.max(b)),
                (a, b) => a.or(b),
            },
        };
        let Some(across) = across else {
            return false;
        };
        let within = match sweeps {
            2 => self.two,
            s => at_span(points, s, sigma_r),
        };
        match within {
            Some(within) => across > APART * within,
            None => across > APART * sigma_r,
        }
    }
}

/// Whether the scan's `sweeps` interleaved sweeps show out of place: its scatter at one beam
/// (or two, for four sweeps) significantly beyond `sigma_r` and beyond [`APART`] times that at
/// `sweeps` beams (points of one sweep), which rough surfaces and noise do not give. (Four
/// sweeps drifting by equal steps leave every other one-beam residual near zero; at two beams
/// they all show.)
///
/// ```
/// use pfe_core::geometry::Point;
/// use pfe_core::preprocess::scatter;
/// // A wall 3 m ahead at 0.5° steps, the odd sweep 20 mm farther.
/// let points: Vec<Point> = (0..181)
///     .map(|i| {
///         let b = (i as f32 - 90.0).to_radians() * 0.5;
///         let r = 3000.0 / b.cos() + if i % 2 == 1 { 20.0 } else { 0.0 };
///         Point::new(r * b.cos(), r * b.sin())
///     })
///     .collect();
/// assert!(scatter::sweeps_apart(&points, 2, 5.0));
/// ```
pub fn sweeps_apart(points: &[Point], sweeps: usize, sigma_r: f32) -> bool {
    Scatter::of(points, sigma_r).sweeps_apart(points, sweeps, sigma_r)
}

/// The factor of [`sweeps_apart`].
pub(crate) const APART: f32 = 1.5;

/// [`sigma`] from the chords of points `span` beams before and after each point.
fn at_span(points: &[Point], span: usize, sigma_r: f32) -> Option<f32> {
    let mut hist = [0u16; BINS];
    let mut total = 0usize;
    let scale = PER_SIGMA / sigma_r;
    let windows = points.windows(2 * span + 1);
    let triples = windows.filter_map(|w| Some((*w.first()?, *w.get(span)?, *w.last()?)));
    if scale > 0.0 && math::finite(scale) {
        for (a, m, b) in triples {
            // The point's range and the chord's length in one call ([`math::sqrt2`]).
            let (cx, cy) = chord(a, b);
            let [r, len] = math::sqrt2(m.x * m.x + m.y * m.y, cx * cx + cy * cy);
            if let Some(e) = residual_of_chord(a, m, b, r, len) {
                count_finite(&mut hist, &mut total, e, scale);
            }
        }
    } else {
        for (a, m, b) in triples {
            // A triple with a point that is not finite has no residual ([`residual_at`]).
            if let Some(e) = chord_residual(a, m, b) {
                count(&mut hist, &mut total, e, scale);
            }
        }
    }
    estimate(&hist, total, sigma_r)
}

/// Counts residual `e` in `hist` (bins of `1 / scale` mm) and in `total`.
#[inline(always)]
fn count(hist: &mut [u16; BINS], total: &mut usize, e: f32, scale: f32) {
    // As `as usize` would bin it: |e| · scale is never negative, and beyond the last bin (or
    // beyond i32::MAX) it falls in the last; i32 converts fastest.
    let bin = ((math::abs(e) * scale) as i32).min(BINS as i32 - 1);
    if let Some(h) = hist.get_mut(bin as usize) {
        *h = h.saturating_add(1);
        *total += 1;
    }
}

/// [`count`] for `e` a residual or not finite (not counted), `scale` positive and finite:
/// one comparison where `|e| · scale` falls within the bins, where [`count`] after
/// [`residual_at`] tests `e` for finiteness and clamps the bin.
#[inline(always)]
fn count_finite(hist: &mut [u16; BINS], total: &mut usize, e: f32, scale: f32) {
    if let Some(h) = bin_finite(e, scale).and_then(|bin| hist.get_mut(bin)) {
        *h = h.saturating_add(1);
        *total += 1;
    }
}

/// The bin [`count_finite`] counts `e` in, `None` where it does not count it.
#[inline(always)]
fn bin_finite(e: f32, scale: f32) -> Option<usize> {
    let x = math::abs(e) * scale;
    if x < BINS as f32 {
        // 0 ≤ x < BINS: the mask changes nothing (it bounds the index for the compiler).
        Some((x as usize) & (BINS - 1))
    } else if math::finite(e) {
        Some(BINS - 1)
    } else {
        None
    }
}

/// One more count in `bin` of `hist`, or in its last for no bin (saturating).
#[inline(always)]
fn add_or_none(hist: &mut [u16; BINS + 1], bin: Option<usize>) {
    if let Some(h) = hist.get_mut(bin.unwrap_or(BINS)) {
        *h = h.saturating_add(1);
    }
}

/// [`at_span`]'s estimate from the histogram of its `total` residuals.
fn estimate(hist: &[u16; BINS], total: usize, sigma_r: f32) -> Option<f32> {
    if total < MIN_SAMPLES {
        return None;
    }
    // A first σ from the lower quartile of all residuals (too large where edges and clutter
    // add large ones), then twice the median of those within 3 σ of the last.
    let to_mm = sigma_r / PER_SIGMA;
    // Below 2²⁴ residuals every count is exact in f32: the quantiles in integers.
    // Direct calls (a function pointer would leave the firmware's stack bound unsound).
    let quantile = |half: f32| {
        if total < EXACT {
            quantile_bin_counted(hist, half)
        } else {
            quantile_bin(hist, half)
        }
    };
    let mut s = quantile(total as f32 * 0.25) * to_mm * QUARTILE_TO_SIGMA;
    // The residuals in the first `upto` bins, `inliers`: the next sum starts from them.
    let (mut inliers, mut upto) = (0usize, 0usize);
    for _ in 0..2 {
        let within = INLIER * RESIDUAL_PER_SIGMA * s / to_mm;
        let bins = (within as usize).clamp(1, BINS - 1);
        inliers = match (hist.get(upto..bins), hist.get(bins..upto)) {
            (Some(more), _) => inliers + sum(more),
            (_, Some(fewer)) => inliers - sum(fewer),
            _ => hist.iter().take(bins).map(|&h| usize::from(h)).sum(),
        };
        upto = bins;
        s = quantile(inliers as f32 * 0.5) * to_mm * MEDIAN_TO_SIGMA;
    }
    // Noise explains the scan only when most residuals are within 3 σ of it (a scan of
    // clutter, edges and posts has a quartile but no noise level).
    let noise = 2 * inliers >= total && inliers >= MIN_SAMPLES;
    let bound = 1.0 + SIGNIFICANT / math::sqrt(inliers as f32);
    (noise && s > bound * sigma_r).then_some(s.min(MAX_FACTOR * sigma_r))
}

/// Range residual of `m` from the chord `a`–`b` along `m`'s direction from the origin.
fn chord_residual(a: Point, m: Point, b: Point) -> Option<f32> {
    residual_at(a, m, b, math::sqrt(m.x * m.x + m.y * m.y))
}

/// [`chord_residual`] with `m`'s range `r` given. `None` when any of `a`, `m`, `b` is not
/// finite (NaN or infinite coordinates): the sine test then compares NaN, or an infinite
/// `|den|` with an infinite or NaN bound, and fails.
#[inline(always)]
fn residual_at(a: Point, m: Point, b: Point, r: f32) -> Option<f32> {
    residual_or_not_finite(a, m, b, r).filter(|e| math::finite(*e))
}

/// [`residual_at`] without its finiteness test: `e` when it is a residual, or not finite
/// when [`residual_at`] gives `None` for a reason other than the sine test.
#[inline(always)]
fn residual_or_not_finite(a: Point, m: Point, b: Point, r: f32) -> Option<f32> {
    let (cx, cy) = chord(a, b);
    residual_of_chord(a, m, b, r, math::sqrt(cx * cx + cy * cy))
}

/// The chord from `a` to `b`.
#[inline(always)]
fn chord(a: Point, b: Point) -> (f32, f32) {
    (b.x - a.x, b.y - a.y)
}

/// [`residual_or_not_finite`] with the chord's length `chord` given (the square root of the
/// sum of its squared coordinates, as that computes it).
#[inline(always)]
fn residual_of_chord(a: Point, m: Point, b: Point, r: f32, chord: f32) -> Option<f32> {
    let (cx, cy) = self::chord(a, b);
    // The sine of the beam's angle to the chord, times r·chord.
    let den = m.x * cy - m.y * cx;
    if !(math::abs(den) > MIN_SINE * r * chord) {
        return None;
    }
    // Beam direction m / r meets the chord at s = (a × b) / (d × c).
    let s = (a.x * b.y - a.y * b.x) * r / den;
    Some(r - s)
}

/// Points whose residuals [`Scatter::of_blocks`] computes at once.
const BLOCK: usize = 64;

/// The bin of no residual in [`Scatter::of_blocks`]' histograms: one past [`count`]'s.
const NONE: u16 = BINS as u16;

/// The bins ([`count`]'s, [`NONE`] for none) of the one-beam and the two-beam residual
/// ([`residual_at`]) of the middle point of each window of five `points`, in `bins`.
/// Branch-free, so that the loop vectorises: the same arithmetic in each lane as in
/// [`residual_at`] and [`count`].
#[inline(never)]
fn residual_bins(points: &[Point], scale: f32, bins: (&mut [u16], &mut [u16])) {
    const LAST: f32 = (BINS - 1) as f32;
    const TWO_23: f32 = 8_388_608.0;
    let bin = |e: f32| {
        // `count`'s bin `(x as i32).min(BINS - 1)` without the saturating conversion, which
        // does not vectorise: x clamped to [0, BINS − 1] (NaN to 0, as `as` does), then
        // truncated: adding 2²³ rounds it to a whole number (exactly), one less where that
        // rounded up; the bits of the sum less those of 2²³ are that number.
        let x = math::abs(e) * scale;
        let y = if x >= LAST {
            LAST
        } else if x >= 0.0 {
            x
        } else {
            0.0
        };
        let big = y + TWO_23;
        let up = u32::from(big - TWO_23 > y);
        let b = big
            .to_bits()
            .wrapping_sub(TWO_23.to_bits())
            .wrapping_sub(up);
        // No residual (NaN: a residual is finite), or a negative bin (a negative `scale`),
        // which `count` does not count.
        if e.is_nan() || x <= -1.0 {
            NONE
        } else {
            b as u16
        }
    };
    let windows = points
        .windows(5)
        .zip(bins.0.iter_mut().zip(bins.1.iter_mut()));
    for (w, (b1, b2)) in windows {
        let &[a, b, m, c, d] = w else {
            continue;
        };
        let r = math::sqrt_lanes(m.x * m.x + m.y * m.y);
        *b1 = bin(residual_or_nan(b, m, c, r));
        *b2 = bin(residual_or_nan(a, m, d, r));
    }
}

/// [`residual_at`] without a branch: NaN for `None`.
#[inline(always)]
fn residual_or_nan(a: Point, m: Point, b: Point, r: f32) -> f32 {
    let (cx, cy) = (b.x - a.x, b.y - a.y);
    let chord = math::sqrt_lanes(cx * cx + cy * cy);
    let den = m.x * cy - m.y * cx;
    let s = (a.x * b.y - a.y * b.x) * r / den;
    let e = r - s;
    if (math::abs(den) > MIN_SINE * r * chord) & math::finite(e) {
        e
    } else {
        f32::NAN
    }
}

/// Counts below which [`quantile_bin_counted`] is [`quantile_bin`]: every whole number up to
/// 2²⁴ is an f32.
const EXACT: usize = 1 << 24;

/// The sum of `counts`, eight at a time.
fn sum(counts: &[u16]) -> usize {
    let mut eights = counts.chunks_exact(8);
    let mut total = 0usize;
    for c in eights.by_ref() {
        total += c.iter().map(|&h| usize::from(h)).sum::<usize>();
    }
    total
        + eights
            .remainder()
            .iter()
            .map(|&h| usize::from(h))
            .sum::<usize>()
}

/// [`quantile_bin`] for a histogram of fewer than [`EXACT`] counts and `half` at most that:
/// the cumulative count in integers, against the least whole number not below `half` (the
/// same comparison, as the f32 sum of whole numbers below 2²⁴ is exact), the same result.
/// Eight bins at a time first: a run of bins whose counts keep the cumulative count below
/// the least whole number not below `half` holds no bin that reaches it.
fn quantile_bin_counted(hist: &[u16; BINS], half: f32) -> f32 {
    if !(half >= 0.0 && half < EXACT as f32) {
        return quantile_bin(hist, half);
    }
    let whole = half as u32;
    let need = whole + u32::from((whole as f32) < half);
    let (mut below, mut from) = (0u32, 0usize);
    for eight in hist.chunks_exact(8) {
        let s: u32 = eight.iter().map(|&h| u32::from(h)).sum();
        if below + s >= need {
            break;
        }
        below += s;
        from += 8;
    }
    let rest = hist.get(from..).unwrap_or_default();
    for (i, &h) in (from..).zip(rest) {
        let h = u32::from(h);
        if below + h >= need && h > 0 {
            return i as f32 + (half - below as f32) / h as f32;
        }
        below += h;
    }
    BINS as f32
}

/// Where the histogram's cumulative count reaches `half`, in bins (linear within a bin).
fn quantile_bin(hist: &[u16; BINS], half: f32) -> f32 {
    let mut below = 0.0f32;
    for (i, &h) in hist.iter().enumerate() {
        let h = f32::from(h);
        if below + h >= half && h > 0.0 {
            return i as f32 + (half - below) / h;
        }
        below += h;
    }
    BINS as f32
}

#[cfg(test)]
#[path = "scatter_bins.rs"]
mod bins;

#[cfg(test)]
#[path = "scatter_tests.rs"]
mod tests;

#[cfg(test)]
mod many {
    extern crate std;
    use super::*;

    /// Beyond `u16::MAX` points a two-byte bin could overflow: [`Scatter::of_blocks`] then
    /// counts as [`Scatter::of_stream`] does. 70 000 points 3 mm apart on an arc of 3 m radius
    /// around the scanner (every beam square to it; the arc run over again every 3 000
    /// points), every other one 4.3 mm behind it, the last 3 000 of them 10.3 mm: over 65 536
    /// one-beam residuals in one bin, about 3 000 in another, where an overflowed count would
    /// put the median.
    #[test]
    fn more_points_than_a_bin_holds_count_as_the_stream() {
        let wall: std::vec::Vec<Point> = (0..70_000)
            .map(|i| {
                let zig = if i < 67_000 { 4.3 } else { 10.3 };
                let r = 3_000.0 + zig * (i % 2) as f32;
                let (s, c) = math::sin_cos(0.001 * (i % 3000) as f32 - 1.5);
                Point::new(r * c, r * s)
            })
            .collect();
        let bits = |s: Scatter| (s.one.map(f32::to_bits), s.two.map(f32::to_bits));
        let (blocks, stream) = (
            Scatter::of_blocks(&wall, 2.0),
            Scatter::of_stream(&wall, 2.0),
        );
        assert!(stream.one.is_some(), "{stream:?}");
        assert_eq!(bits(blocks), bits(stream));
    }
}

#[cfg(test)]
#[path = "scatter_sign.rs"]
mod sign;
