//! The extractor: it owns a beam table, the work buffers of one scan and the output, and runs
//! the steps over them (see [`Extractor::extract`]).

use heapless::Vec;

use crate::beams::{BeamTable, Beams};
use crate::check;
use crate::classify;
use crate::config::Config;
use crate::error::ExtractError;
use crate::feature::Feature;
use crate::flags::{END, START, VEIL};
use crate::geometry::Point;
use crate::mark;
use crate::output::{FeatureSink, Stage, StageObserver, Stats, Unobserved};
use crate::pass::Pass;
use crate::preprocess;
use crate::reach;
#[cfg(test)]
use crate::rule::Rule;
use crate::scan::Scan;
use crate::segment;
use crate::sift;
use crate::sweeps;

mod marking;

use marking::{in_place, Marking};

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
    /// What depends only on the scan geometry, kept across scans.
    beams: BeamTable<N>,
    /// The last scan's points, ranges and flags.
    work: Buffers<N>,
    /// The last extraction's features and statistics.
    out: Output<M>,
}

/// The work buffers of one scan: a slot per reading, `len` of them in use.
struct Buffers<const N: usize> {
    points: [Point; N],
    ranges: [f32; N],
    flags: [u8; N],
    len: usize,
}

/// An extraction's output.
struct Output<const M: usize> {
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
        // All zero bytes (slots past `len` are never read), so that a `static` extractor goes
        // to .bss rather than being copied from flash as well.
        Self {
            beams: BeamTable::new(),
            work: Buffers {
                points: [Point::new(0.0, 0.0); N],
                ranges: [0.0; N],
                flags: [0; N],
                len: 0,
            },
            out: Output {
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
                    sweeps_aligned: 0,
                    scan_sigma_um: 0,
                    objects: 0,
                    veils: 0,
                },
            },
        }
    }

    /// Extracts the features of `scan`. On `Err(FeatureCapacity)` the features that fitted are
    /// still available from [`features`](Self::features): the first `M`, less the lines the
    /// real-scan checks then found the scanner could not have seen (the capacity they held is
    /// not refilled), plus small objects where room is left.
    pub fn extract(&mut self, scan: &Scan<'_>, config: &Config) -> Result<Stats, ExtractError> {
        self.work.len = 0;
        self.out.features.clear();
        self.out.stats = Stats::default();
        self.work.len = accept(scan, config, N)?;
        let Self { beams, work, out } = self;
        let beams = beams.of(scan.geometry);
        run(
            beams,
            work.slots(),
            scan,
            config,
            &mut out.stats,
            &mut out.features,
        )
    }

    /// [`extract`](Self::extract), telling `observer` when each [`Stage`] ends (for per-stage
    /// timings or instruction counts; the same features and statistics). A scan refused before
    /// any stage (`Err` other than `FeatureCapacity`) tells it nothing.
    pub fn extract_observed(
        &mut self,
        scan: &Scan<'_>,
        config: &Config,
        observer: &mut dyn StageObserver,
    ) -> Result<Stats, ExtractError> {
        self.work.len = 0;
        self.out.features.clear();
        self.out.stats = Stats::default();
        self.work.len = accept(scan, config, N)?;
        let Self { beams, work, out } = self;
        let beams = beams.of(scan.geometry);
        run_observed(
            beams,
            work.slots(),
            scan,
            config,
            (&mut out.stats, &mut out.features),
            observer,
        )
    }

    /// Features of the last extraction, in scan order.
    pub fn features(&self) -> &[Feature] {
        &self.out.features
    }

    /// Runs `step` on the work state of `scan` (loaded: corrected, flags valid, nothing
    /// marked) with `config`'s rule: one step of the pipeline under test.
    #[cfg(test)]
    pub(crate) fn with_pass<R>(
        &mut self,
        scan: &Scan<'_>,
        config: &Config,
        step: impl FnOnce(&mut Pass<'_>, &Rule) -> R,
    ) -> R {
        self.work.len = scan.ranges.len().min(N);
        let Extractor { beams, work, out } = self;
        let mut pass = Pass::load(
            beams.of(scan.geometry),
            work.slots(),
            scan,
            config,
            &mut out.stats,
        );
        let rule = Rule::new(config, scan.geometry.r_max, pass.beams.gap_factor);
        step(&mut pass, &rule)
    }

    /// Statistics of the last extraction.
    pub fn stats(&self) -> Stats {
        self.out.stats
    }

    /// Points of the last scan (after correction and de-skew); invalid readings are
    /// [`Point::INVALID`].
    pub fn points(&self) -> &[Point] {
        self.work.points.get(..self.work.len).unwrap_or(&[])
    }

    /// Mark points of the last extraction: the first and last point of every segment (after
    /// the check step and pairing, and in the default mode the reach of line ends over the
    /// beams beside them), in increasing order.
    pub fn marks(&self) -> impl Iterator<Item = usize> + '_ {
        self.work
            .flags
            .iter()
            .take(self.work.len)
            .enumerate()
            .filter(|(_, f)| **f & (START | END) != 0)
            .map(|(i, _)| i)
    }

    /// True when point `i` is a mixed pixel: a point of a line the scanner cannot see (over
    /// 85° incidence at its midpoint, or shorter than 10 mm), in no feature (with
    /// [`Config::scrutiny`]; their number is [`Stats::veils`]).
    ///
    /// ```
    /// use pfe_core::{Config, Extractor, ScanGeometry, Scan};
    /// let mut ex = Extractor::<361, 32>::new();
    /// ex.extract(&Scan::from_mm(ScanGeometry::LMS200_180_050, &[2000.0; 361]), &Config::default())?;
    /// assert!(!(0..361).any(|i| ex.is_veil(i)));
    /// # Ok::<(), pfe_core::ExtractError>(())
    /// ```
    pub fn is_veil(&self, i: usize) -> bool {
        i < self.work.len && self.work.flags.get(i).is_some_and(|f| f & VEIL != 0)
    }

    /// True when point `i` is a mark point.
    pub fn is_mark(&self, i: usize) -> bool {
        i < self.work.len
            && self
                .work
                .flags
                .get(i)
                .is_some_and(|f| f & (START | END) != 0)
    }
}

impl<const N: usize> Buffers<N> {
    /// The slots in use: points, ranges and flags.
    fn slots(&mut self) -> (&mut [Point], &mut [f32], &mut [u8]) {
        let n = self.len;
        (
            self.points.get_mut(..n).unwrap_or_default(),
            self.ranges.get_mut(..n).unwrap_or_default(),
            self.flags.get_mut(..n).unwrap_or_default(),
        )
    }
}

/// The number of readings of `scan`, when an extractor with room for `capacity` readings can
/// extract it with `config`.
fn accept(scan: &Scan<'_>, config: &Config, capacity: usize) -> Result<usize, ExtractError> {
    if !scan.geometry.is_valid() {
        return Err(ExtractError::InvalidGeometry);
    }
    if !config.is_valid() {
        return Err(ExtractError::InvalidConfig);
    }
    let n = scan.ranges.len();
    let capacity = capacity.min(usize::from(u16::MAX));
    if n > capacity {
        return Err(ExtractError::TooManyReadings { got: n, capacity });
    }
    Ok(n)
}

/// The paper's steps and ours, in order, over an extractor's parts (not generic: compiled
/// once, here).
#[inline(never)]
fn run(
    beams: Beams<'_>,
    slots: (&mut [Point], &mut [f32], &mut [u8]),
    scan: &Scan<'_>,
    config: &Config,
    stats: &mut Stats,
    out: &mut dyn FeatureSink,
) -> Result<Stats, ExtractError> {
    steps(beams, slots, scan, config, (stats, out), &mut Unobserved)
}

/// [`run`] telling `observer` where each stage ends (its own copy: `run` has no calls).
#[inline(never)]
fn run_observed(
    beams: Beams<'_>,
    slots: (&mut [Point], &mut [f32], &mut [u8]),
    scan: &Scan<'_>,
    config: &Config,
    out: (&mut Stats, &mut dyn FeatureSink),
    observer: &mut dyn StageObserver,
) -> Result<Stats, ExtractError> {
    steps(beams, slots, scan, config, out, observer)
}

/// The steps, in order; `observer` is told where each ends.
#[inline(always)]
fn steps<O: StageObserver + ?Sized>(
    beams: Beams<'_>,
    (points, ranges, flags): (&mut [Point], &mut [f32], &mut [u8]),
    scan: &Scan<'_>,
    config: &Config,
    (stats, out): (&mut Stats, &mut dyn FeatureSink),
    observer: &mut O,
) -> Result<Stats, ExtractError> {
    let motion = scan.deskewing();
    let checks = config.scrutinised();
    // §2: readings to points (range correction, de-skew).
    let slots = (&mut *points, &mut *ranges, &mut *flags);
    preprocess::load(slots, &beams, motion, scan, config, stats);
    observer.ended(Stage::Load);
    // Ours, with the checks for real scans: the readings' rounding joins the systematic error
    // (see `Scan::quantum`), and the walk takes the scan's own σ where it scatters well beyond
    // σ_r ([`scatter`]).
    let rounded;
    let config = match checks {
        true => {
            let var = config.sigma_sys * config.sigma_sys + scan.shared_rounding(config.sigma_r);
            rounded = config.with_sigma_sys(crate::math::sqrt(var));
            &rounded
        }
        false => config,
    };
    let gauge = (scan.geometry.r_max, beams.gap_factor);
    let walk = match checks {
        true => Marking::own(points, config, gauge, stats),
        false => Marking::of(config, gauge),
    };
    observer.ended(Stage::Scatter);
    // §3.1–3.2, §3.6: mark points by prediction.
    let uneven = motion.is_some_and(|m| m.sweeps_apart());
    let mut pass = Pass::over(beams, (&*points, &*ranges, &mut *flags), motion, stats);
    let before = pass.stats.predictions;
    let noted = mark::mark(&mut pass, &walk.rule, uneven);
    let walked = (noted, pass.stats.predictions - before);
    observer.ended(Stage::Mark);
    // Ours: interleaved sweeps out of place (no odometry) moved onto sweep 0 and marked again.
    let parts = (beams, scan, config);
    let marks = in_place(parts, (points, ranges, flags), walk, walked, stats);
    observer.ended(Stage::Sweeps);
    let fitted;
    let config = match checks {
        true => {
            fitted = config.with_sigma_r(marks.by.sigma_r);
            &fitted
        }
        false => config,
    };
    let rule = &marks.by.rule;
    let mut pass = Pass::over(beams, (&*points, &*ranges, &mut *flags), motion, stats);
    // §3.3: the check step.
    if config.check_step {
        check::check(&mut pass, rule, marks.noted.as_deref(), marks.moved);
    }
    observer.ended(Stage::Check);
    // §3.4–3.5: segments and pairing, merges, the type and fit of each.
    segment::segments(&mut pass, rule, config, out);
    // Ours: the features inherit the error of the offsets that moved the sweeps.
    if classify::honest(config, checks) {
        sweeps::inherit(out.features_mut(), marks.alignment);
    }
    observer.ended(Stage::Segments);
    // Ours, with the checks for real scans: line ends reach over the beams beside them that
    // lie on them.
    if let (true, Some(noise)) = (checks, rule.noise()) {
        reach::extend(&mut pass, noise, out.features_mut());
    }
    observer.ended(Stage::Reach);
    // Ours, with the checks for real scans: no line the scanner cannot see; small objects.
    if checks {
        sift::sift(&mut pass, config, out);
        if classify::honest(config, checks) {
            sweeps::inherit_objects(out.features_mut(), marks.alignment);
        }
    }
    observer.ended(Stage::Sift);
    outcome(pass.stats)
}

/// The extraction's result from its statistics.
fn outcome(stats: &Stats) -> Result<Stats, ExtractError> {
    match stats.dropped {
        0 => Ok(*stats),
        dropped => Err(ExtractError::FeatureCapacity { dropped }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math;
    use crate::scan::ScanGeometry;

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
                ex.work.len = ranges.len();
                let Extractor { beams, work, out } = ex;
                let mut pass =
                    Pass::load(beams.of(g), work.slots(), &scan, &config, &mut out.stats);
                let rule = Rule::new(&config, g.r_max, pass.beams.gap_factor);
                let mut neighbours = mark::mark(&mut pass, &rule, false);
                let mut before = [0u8; 361];
                before.copy_from_slice(pass.flags);
                match (&neighbours, all) {
                    (_, true) => neighbours = None,
                    (Some(_), false) => noted += 1,
                    (None, false) => overflowed += 1,
                }
                check::check(&mut pass, &rule, neighbours.as_deref(), false);
                joined += usize::from(!all && pass.flags != before);
                flags[usize::from(all)].copy_from_slice(pass.flags);
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

    /// Extractors of different capacities give the same marks, features and statistics, in
    /// both modes.
    #[test]
    fn every_capacity_gives_the_same() {
        let g = ScanGeometry::LMS200_180_050;
        let (mut lms, mut other) = (Extractor::<401, 48>::new(), Extractor::<361, 48>::new());
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
}
