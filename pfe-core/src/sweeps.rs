//! Interleaved sweeps without odometry: the rigid offset of each sweep against sweep 0,
//! estimated from the scan itself, and its removal.
//!
//! A scan of `S` interleaved sweeps (an LMS2xx at 0.5°: `S = 2`, 0.25°: `S = 4`) has beam `i`
//! in sweep `i mod S`, one mirror turn after the sweep before. A moving scanner takes sweep `s`
//! from a pose `(dx, dy, dθ)` in the frame of sweep 0, so along a smooth surface its points
//! lie off the surface that sweep 0 sees and the beams zigzag. For beam `q = S·j + s` between
//! the sweep-0 beams `a = S·j` and `b = S·(j + 1)`, the signed distance `e` of `q` from the
//! chord `ab` (unit normal `n`) is, to first order,
//!
//! `e − f(1 − f)·e₀ = −n·(d + dθ × q)`, `d = (dx, dy)`, `f = s / S`,
//!
//! where `e₀`, the distance of `b` from the chord of `a` and `c = S·(j + 2)` (all sweep 0),
//! removes the surface's own curvature (on a circle of radius R the sagitta at fraction `f`
//! of a chord `L` is `f(1 − f)·L²/2R`, and `e₀ = L²/2R`). A linear least-squares problem in
//! `(dx, dy, dθ)` over such beams where the surface is smooth (no jump, a small `e₀`), solved
//! again once without the rows beyond 3σ of the first solution (corners, edges).
//!
//! The extractor moves sweep `s`'s points by the estimate (rotation `dθ`, then translation `d`)
//! when it is significant (χ² of the estimate against its covariance above
//! [`SweepOffset::CHI2_SIGNIFICANT`]) and moves some point by more than
//! [`SweepOffset::MIN_SHIFT_MM`]; otherwise the points stay as they are.

use crate::feature::{CircleFeature, Feature, LineFeature, ObjectFeature};
use crate::flags::{START, VALID};
use crate::geometry::Point;
use crate::math;

mod solve;

/// Most rows (beams) one sweep's estimate uses: longer sweeps are subsampled evenly.
pub(crate) const MAX_ROWS: usize = 64;

/// The pose of one sweep's scanner in the frame of sweep 0, estimated from the scan.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SweepOffset {
    /// Translation along x, mm.
    pub dx: f32,
    /// Translation along y, mm.
    pub dy: f32,
    /// Rotation, rad (counter-clockwise positive).
    pub dtheta: f32,
    /// Standard errors of `dx`, `dy` (mm) and `dtheta` (rad).
    pub sd: [f32; 3],
    /// Residual standard deviation of the rows used, mm.
    pub sigma: f32,
    /// χ² of the estimate against zero with its covariance (3 degrees of freedom).
    pub chi2: f32,
    /// Rows (beams) used.
    pub rows: u16,
    /// Largest displacement the offset gives a point of the sweep, mm.
    pub max_shift: f32,
}

impl SweepOffset {
    /// χ² (3 degrees of freedom) above which an offset is significant (p ≈ 0.1 %).
    pub const CHI2_SIGNIFICANT: f32 = 16.3;
    /// Smallest point displacement worth applying, mm.
    pub const MIN_SHIFT_MM: f32 = 1.0;

    /// True when the extractor applies this offset.
    pub fn is_significant(&self) -> bool {
        self.chi2 > Self::CHI2_SIGNIFICANT && self.max_shift > Self::MIN_SHIFT_MM
    }

    /// Point `p` of the sweep in the frame of sweep 0: rotated by `dtheta`, then translated.
    // The extractor turns whole sweeps ([`Offsets::apply`]); this is the tests' entry.
    #[cfg_attr(not(any(test, feature = "internals")), allow(dead_code))]
    pub fn apply(&self, p: Point) -> Point {
        self.turned(math::sin_cos(self.dtheta), p)
    }

    /// [`apply`](Self::apply) with the sine and cosine of `dtheta` given (asked once a sweep).
    #[inline(always)]
    fn turned(&self, (s, c): (f32, f32), p: Point) -> Point {
        Point::new(c * p.x - s * p.y + self.dx, s * p.x + c * p.y + self.dy)
    }
}

/// The offset of sweep `sweep` (1 ≤ `sweep` < `sweeps`) of `points` (one per beam, invalid
/// ones not finite) against sweep 0; `angle_step` is the bearing step between beams, rad.
/// `None` when too few beams are on smooth surfaces or the geometry does not fix the offset.
///
/// ```
/// use pfe_core::sweeps::estimate;
/// use pfe_core::{Point, ScanGeometry};
/// // A room 3 m × 4 m; the odd beams from a scanner 8 mm ahead.
/// let g = ScanGeometry::LMS200_180_050;
/// let points: Vec<Point> = (0..361)
///     .map(|i| {
///         let (b, o) = (g.bearing(i), if i % 2 == 1 { 8.0 } else { 0.0 });
///         let (s, c) = (b.sin(), b.cos());
///         let front = if c > 1e-6 { (3000.0 - o) / c } else { f32::INFINITY };
///         let side = 2000.0 / s.abs();
///         Point::new(front.min(side) * c, front.min(side) * s)
///     })
///     .collect();
/// let e = estimate(&points, 2, 1, g.angle_step).unwrap();
/// assert!((e.dx - 8.0).abs() < 0.3 && e.dy.abs() < 0.3 && e.dtheta.abs() < 1e-4);
/// ```
pub fn estimate(
    points: &[Point],
    sweeps: usize,
    sweep: usize,
    angle_step: f32,
) -> Option<SweepOffset> {
    if sweep == 0 || sweep >= sweeps || !math::finite(angle_step) {
        return None;
    }
    solve::offset_of(points, (sweeps, sweep), angle_step)
}

/// Moves the points of every sweep `s ≥ 1` of a scan of `sweeps` interleaved sweeps onto
/// sweep 0 by its [`estimate`], where significant, and sets their `ranges` to their new
/// distance from the origin. Returns the number of sweeps moved.
pub(crate) fn align(
    points: &mut [Point],
    ranges: &mut [f32],
    flags: &[u8],
    sweeps: usize,
    angle_step: f32,
) -> usize {
    let offsets = Offsets::of(points, sweeps, angle_step);
    offsets.apply(points, ranges, flags);
    offsets.moved()
}

/// Most sweeps a scan is aligned for (an LMS2xx at 0.25°): a scan declared with more is left
/// as it is, rather than some of its sweeps moved.
pub const MAX_SWEEPS: usize = 4;

/// The significant offsets of sweeps 1 to 3 of one scan of at most [`MAX_SWEEPS`].
#[derive(Clone, Copy, Default)]
pub(crate) struct Offsets {
    sweeps: usize,
    of: [Option<SweepOffset>; MAX_SWEEPS - 1],
}

impl Offsets {
    /// Each sweep's [`estimate`] where it is significant (none beyond [`MAX_SWEEPS`]).
    pub(crate) fn of(points: &[Point], sweeps: usize, angle_step: f32) -> Offsets {
        if sweeps > MAX_SWEEPS {
            return Offsets::default();
        }
        let mut of = [None; MAX_SWEEPS - 1];
        for (s, slot) in of.iter_mut().enumerate() {
            let sweep = s + 1;
            if sweep < sweeps.min(points.len()) {
                *slot =
                    estimate(points, sweeps, sweep, angle_step).filter(SweepOffset::is_significant);
            }
        }
        Offsets { sweeps, of }
    }

    /// The variance of the offsets applied, as a feature over all sweeps inherits it: sweep s
    /// holds 1/S of its points (interleaved), which move by s's error, so the feature moves
    /// by 1/S of it. Σ over the moved sweeps of (sd/S)² for x, y (mm²) and θ (rad²); the
    /// estimates' correlations are left out.
    pub(crate) fn variance(&self) -> [f32; 3] {
        let share = 1.0 / self.sweeps.max(1) as f32;
        let mut v = [0.0f32; 3];
        for o in self.of.iter().flatten() {
            for (v, sd) in v.iter_mut().zip(o.sd) {
                let s = sd * share;
                *v += s * s;
            }
        }
        if v.iter().all(|x| math::finite(*x)) {
            v
        } else {
            [0.0; 3]
        }
    }

    /// Sweeps with a significant offset.
    pub(crate) fn moved(&self) -> usize {
        self.of.iter().flatten().count()
    }

    /// Moves each sweep's valid points by its offset and sets their `ranges` to their new
    /// distance from the origin.
    pub(crate) fn apply(&self, points: &mut [Point], ranges: &mut [f32], flags: &[u8]) {
        // One slice of each, cut to one length: the loops index them without checks.
        let n = points.len().min(ranges.len()).min(flags.len());
        let (Some(points), Some(ranges), Some(flags)) =
            (points.get_mut(..n), ranges.get_mut(..n), flags.get(..n))
        else {
            return;
        };
        let step = self.sweeps.max(1);
        for (s, offset) in self.of.iter().enumerate() {
            let Some(offset) = offset else {
                continue;
            };
            let turn = math::sin_cos(offset.dtheta);
            let mut i = s + 1;
            while let (Some(p), Some(r), Some(f)) =
                (points.get_mut(i), ranges.get_mut(i), flags.get(i))
            {
                if f & VALID != 0 {
                    *p = offset.turned(turn, *p);
                    *r = math::hypot(p.x, p.y);
                }
                i += step;
            }
        }
    }
}

/// Whether the default mode's walk over a scan of interleaved sweeps left the marks that
/// sweeps out of place make: more segment starts among `flags` than one in [`SUSPECT_EVERY`]
/// of the `valid` points, or more neighbouring starts than the walk notes (`noted` false).
pub(crate) fn suspect(flags: &[u8], noted: bool, valid: usize) -> bool {
    !noted || flags.iter().filter(|f| **f & START != 0).count() * SUSPECT_EVERY > valid
}

/// One segment start in this many valid points is more than a scan of sweeps in place makes.
pub(crate) const SUSPECT_EVERY: usize = 18;

/// Adds to every feature's covariance what it inherits from the offsets that moved
/// interleaved sweeps onto sweep 0 (`alignment`: their [`Offsets::variance`]).
pub(crate) fn inherit(features: &mut [Feature], alignment: [f32; 3]) {
    for f in features {
        match f {
            Feature::Line(lf) => aligned_line(lf, alignment),
            Feature::Circle(cf) => aligned_circle(cf, alignment),
            Feature::Object(of) => aligned_object(of, alignment),
        }
    }
}

/// [`inherit`] for the small objects only (they are made after the lines and circles
/// inherited theirs).
pub(crate) fn inherit_objects(features: &mut [Feature], alignment: [f32; 3]) {
    for f in features {
        if let Feature::Object(of) = f {
            aligned_object(of, alignment);
        }
    }
}

/// Adds to an object's centre covariance what it inherits from the offsets that moved
/// interleaved sweeps, as a circle's centre does.
fn aligned_object(of: &mut ObjectFeature, [xx, yy, tt]: [f32; 3]) {
    let c = of.center;
    let [[cxx, cxy], [cyx, cyy]] = &mut of.cov;
    *cxx += xx + tt * c.y * c.y;
    *cyy += yy + tt * c.x * c.x;
    *cxy -= tt * c.x * c.y;
    *cyx -= tt * c.x * c.y;
}

/// Adds to a line's covariance what it inherits from the offsets that moved interleaved
/// sweeps (`alignment`, see [`Offsets::variance`]): moving its points by (dx, dy) and turning them
/// by dθ about the scanner moves ρ by n·(dx, dy) and α by dθ, each by the share of points the
/// sweep holds (already in `alignment`).
fn aligned_line(lf: &mut LineFeature, [xx, yy, tt]: [f32; 3]) {
    if !(xx > 0.0 || yy > 0.0 || tt > 0.0) {
        return;
    }
    let (sin, cos) = math::sin_cos(lf.alpha);
    lf.var_rho += cos * cos * xx + sin * sin * yy;
    lf.var_alpha += tt;
}

/// Adds to a circle's centre covariance what it inherits from the offsets that moved
/// interleaved sweeps (`alignment`, see [`Offsets::variance`]): (dx, dy) moves the centre c by
/// itself, dθ by dθ (−c_y, c_x).
fn aligned_circle(cf: &mut CircleFeature, [xx, yy, tt]: [f32; 3]) {
    let c = cf.center;
    let [[cxx, cxy, _], [cyx, cyy, _], _] = &mut cf.cov;
    *cxx += xx + tt * c.y * c.y;
    *cyy += yy + tt * c.x * c.x;
    *cxy -= tt * c.x * c.y;
    *cyx -= tt * c.x * c.y;
}

#[cfg(test)]
mod tests {
    use super::{aligned_circle, aligned_line, aligned_object, Offsets, SweepOffset};
    use crate::feature::{CircleFeature, LineFeature, ObjectFeature};
    use crate::geometry::Point;

    /// An object's centre inherits the sweeps' offsets as a point does: (x, y) moved by
    /// (dx, dy) and turned by dθ about the scanner, (−y, x) dθ.
    #[test]
    fn an_object_inherits_the_offsets_as_its_centre_does() {
        let mut of = ObjectFeature {
            first: 10,
            last: 14,
            points: 5,
            center: Point::new(2000.0, 500.0),
            cov: [[100.0, 10.0], [10.0, 50.0]],
            extent: 120.0,
        };
        aligned_object(&mut of, [4.0, 9.0, 1e-6]);
        let [[xx, xy], [yx, yy]] = of.cov;
        assert!(
            (xx - (100.0 + 4.0 + 1e-6 * 500.0 * 500.0)).abs() < 1e-3,
            "{xx}"
        );
        assert!(
            (yy - (50.0 + 9.0 + 1e-6 * 2000.0 * 2000.0)).abs() < 1e-3,
            "{yy}"
        );
        assert!((xy - (10.0 - 1e-6 * 2000.0 * 500.0)).abs() < 1e-3, "{xy}");
        assert_eq!(xy, yx);
    }

    /// A walk is suspect of sweeps out of place when it did not note its starts, or when more
    /// than one valid point in `SUSPECT_EVERY` starts a segment: 361 valid points with 20
    /// starts (one in 18.05) are not, with 21 they are; 360 with 20 (exactly one in 18) are not.
    #[test]
    fn a_walk_with_more_starts_than_sweeps_in_place_make_is_suspect() {
        use crate::flags::START;
        let flags = |starts: usize| -> [u8; 361] {
            core::array::from_fn(|i| if i < starts { START } else { 0 })
        };
        assert!(!super::suspect(&flags(20), true, 361));
        assert!(super::suspect(&flags(21), true, 361));
        assert!(!super::suspect(&flags(20), true, 360));
        assert!(super::suspect(&flags(0), false, 361));
    }

    /// An offset is applied when its χ² is above [`SweepOffset::CHI2_SIGNIFICANT`] and it
    /// moves some point by more than [`SweepOffset::MIN_SHIFT_MM`] (the module's rule): at
    /// either bound exactly it is not, one f32 step above both it is.
    #[test]
    fn an_offset_is_applied_only_above_both_bounds() {
        let at = |chi2: f32, max_shift: f32| SweepOffset {
            dx: 0.5,
            dy: 0.0,
            dtheta: 0.0,
            sd: [0.1; 3],
            sigma: 2.0,
            chi2,
            rows: 64,
            max_shift,
        };
        let up = |x: f32| f32::from_bits(x.to_bits() + 1);
        let (chi2, shift) = (SweepOffset::CHI2_SIGNIFICANT, SweepOffset::MIN_SHIFT_MM);
        assert!(at(up(chi2), up(shift)).is_significant());
        assert!(!at(up(chi2), shift).is_significant());
        assert!(!at(chi2, up(shift)).is_significant());
        assert!(!at(100.0, 0.5).is_significant());
        assert!(!at(10.0, 30.0).is_significant());
    }

    /// Each moved sweep's standard errors over the sweeps, squared and summed; sweeps not
    /// moved add nothing.
    #[test]
    fn the_offsets_variance_is_their_share_of_each_sweeps() {
        let moved = |sd: [f32; 3]| {
            Some(SweepOffset {
                dx: 8.0,
                dy: 0.0,
                dtheta: 0.006,
                sd,
                sigma: 5.0,
                chi2: 100.0,
                rows: 64,
                max_shift: 30.0,
            })
        };
        let two = Offsets {
            sweeps: 2,
            of: [moved([2.0, 4.0, 1.0 / 1024.0]), None, None],
        };
        assert_eq!(two.variance(), [1.0, 4.0, 1.0 / 4_194_304.0]);
        let four = Offsets {
            sweeps: 4,
            of: [moved([4.0, 8.0, 1.0 / 256.0]), None, moved([8.0, 4.0, 0.0])],
        };
        assert_eq!(four.variance(), [5.0, 5.0, 1.0 / 1_048_576.0]);
        assert_eq!(Offsets::default().variance(), [0.0; 3]);
    }

    /// The offsets that moved interleaved sweeps: ρ gets n·(x, y)'s variance, α the turn's; a
    /// circle's centre c gets (x, y)'s and the turn's lever (−c_y, c_x); nothing when none moved.
    #[test]
    fn aligned_sweeps_add_the_offsets_variance() {
        let alignment = [4.0f32, 9.0, 1e-6];
        let (alpha, rho) = (0.5f32, 2000.0f32);
        let mut lf = LineFeature {
            first: 0,
            last: 9,
            points: 10,
            alpha,
            rho,
            var_alpha: 1e-6,
            var_rho: 4.0,
            cov_alpha_rho: 1e-4,
            start: Point::new(1000.0, 0.0),
            end: Point::new(0.0, 2000.0),
        };
        let plain = lf;
        aligned_line(&mut lf, [0.0; 3]);
        assert_eq!(lf, plain);
        // Each term alone counts.
        for one in [[4.0, 0.0, 0.0], [0.0, 9.0, 0.0], [0.0, 0.0, 1e-6]] {
            let mut l = plain;
            aligned_line(&mut l, one);
            assert_ne!(
                (l.var_alpha, l.var_rho),
                (plain.var_alpha, plain.var_rho),
                "{one:?}"
            );
        }
        aligned_line(&mut lf, alignment);
        let (c, s) = (f64::from(alpha).cos(), f64::from(alpha).sin());
        let want_rho = 4.0 + c * c * 4.0 + s * s * 9.0;
        assert!(
            (f64::from(lf.var_rho) - want_rho).abs() < 1e-4,
            "{}",
            lf.var_rho
        );
        assert!((f64::from(lf.var_alpha) - 2e-6).abs() < 1e-12);
        assert_eq!(lf.cov_alpha_rho, 1e-4);

        let mut cf = CircleFeature {
            first: 0,
            last: 9,
            points: 10,
            center: Point::new(1000.0, -2000.0),
            radius: 150.0,
            cov: [[1.0, 0.5, 0.0], [0.5, 2.0, 0.0], [0.0, 0.0, 3.0]],
            start_angle: 0.0,
            end_angle: 1.0,
        };
        aligned_circle(&mut cf, alignment);
        // dθ moves the centre by dθ (2000, 1000).
        let want = [[1.0 + 4.0 + 4.0, 0.5 + 2.0], [0.5 + 2.0, 2.0 + 9.0 + 1.0]];
        for (i, row) in want.iter().enumerate() {
            for (j, v) in row.iter().enumerate() {
                assert!((cf.cov[i][j] - v).abs() < 1e-4, "{i}{j}: {:?}", cf.cov);
            }
        }
        assert_eq!(cf.cov[2], [0.0, 0.0, 3.0]);
    }
}
