//! How the walk's marks are made: the σ_r the walk takes ([`Marking`]) and, for interleaved
//! sweeps out of place, their alignment and the walk again ([`in_place`]).

use crate::beams::Beams;
use crate::config::Config;
use crate::flags::{self, starts, END, JUMP, START, VALID, VEIL};
use crate::geometry::Point;
use crate::mark::{self, Neighbours};
use crate::output::Stats;
use crate::pass::Pass;
use crate::preprocess::{self, scatter};
use crate::rule::Rule;
use crate::scan::Scan;
use crate::sweeps;

/// How a walk marks: the σ_r it takes (the fits after it take it too) and its rule.
#[derive(Clone, Copy)]
pub(super) struct Marking {
    pub(super) sigma_r: f32,
    pub(super) rule: Rule,
    /// The scatter of the points it took its σ_r from ([`Marking::own`]), for
    /// [`scrutinised`] to ask the same points no more.
    scatter: Option<scatter::Scatter>,
}

impl Marking {
    /// With `config` as it is, for a scanner of maximum range and gap factor `gauge`.
    pub(super) fn of(config: &Config, (r_max, gap): (f32, f32)) -> Self {
        let rule = Rule::new(config, r_max, gap);
        Self {
            sigma_r: config.sigma_r,
            rule,
            scatter: None,
        }
    }

    /// With the σ_r of `points` where they scatter well beyond `config`'s ([`scatter`]),
    /// noted in `stats.scan_sigma_um` (0 where not).
    pub(super) fn own(
        points: &[Point],
        config: &Config,
        gauge: (f32, f32),
        stats: &mut Stats,
    ) -> Self {
        let scatter = scatter::Scatter::of(points, config.sigma_r);
        let sigma_r = match scatter.sigma() {
            Some(sigma) => {
                stats.scan_sigma_um = (sigma * 1000.0) as u32;
                sigma
            }
            None => {
                stats.scan_sigma_um = 0;
                config.sigma_r
            }
        };
        Self {
            scatter: Some(scatter),
            ..Self::of(&config.with_sigma_r(sigma_r), gauge)
        }
    }
}

/// The marks the check step and the segments go on from.
pub(super) struct Marks {
    /// How they were made.
    pub(super) by: Marking,
    /// The neighbouring starts the walk noted, when they were made by the walk the check step
    /// follows (else `None`: it reads every flag).
    pub(super) noted: Neighbours,
    /// Interleaved sweeps were moved onto sweep 0 by an estimate of their offset.
    pub(super) moved: bool,
    /// The variance the features inherit from that estimate ([`sweeps::Offsets::variance`]);
    /// zero when no sweep was moved by one.
    pub(super) alignment: [f32; 3],
}

/// Interleaved sweeps without odometry (default mode) are moved onto sweep 0 by their offset
/// estimated from the scan, when the marks of `walk` (which noted `noted` and counted
/// `predictions`) or, with the checks for real scans, the scan's scatter show them out of
/// place, and walked again; otherwise the walk's marks stand.
#[inline(always)]
pub(super) fn in_place(
    (beams, scan, config): (Beams<'_>, &Scan<'_>, &Config),
    slots: (&mut [Point], &mut [f32], &mut [u8]),
    walk: Marking,
    (noted, predictions): (Neighbours, usize),
    stats: &mut Stats,
) -> Marks {
    let sweeps = usize::from(scan.sweeps.max(1));
    if !(sweeps > 1 && scan.deskewing().is_none() && walk.rule.noise().is_some()) {
        return Marks::standing(walk, noted);
    }
    if config.scrutinised() {
        return scrutinised(
            (beams, scan, config),
            slots,
            walk,
            (noted, predictions),
            stats,
        );
    }
    let (points, ranges, flags) = slots;
    match suspected(scan, (points, ranges, flags), noted.is_some(), stats) {
        Suspect::No => Marks::standing(walk, noted),
        // Nothing to move: the marks stand (the check step reads every flag).
        Suspect::Unmoved => Marks::standing(walk, None),
        Suspect::Moved => {
            // Walked here, not in `suspected`: its frame stays off the walk's stack path.
            let noted = walk_again(beams, (points, ranges, flags), &walk.rule, true, stats);
            Marks {
                by: walk,
                noted,
                moved: true,
                alignment: [0.0; 3],
            }
        }
    }
}

impl Marks {
    /// The marks of `walk`, where the points stand, as the check step follows them.
    fn standing(by: Marking, noted: Neighbours) -> Self {
        Self {
            by,
            noted,
            moved: false,
            alignment: [0.0; 3],
        }
    }
}

/// What [`suspected`] did with the walk's marks.
enum Suspect {
    /// Not suspect: they stand.
    No,
    /// Suspect, but no sweep was moved: they stand.
    Unmoved,
    /// The sweeps were moved onto sweep 0: the points are to be walked again.
    Moved,
}

/// [`in_place`] without the checks for real scans: the sweeps are moved when the walk's marks
/// (`noted`: whether it noted every neighbouring start) are suspect ([`sweeps::suspect`]);
/// the caller walks them again with the same rule.
#[inline(never)]
fn suspected(
    scan: &Scan<'_>,
    (points, ranges, flags): (&mut [Point], &mut [f32], &mut [u8]),
    noted: bool,
    stats: &mut Stats,
) -> Suspect {
    // The marks' evidence (many segment starts): no fit is made before aligning.
    if !sweeps::suspect(flags, noted, stats.valid) {
        return Suspect::No;
    }
    let sweeps = usize::from(scan.sweeps.max(1));
    let step = scan.geometry.angle_step;
    stats.sweeps_aligned = sweeps::align(points, ranges, flags, sweeps, step);
    match stats.sweeps_aligned {
        0 => Suspect::Unmoved,
        _ => Suspect::Moved,
    }
}

/// [`in_place`] with the checks for real scans: declared sweeps (without odometry) with a
/// significant offset ([`sweeps`]) are moved onto sweep 0, so that the lines lie where sweep 0
/// saw them rather than between the sweeps, and walked again:
/// - two sweeps: with the first walk's σ when their scatter shows them apart, else with the
///   moved points' own σ (a turn between the sweeps moves points across the beams, which the
///   scatter shows only where beams graze a surface, and there the walk marks them). The new
///   walk is kept when it leaves fewer marks; otherwise the first walk's marks stand (kept in
///   [`STASHED`] meanwhile; its `predictions` count again, as when it was walked again), fitted
///   on the moved points when the sweeps showed apart and on the points as they were if not;
/// - more sweeps, when apart: with the first walk's σ (its marks on the unmoved points cut
///   segments into pieces of one period, four sweeps drifting apart).
///
/// The fits of moved points use their own σ.
#[inline(never)]
fn scrutinised(
    (beams, scan, config): (Beams<'_>, &Scan<'_>, &Config),
    (points, ranges, flags): (&mut [Point], &mut [f32], &mut [u8]),
    walk: Marking,
    (noted, predictions): (Neighbours, usize),
    stats: &mut Stats,
) -> Marks {
    let sweeps = usize::from(scan.sweeps.max(1));
    // The walk's σ came from these points' scatter at the same σ_r: asked once.
    let apart = match &walk.scatter {
        Some(seen) => seen.sweeps_apart(points, sweeps, config.sigma_r),
        None => scatter::sweeps_apart(points, sweeps, config.sigma_r),
    };
    let offsets = match apart || sweeps == 2 {
        true => sweeps::Offsets::of(points, sweeps, scan.geometry.angle_step),
        false => sweeps::Offsets::default(),
    };
    if offsets.moved() == 0 {
        return Marks::standing(walk, noted);
    }
    let walk_sigma_um = stats.scan_sigma_um;
    offsets.apply(points, ranges, flags);
    let gauge = (scan.geometry.r_max, beams.gap_factor);
    let moved = Marking::own(points, config, gauge, stats);
    let moved_sigma_um = stats.scan_sigma_um;
    if sweeps > 2 {
        walk_again(beams, (points, ranges, flags), &walk.rule, true, stats);
    } else {
        let rule = if apart { &walk.rule } else { &moved.rule };
        // The first walk's starts, and its marks kept in `STASHED` where the walk again
        // clears them.
        let unmoved = starts(flags);
        flags::rewrite(flags, stash);
        let mut pass = Pass::over(beams, (&*points, &*ranges, &mut *flags), None, stats);
        mark::mark(&mut pass, rule, true);
        if starts(flags) >= unmoved {
            // The first walk stands (the same walk over the points would mark them the same,
            // and count its predictions again). When apart, on the points as moved: they are
            // what loading them again and moving them again gives, so only its marks come
            // back (on the valid points, as a load keeps them).
            stats.predictions += predictions;
            if apart {
                flags::rewrite(flags, unstash_valid);
            } else {
                // The points as they were: loaded again, the first walk's marks kept.
                let motion = scan.deskewing();
                let slots = (&mut *points, &mut *ranges, &mut *flags);
                preprocess::load_keeping::<STASHED>(slots, &beams, motion, scan, config, stats);
                flags
                    .iter_mut()
                    .for_each(|f| *f = (*f & VALID) | (*f & STASHED) >> 4);
                stats.scan_sigma_um = walk_sigma_um;
                return Marks::standing(walk, None);
            }
        } else {
            let unstashed = u32::from(!STASHED);
            flags::rewrite(flags, |f, lanes| f & (unstashed * lanes));
        }
    }
    stats.scan_sigma_um = moved_sigma_um;
    stats.sweeps_aligned = offsets.moved();
    // The check step reads every flag (the same outcome as following the walk's notes).
    Marks {
        by: moved,
        noted: None,
        moved: true,
        alignment: offsets.variance(),
    }
}

/// Walks the points (no motion) again with `rule`, from the flags of the pre-processing
/// (`uneven`: see [`mark::mark`]); returns the neighbouring starts it noted (every walk's
/// predictions are counted).
fn walk_again(
    beams: Beams<'_>,
    (points, ranges, flags): (&[Point], &[f32], &mut [u8]),
    rule: &Rule,
    uneven: bool,
    stats: &mut Stats,
) -> Neighbours {
    let kept = u32::from(VALID | STASHED);
    flags::rewrite(flags, |f, lanes| f & (kept * lanes));
    let mut pass = Pass::over(beams, (points, ranges, flags), None, stats);
    mark::mark(&mut pass, rule, uneven)
}

/// A flag (or each byte of a word, `lanes`: see [`flags::rewrite`]) with the [`WALKED`] bits
/// kept in [`STASHED`] and cleared as a walk again clears them (`VALID` and `STASHED` kept).
fn stash(f: u32, lanes: u32) -> u32 {
    let (kept, walked) = (u32::from(VALID | STASHED), u32::from(WALKED));
    (f & (kept * lanes)) | ((f & (walked * lanes)) << 4)
}

/// A flag (or each byte of a word) as loading the points again keeps it, then with its
/// [`STASHED`] bits back as [`WALKED`]: `VALID` and those where valid, else 0.
fn unstash_valid(f: u32, lanes: u32) -> u32 {
    // 0xff in the bytes of valid points (`VALID` is bit 0), else 0.
    let v = f & (u32::from(VALID) * lanes);
    v | (((f & (u32::from(STASHED) * lanes)) >> 4) & (v * 0xff))
}

/// The flags a walk sets ([`mark::mark`]).
const WALKED: u8 = START | JUMP;
/// Where [`scrutinised`] keeps the first walk's [`WALKED`] flags while it walks again: bits no
/// step sets (none of [`crate::flags`]).
const STASHED: u8 = WALKED << 4;
const _: () = assert!(STASHED >> 4 == WALKED && STASHED & (VALID | WALKED | END | VEIL) == 0);
// The flags rewritten four at a time: `VALID` times 0xff is a byte's mask.
const _: () = assert!(VALID == 1);

#[cfg(test)]
mod tests {
    use super::*;

    /// The flag rules the sweeps' second walk rewrites four flags at a time by are the
    /// byte-wise steps they replace, for every byte: the stash (`*f |= (*f & WALKED) << 4`,
    /// then the walk's `*f &= VALID | STASHED`), and the marks back on the moved points
    /// (loading them again: `VALID | (*f & STASHED)` where valid, else 0; then
    /// `(*f & VALID) | (*f & STASHED) >> 4`); four bytes in a word as each on its own.
    #[test]
    fn the_stash_rules_are_the_byte_steps() {
        for f in 0..=255u8 {
            let stashed = (f | (f & WALKED) << 4) & (VALID | STASHED);
            assert_eq!(stash(u32::from(f), 1), u32::from(stashed), "{f:#04x}");
            let loaded = if f & VALID != 0 {
                VALID | (f & STASHED)
            } else {
                0
            };
            let back = (loaded & VALID) | (loaded & STASHED) >> 4;
            assert_eq!(unstash_valid(u32::from(f), 1), u32::from(back), "{f:#04x}");
            let word = u32::from_le_bytes([f, 0xff, f ^ 0x55, 0xa1]);
            for rule in [stash, unstash_valid] {
                let bytes = word.to_le_bytes().map(|b| rule(u32::from(b), 1) as u8);
                assert_eq!(rule(word, 0x0101_0101).to_le_bytes(), bytes, "{f:#04x}");
            }
        }
    }
}
