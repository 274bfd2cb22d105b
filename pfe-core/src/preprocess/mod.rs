//! Pre-processing (§2): readings to points, with the systematic range
//! [`correction`](crate::correction) and motion de-skewing ([`motion`](crate::motion)) when
//! configured; the scan's own noise measured from its points (`scatter`). Invalid readings (no
//! return, reserved codes) are not points.

#[cfg(feature = "internals")]
pub mod scatter;
#[cfg(not(feature = "internals"))]
pub(crate) mod scatter;

use crate::beams::Beams;
use crate::config::Config;
use crate::flags::VALID;
use crate::geometry::Point;
use crate::math;
use crate::motion::Motion;
use crate::output::Stats;
use crate::scan::{max_code, valid_mm, Ranges, Scan};

/// Converts the readings of `scan` to points, ranges and flags (one slot per reading), with
/// the beam directions of `beams` and the scanner's `motion` (when de-skewing).
pub(crate) fn load(
    slots: (&mut [Point], &mut [f32], &mut [u8]),
    beams: &Beams<'_>,
    motion: Option<Motion>,
    scan: &Scan<'_>,
    config: &Config,
    stats: &mut Stats,
) {
    load_keeping::<0>(slots, beams, motion, scan, config, stats);
}

/// [`load`] keeping the bits `KEEP` of the flags of valid points (which `VALID` must not be
/// among): the points loaded again with what a step noted in those bits.
pub(crate) fn load_keeping<const KEEP: u8>(
    (points, ranges, flags): (&mut [Point], &mut [f32], &mut [u8]),
    beams: &Beams<'_>,
    motion: Option<Motion>,
    scan: &Scan<'_>,
    config: &Config,
    stats: &mut Stats,
) {
    let g = scan.geometry;
    let n = flags.len();
    let Some(dirs) = beams.dirs.get(..n) else {
        // Not reached (the beam table has room for every reading): an empty scan rather than
        // stale points.
        flags.fill(0);
        return;
    };
    // One loop per kind of reading, without a correction or de-skewing.
    let slots = (&mut *points, &mut *ranges, &mut *flags, dirs);
    let invalid = match scan.ranges {
        Ranges::Raw {
            values,
            mm_per_unit,
            max_valid,
        } => place_codes::<KEEP>(
            slots,
            values,
            mm_per_unit,
            max_code(mm_per_unit, max_valid, g.r_max),
        ),
        Ranges::Mm(mm) => place_mm::<KEEP>(slots, mm, g.r_max),
    };
    stats.readings = n;
    stats.valid = n - invalid;
    if config.correction.is_some() || motion.is_some() {
        let slots = (points, ranges, flags, dirs);
        stats.valid -= adjust(slots, motion, config);
    }
}

/// Applies the range correction and de-skewing to the valid points; a point they make invalid
/// is dropped. Returns the number dropped.
fn adjust(slots: Slots<'_>, motion: Option<Motion>, config: &Config) -> usize {
    let correction = config.correction;
    let (points, ranges, flags, dirs) = slots;
    let slots = points
        .iter_mut()
        .zip(ranges.iter_mut())
        .zip(flags.iter_mut())
        .zip(dirs.iter());
    let mut dropped = 0usize;
    for (i, (((point, range), flag), d)) in slots.enumerate() {
        if *flag & VALID == 0 {
            continue;
        }
        let mut r = *range;
        if let Some(k) = correction {
            r = k.apply(r);
        }
        // The beam's point turned and moved by the scanner's pose at its time (from the beam
        // table's direction: standing still, exactly the point without odometry).
        let p = match motion {
            Some(m) => {
                let pose = m.pose(i);
                let (s, c) = math::sin_cos(pose.theta);
                let (x, y) = (r * d.x, r * d.y);
                Point::new(c * x - s * y + pose.origin.x, s * x + c * y + pose.origin.y)
            }
            None => Point::new(r * d.x, r * d.y),
        };
        if math::finite(r) && r > 0.0 && p.is_valid() {
            (*point, *range) = (p, r);
        } else {
            dropped += 1;
            (*point, *range, *flag) = (Point::INVALID, 0.0, 0);
        }
    }
    dropped
}

/// The slots of a scan's beams (points, ranges, flags) and their directions, all of one length.
type Slots<'a> = (&'a mut [Point], &'a mut [f32], &'a mut [u8], &'a [Point]);

/// [`place`] for LMS range codes: `1 ..= max_code` are returns, in (0, r_max] mm. Not inlined
/// (nor is [`place_mm`]): the loop then keeps one pointer a slice in registers.
#[inline(never)]
fn place_codes<const KEEP: u8>(
    slots: Slots<'_>,
    codes: &[u16],
    mm_per_unit: f32,
    max_code: u16,
) -> usize {
    place::<KEEP, _>(slots, codes, |v| {
        (u32::from(v).wrapping_sub(1) < u32::from(max_code)).then(|| f32::from(v) * mm_per_unit)
    })
}

/// [`place`] for ranges in mm.
#[inline(never)]
fn place_mm<const KEEP: u8>(slots: Slots<'_>, mm: &[f32], r_max: f32) -> usize {
    place::<KEEP, _>(slots, mm, |r| valid_mm(r, r_max))
}

/// Points, ranges and flags from `readings` and `range(reading)`, the range in mm of a return
/// (`None`: no return). Returns the number of invalid readings (counting them keeps the common
/// path short).
#[inline(always)]
fn place<const KEEP: u8, T: Copy>(
    slots: Slots<'_>,
    readings: &[T],
    range: impl Fn(T) -> Option<f32>,
) -> usize {
    let (points, ranges, flags, dirs) = slots;
    let mut invalid = 0usize;
    let slots = points
        .iter_mut()
        .zip(ranges.iter_mut())
        .zip(flags.iter_mut())
        .zip(dirs.iter().zip(readings));
    for (((point, slot), flag), (d, &v)) in slots {
        (*point, *slot, *flag) = match range(v) {
            Some(r) => (Point::new(r * d.x, r * d.y), r, VALID | (*flag & KEEP)),
            None => {
                invalid += 1;
                (Point::INVALID, 0.0, 0)
            }
        };
    }
    invalid
}
