//! Scan input for any scanner: geometry, ranges (raw LMS codes or mm), optional motion.

use crate::geometry::Point;
use crate::math;
use crate::motion::Motion;

/// Where the beams point and how far the scanner sees.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub struct ScanGeometry {
    /// Bearing of beam 0, rad (x forward, y left, counter-clockwise positive).
    pub start_angle: f32,
    /// Bearing increment from one beam to the next, rad (may be negative).
    pub angle_step: f32,
    /// Maximum range, mm: readings beyond it are no return.
    pub r_max: f32,
}

impl ScanGeometry {
    /// A geometry from beam 0's bearing (rad), the bearing step (rad) and the maximum range (mm).
    ///
    /// ```
    /// use pfe_core::ScanGeometry;
    /// let g = ScanGeometry::new(-1.0, 0.01, 4000.0);
    /// assert!(g.is_valid());
    /// assert_eq!(g.bearing(100), -1.0 + 0.01 * 100.0);
    /// ```
    pub const fn new(start_angle: f32, angle_step: f32, r_max: f32) -> Self {
        Self {
            start_angle,
            angle_step,
            r_max,
        }
    }

    /// The SICK LMS200 in its default variant: 180° at 0.5° (361 beams from −90°), 8 m mode.
    pub const LMS200_180_050: ScanGeometry = ScanGeometry {
        start_angle: -core::f32::consts::FRAC_PI_2,
        angle_step: core::f32::consts::PI / 360.0,
        r_max: 8000.0,
    };

    /// An LMS200 variant (field of view and resolution in degrees), centred on x, 8 m mode.
    pub fn lms200(field_deg: f32, resolution_deg: f32) -> Self {
        let d2r = core::f32::consts::PI / 180.0;
        Self {
            start_angle: -0.5 * field_deg * d2r,
            angle_step: resolution_deg * d2r,
            r_max: 8000.0,
        }
    }

    /// Bearing of beam `i`, rad.
    pub fn bearing(&self, i: usize) -> f32 {
        self.start_angle + self.angle_step * i as f32
    }

    /// True when the geometry can be used.
    pub fn is_valid(&self) -> bool {
        math::all_finite(&[self.start_angle, self.angle_step, self.r_max])
            && self.angle_step != 0.0
            && math::abs(self.angle_step) < 1.0
            && self.r_max > 0.0
    }

    /// The interleaved sweeps an LMS2xx scan of this geometry is made of: 2 at 0.5°, 4 at
    /// 0.25° ([`BeamTiming::lms2xx`](crate::BeamTiming::lms2xx)); 1 at 1° and for a step no
    /// LMS2xx has (more than 1 % from 0.25°, 0.5° and 1°: another scanner's).
    ///
    /// ```
    /// use pfe_core::ScanGeometry;
    /// assert_eq!(ScanGeometry::lms200(180.0, 0.5).lms2xx_sweeps(), 2);
    /// assert_eq!(ScanGeometry::lms200(100.0, 0.25).lms2xx_sweeps(), 4);
    /// assert_eq!(ScanGeometry::lms200(180.0, 1.0).lms2xx_sweeps(), 1);
    /// assert_eq!(ScanGeometry::lms200(240.0, 0.352).lms2xx_sweeps(), 1); // a Hokuyo URG
    /// ```
    pub fn lms2xx_sweeps(&self) -> u8 {
        let deg = math::abs(self.angle_step).to_degrees();
        let lms = [0.25f32, 0.5, 1.0]
            .iter()
            .any(|r| math::abs(deg / r - 1.0) < 0.01);
        if lms {
            crate::motion::BeamTiming::lms2xx(deg).sweeps
        } else {
            1
        }
    }
}

/// Range readings of one scan.
#[derive(Clone, Copy, Debug)]
pub enum Ranges<'a> {
    /// Ranges in mm. NaN, ±inf, ≤ 0 and > r_max are no return.
    Mm(&'a [f32]),
    /// Raw LMS range codes (already masked to the measuring mode's range bits).
    Raw {
        /// The codes.
        values: &'a [u16],
        /// mm per code unit: 1.0 in mm mode, 10.0 in cm mode.
        mm_per_unit: f32,
        /// Largest valid code; above it are the reserved codes (8182 in the 8 m / 80 m modes).
        max_valid: u16,
    },
}

impl Ranges<'_> {
    /// Number of readings.
    pub fn len(&self) -> usize {
        match self {
            Ranges::Mm(r) => r.len(),
            Ranges::Raw { values, .. } => values.len(),
        }
    }

    /// True when there is no reading.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Reading `i` in mm, or `None` when it is no return (or `i` is out of range).
    pub fn get_mm(&self, i: usize, r_max: f32) -> Option<f32> {
        let r = match self {
            Ranges::Mm(r) => *r.get(i)?,
            Ranges::Raw {
                values,
                mm_per_unit,
                max_valid,
            } => code_mm(*values.get(i)?, *mm_per_unit, *max_valid)?,
        };
        valid_mm(r, r_max)
    }

    /// The grid the readings (the returns within `r_max`) lie on, mm: the coarsest of 100, 50,
    /// 25, 20, 10, 5, 2 and 1 mm that divides every one of them, when all are whole mm (to
    /// 0.05 mm: logs in m read through f32) and at least 20 of them, of at least 5 distinct
    /// values, tell; otherwise 0 (unknown). What [`Scan::lms2xx`] takes as its
    /// [`quantum`](Scan::quantum), and the host's formats for every recording.
    ///
    /// ```
    /// use pfe_core::Ranges;
    /// let grid: Vec<f32> = (0..181).map(|i| 1000.0 + 50.0 * (i % 7) as f32).collect();
    /// assert_eq!(Ranges::Mm(&grid).grid(80_000.0), 50.0);
    /// let codes: Vec<u16> = (0..361).map(|i| 1000 + i).collect();
    /// let raw = Ranges::Raw { values: &codes, mm_per_unit: 10.0, max_valid: 8182 };
    /// assert_eq!(raw.grid(81_820.0), 10.0);
    /// let fine: Vec<f32> = (0..181).map(|i| 2000.0 + 0.37 * i as f32).collect();
    /// assert_eq!(Ranges::Mm(&fine).grid(80_000.0), 0.0);
    /// ```
    pub fn grid(&self, r_max: f32) -> f32 {
        let mut tally = Tally::new();
        match *self {
            Ranges::Raw {
                values,
                mm_per_unit,
                max_valid,
            } if (1.0..=100.0).contains(&mm_per_unit)
                && (mm_per_unit as u32) as f32 == mm_per_unit =>
            {
                // Whole mm per code: every return is whole, so the first 20 of 5 distinct
                // values on a grid of 1 mm settle it.
                let top = max_code(mm_per_unit, max_valid, r_max);
                let unit = mm_per_unit as u32;
                for &v in values {
                    if v != 0 && v <= top {
                        tally.add(u32::from(v) * unit);
                        if tally.settled() {
                            break;
                        }
                    }
                }
            }
            _ => {
                for i in 0..self.len() {
                    let Some(r) = self.get_mm(i, r_max) else {
                        continue;
                    };
                    let m = math::round(r);
                    if math::abs(r - m) > 0.05 || m > u32::MAX as f32 {
                        return 0.0;
                    }
                    tally.add(m as u32);
                }
            }
        }
        tally.grid()
    }
}

/// Grids readings may lie on, mm, coarsest first: a scanner's or a log's unit (1 mm, 1 cm)
/// and coarser roundings seen in published logs (whole scans of three shared CARMEN logs lie
/// on 50 mm).
const GRIDS_MM: [u32; 8] = [100, 50, 25, 20, 10, 5, 2, 1];

/// Whole-mm readings counted for [`Ranges::grid`]: how many, up to 5 distinct values, and the
/// greatest common divisor of all (a grid divides every reading when it divides that).
struct Tally {
    count: usize,
    distinct: [u32; 5],
    kinds: usize,
    gcd: u32,
}

impl Tally {
    const fn new() -> Self {
        Self {
            count: 0,
            distinct: [0; 5],
            kinds: 0,
            gcd: 0,
        }
    }

    #[inline]
    fn add(&mut self, m: u32) {
        self.count += 1;
        if self.kinds < self.distinct.len() {
            let seen = self.distinct.get(..self.kinds).unwrap_or(&[]);
            if !seen.contains(&m) {
                if let Some(slot) = self.distinct.get_mut(self.kinds) {
                    *slot = m;
                }
                self.kinds += 1;
            }
        }
        if self.gcd != 1 {
            let (mut a, mut b) = (self.gcd, m);
            while b != 0 {
                (a, b) = (b, a % b);
            }
            self.gcd = a;
        }
    }

    /// True when no further reading can change the grid: 1 mm, told by enough readings.
    fn settled(&self) -> bool {
        self.gcd == 1 && self.count >= 20 && self.kinds >= 5
    }

    fn grid(&self) -> f32 {
        if self.count < 20 || self.kinds < 5 {
            return 0.0;
        }
        GRIDS_MM
            .iter()
            .find(|&&q| self.gcd % q == 0)
            .map_or(0.0, |&q| q as f32)
    }
}

/// A raw code in mm, `None` for 0 and the reserved codes above `max_valid`.
#[inline]
pub(crate) fn code_mm(v: u16, mm_per_unit: f32, max_valid: u16) -> Option<f32> {
    (v != 0 && v <= max_valid).then(|| f32::from(v) * mm_per_unit)
}

/// The largest code `v ≤ max_valid` whose range `v · mm_per_unit` is at most `r_max` (so that
/// codes `1 ..= max_code` are exactly the returns); 0 when there is none.
pub(crate) fn max_code(mm_per_unit: f32, max_valid: u16, r_max: f32) -> u16 {
    if !(mm_per_unit > 0.0) || !math::finite(mm_per_unit) {
        return 0;
    }
    let fits = |v: u16| f32::from(v) * mm_per_unit <= r_max;
    // The quotient is within a code of the answer; the two loops make it exact.
    let q = r_max / mm_per_unit;
    let mut v = if q >= f32::from(max_valid) {
        max_valid
    } else if q >= 0.0 {
        q as u16
    } else {
        0
    };
    while v > 0 && !fits(v) {
        v -= 1;
    }
    while v < max_valid && fits(v + 1) {
        v += 1;
    }
    v
}

/// `r` when it is a return: finite, positive and at most `r_max`.
#[inline]
pub(crate) fn valid_mm(r: f32, r_max: f32) -> Option<f32> {
    (math::finite(r) && r > 0.0 && r <= r_max).then_some(r)
}

/// The largest valid LMS range code in the 8 m / 80 m measuring modes; 8183 and above are
/// reserved (no return, dazzle, overflow, …).
pub const LMS_MAX_VALID_8M: u16 = 8182;

/// One scan: geometry, readings and, optionally, the robot's motion during the scan.
#[derive(Clone, Copy, Debug)]
pub struct Scan<'a> {
    /// Beam geometry.
    pub geometry: ScanGeometry,
    /// Readings.
    pub ranges: Ranges<'a>,
    /// Constant-velocity motion during the scan, for de-skewing.
    pub motion: Option<Motion>,
    /// Number of interleaved sweeps (1: none; 0 counts as 1): beam `i` is in sweep
    /// `i mod sweeps`. Without [`motion`](Self::motion), the sweeps' offset against sweep 0 is
    /// estimated from the scan and removed (default mode, up to 4 sweeps; a scan declared with
    /// more is extracted as it is); with it, its timing's sweeps rule.
    pub sweeps: u8,
    /// Resolution of the readings, mm (0: unknown, or finer than matters). Readings rounded to
    /// a grid of q mm carry an error of variance q²/12. Range noise much finer than q leaves
    /// it a function of the true range, which neighbouring beams on one surface share (a fit
    /// cannot see it in its scatter); noise of q/2 or more dithers it into independent noise
    /// (Widrow). With [`Config::scrutiny`](crate::Config::scrutiny) the shared part
    /// ([`Self::shared_rounding`]) counts as systematic, beside
    /// [`Config::sigma_sys`](crate::Config::sigma_sys).
    pub quantum: f32,
}

impl<'a> Scan<'a> {
    /// A scan of ranges in mm.
    ///
    /// ```
    /// use pfe_core::{Scan, ScanGeometry};
    /// let ranges = [1000.0_f32; 361];
    /// let scan = Scan::from_mm(ScanGeometry::LMS200_180_050, &ranges);
    /// assert_eq!(scan.ranges.len(), 361);
    /// ```
    pub fn from_mm(geometry: ScanGeometry, ranges: &'a [f32]) -> Self {
        Self {
            geometry,
            ranges: Ranges::Mm(ranges),
            motion: None,
            sweeps: 1,
            quantum: 0.0,
        }
    }

    /// A scan of raw LMS codes in the 8 m / 80 m modes (`mm_per_unit` 1.0 for mm, 10.0 for cm,
    /// also its [`quantum`](Self::quantum)).
    ///
    /// ```
    /// use pfe_core::{Scan, ScanGeometry};
    /// let codes = [250_u16; 181];
    /// let scan = Scan::from_lms(ScanGeometry::lms200(180.0, 1.0), &codes, 10.0);
    /// assert_eq!(scan.point(90).map(|p| p.norm()), Some(2500.0));
    /// assert_eq!(scan.quantum, 10.0);
    /// ```
    pub fn from_lms(geometry: ScanGeometry, values: &'a [u16], mm_per_unit: f32) -> Self {
        Self {
            geometry,
            ranges: Ranges::Raw {
                values,
                mm_per_unit,
                max_valid: LMS_MAX_VALID_8M,
            },
            motion: None,
            sweeps: 1,
            quantum: mm_per_unit,
        }
    }

    /// A scan from a SICK LMS2xx as `pfe extract --format lms200` and the firmware build it:
    /// its interleaved sweeps from the geometry's step ([`ScanGeometry::lms2xx_sweeps`]: 2 at
    /// 0.5°, 4 at 0.25°) and its [`quantum`](Self::quantum) the grid its readings lie on
    /// ([`Ranges::grid`]), no motion.
    ///
    /// ```
    /// use pfe_core::{Ranges, Scan, ScanGeometry};
    /// let codes: Vec<u16> = (0..361).map(|i| 2000 + 10 * (i % 9)).collect();
    /// let ranges = Ranges::Raw { values: &codes, mm_per_unit: 1.0, max_valid: 8182 };
    /// let scan = Scan::lms2xx(ScanGeometry::LMS200_180_050, ranges);
    /// assert_eq!((scan.sweeps, scan.quantum), (2, 10.0));
    /// ```
    pub fn lms2xx(geometry: ScanGeometry, ranges: Ranges<'a>) -> Self {
        Self {
            geometry,
            ranges,
            motion: None,
            sweeps: geometry.lms2xx_sweeps(),
            quantum: ranges.grid(geometry.r_max),
        }
    }

    /// The same scan, its readings on a grid of `quantum` mm (see [`Self::quantum`]).
    ///
    /// ```
    /// use pfe_core::{Scan, ScanGeometry};
    /// let ranges = [2050.0_f32; 181];
    /// let scan = Scan::from_mm(ScanGeometry::lms200(180.0, 1.0), &ranges).with_quantum(50.0);
    /// // Noise of σ_r = 5 mm leaves most of a 50 mm rounding shared by neighbouring beams,
    /// // noise of 50 mm none of it.
    /// assert!((scan.shared_rounding(5.0) / (2500.0 / 12.0) - 0.821).abs() < 0.002);
    /// assert!(scan.shared_rounding(50.0) < 1e-6);
    /// ```
    pub fn with_quantum(mut self, quantum: f32) -> Self {
        self.quantum = quantum;
        self
    }

    /// The part of the readings' rounding variance q²/12 (mm²) that neighbouring beams on one
    /// surface share, under range noise `sigma_r` (mm): q²/12 · exp(−2π² σ_r²/q²), the
    /// amplitude with which the rounding error of a noisy reading still follows the true range
    /// (the first harmonic of its dependence, Widrow and Kollár, *Quantization Noise*, 2008).
    /// 0 when [`Self::quantum`] or `sigma_r` is not a finite number ≥ 0, or q is 0.
    pub fn shared_rounding(&self, sigma_r: f32) -> f32 {
        let q = self.quantum;
        let var = q * q / 12.0;
        if !(q > 0.0 && crate::math::finite(var) && sigma_r >= 0.0) {
            return 0.0;
        }
        let x = 2.0 * core::f32::consts::PI * core::f32::consts::PI * sigma_r * sigma_r / (q * q);
        var * exp_neg(x)
    }

    /// The same scan, de-skewed for `motion`.
    pub fn with_motion(mut self, motion: Motion) -> Self {
        self.motion = Some(motion);
        self
    }

    /// The same scan, made of `sweeps` interleaved sweeps (an LMS2xx at 0.5°: 2, at 0.25°: 4).
    ///
    /// ```
    /// use pfe_core::{Scan, ScanGeometry};
    /// let ranges = [1000.0_f32; 361];
    /// let scan = Scan::from_mm(ScanGeometry::LMS200_180_050, &ranges).with_sweeps(2);
    /// assert_eq!(scan.sweep_count(), 2);
    /// ```
    pub fn with_sweeps(mut self, sweeps: u8) -> Self {
        self.sweeps = sweeps;
        self
    }

    /// The motion the extraction de-skews with: [`Self::motion`] when valid and moving
    /// (standing still, de-skewing would change nothing: the scan is extracted as without
    /// odometry).
    pub(crate) fn deskewing(&self) -> Option<Motion> {
        self.motion.filter(|m| m.is_valid() && m.moves())
    }

    /// Number of interleaved sweeps (at least 1): the motion's timing's when there is one.
    pub fn sweep_count(&self) -> usize {
        match self.motion {
            Some(m) => m.timing.sweep_count(),
            None => usize::from(self.sweeps.max(1)),
        }
    }

    /// Cartesian point of beam `i` (without correction or de-skew), if valid.
    pub fn point(&self, i: usize) -> Option<Point> {
        let r = self.ranges.get_mm(i, self.geometry.r_max)?;
        Some(Point::from_polar(r, self.geometry.bearing(i)))
    }
}

/// e^(−x) for x ≥ 0 as (1 + x/4096)^(−4096): above it by x²/8192 of it (0.2 % up to x = 3,
/// 7 % at x = 24, where e^(−x) < 10⁻¹⁰), 0 from x = 24 on; NaN and +∞ give 0.
fn exp_neg(x: f32) -> f32 {
    if !(x < 24.0) {
        return 0.0;
    }
    let mut y = 1.0 / (1.0 + x / 4096.0);
    for _ in 0..12 {
        y *= y;
    }
    y
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;

    /// `exp_neg` against f64's exp.
    #[test]
    fn exp_neg_follows_exp() {
        for i in 0..240 {
            let x = i as f32 * 0.1;
            let want = (-f64::from(x)).exp();
            let got = f64::from(exp_neg(x));
            let tol = want * (0.0005 + f64::from(x * x) / 7000.0);
            assert!((got - want).abs() <= tol, "x {x}: {got} against {want}");
        }
        for x in [f32::NAN, f32::INFINITY, 24.0, 1e30] {
            assert_eq!(exp_neg(x), 0.0, "{x}");
        }
        assert_eq!(exp_neg(0.0), 1.0);
    }

    /// The shared part of the rounding at both ends of Widrow's range, and its refusals.
    #[test]
    fn shared_rounding_fades_with_noise() {
        let r = [1000.0_f32; 10];
        let at = |q: f32, s: f32| {
            Scan::from_mm(ScanGeometry::lms200(180.0, 1.0), &r)
                .with_quantum(q)
                .shared_rounding(s)
        };
        assert_eq!(at(50.0, 0.0), 2500.0 / 12.0);
        // σ_r = q/4: e^(−π²/8) = 0.2912.
        assert!((at(40.0, 10.0) / (1600.0 / 12.0) - 0.2912).abs() < 0.001);
        assert!(at(10.0, 10.0) < 1e-7);
        for (q, s) in [
            (0.0, 1.0),
            (-10.0, 1.0),
            (f32::NAN, 1.0),
            (f32::INFINITY, 1.0),
            (1e30, 1.0),
            (10.0, -1.0),
            (10.0, f32::NAN),
        ] {
            assert_eq!(at(q, s), 0.0, "q {q}, σ {s}");
        }
    }

    /// `Ranges::grid` on raw codes (its whole-unit shortcut included) equals it on the same
    /// readings in mm, for codes on grids of 1 to 100 mm, few or many readings, no returns and
    /// reserved codes among them.
    #[test]
    fn grid_of_codes_is_grid_of_their_mm() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let mut seen = [0usize; 9];
        for case in 0..3000 {
            let n = [5usize, 19, 20, 21, 40, 361, 401][case % 7];
            let step = [1u64, 2, 3, 5, 7, 10, 20, 25, 50, 100][(next() % 10) as usize];
            let kinds = 1 + next() % 9;
            let base = next() % 4000;
            let codes: std::vec::Vec<u16> = (0..n)
                .map(|_| match next() % 20 {
                    0 => 0,
                    1 => 8183 + (next() % 8) as u16,
                    _ => (base + step * (next() % kinds)) as u16,
                })
                .collect();
            for (unit, max_valid, r_max) in [
                (1.0f32, LMS_MAX_VALID_8M, 8182.0f32),
                (10.0, LMS_MAX_VALID_8M, 81_820.0),
                (1.0, LMS_MAX_VALID_8M, 3000.0),
                (0.5, LMS_MAX_VALID_8M, 8000.0),
            ] {
                let raw = Ranges::Raw {
                    values: &codes,
                    mm_per_unit: unit,
                    max_valid,
                };
                let mm: std::vec::Vec<f32> = codes
                    .iter()
                    .map(|&c| {
                        code_mm(c, unit, max_valid)
                            .and_then(|r| valid_mm(r, r_max))
                            .unwrap_or(f32::NAN)
                    })
                    .collect();
                let g = raw.grid(r_max);
                assert_eq!(g, Ranges::Mm(&mm).grid(r_max), "{codes:?} {unit} {r_max}");
                let k = [0.0, 1.0, 2.0, 5.0, 10.0, 20.0, 25.0, 50.0, 100.0]
                    .iter()
                    .position(|&q| q == g);
                if let Some(c) = k.and_then(|k| seen.get_mut(k)) {
                    *c += 1;
                }
            }
        }
        // Every answer came up, unknown included.
        assert!(seen.iter().all(|&c| c > 0), "{seen:?}");
    }

    /// `max_code` against the definition (a code is a return when `code_mm` and `valid_mm`
    /// accept it), for unit sizes and range limits that do and do not divide evenly, and for
    /// limits no range meets (0, negative, NaN: code 0, without a step below it).
    #[test]
    fn max_code_is_the_last_valid_code() {
        let units = [
            1.0f32,
            10.0,
            0.1,
            0.3,
            7.7,
            0.0,
            -1.0,
            f32::NAN,
            f32::INFINITY,
        ];
        let limits = [
            8000.0f32,
            8182.0,
            8183.0,
            80_000.0,
            0.05,
            1.0,
            4.45,
            655_350.0,
            0.0,
            -5.0,
            f32::NAN,
        ];
        for &mm in &units {
            for &r_max in &limits {
                for max_valid in [LMS_MAX_VALID_8M, 100, u16::MAX] {
                    let expected = (1..=max_valid)
                        .rev()
                        .find(|&v| {
                            code_mm(v, mm, max_valid)
                                .and_then(|r| valid_mm(r, r_max))
                                .is_some()
                        })
                        .unwrap_or(0);
                    assert_eq!(
                        max_code(mm, max_valid, r_max),
                        expected,
                        "{mm} {r_max} {max_valid}"
                    );
                }
            }
        }
    }

    /// Range limits exactly at a code's range and one f32 step below it, for 2 000 unit sizes:
    /// where the quotient `r_max / mm` rounds to the wrong side of a code, both of `max_code`'s
    /// correcting walks are needed (against the definition, as above).
    #[test]
    fn max_code_is_exact_where_the_quotient_rounds_past_a_code() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let (mut down, mut up) = (0, 0);
        for _ in 0..2000 {
            let mm = 0.01 + (next() % 2_000_000) as f32 * 1e-5;
            let max_valid = 100 + (next() % 16_000) as u16;
            let v0 = 1 + (next() % u64::from(max_valid - 1)) as u16;
            let at = f32::from(v0) * mm;
            for r_max in [at, f32::from_bits(at.to_bits() - 1)] {
                let expected = (1..=max_valid)
                    .rev()
                    .find(|&v| f32::from(v) * mm <= r_max)
                    .unwrap_or(0);
                assert_eq!(
                    max_code(mm, max_valid, r_max),
                    expected,
                    "{mm} {r_max} {max_valid}"
                );
                let q = (r_max / mm) as u16;
                down += usize::from(q > expected);
                up += usize::from(q < expected);
            }
        }
        // Both walks were needed.
        assert!(down > 10 && up > 10, "{down} {up}");
    }

    /// The grid needs at least 20 readings of at least 5 distinct values: readings on 50 mm
    /// (1 000 to 1 200 mm) of only 4 values, however many, tell nothing (0); a fifth value
    /// tells 50 mm from 20 readings on, not from 19. In mm and as raw codes of 10 mm.
    #[test]
    fn a_grid_needs_five_distinct_readings_and_twenty_in_all() {
        let mm = |n: usize, kinds: usize| -> std::vec::Vec<f32> {
            (0..n).map(|i| 1000.0 + 50.0 * (i % kinds) as f32).collect()
        };
        assert_eq!(Ranges::Mm(&mm(40, 4)).grid(8000.0), 0.0);
        assert_eq!(Ranges::Mm(&mm(361, 4)).grid(8000.0), 0.0);
        assert_eq!(Ranges::Mm(&mm(40, 5)).grid(8000.0), 50.0);
        assert_eq!(Ranges::Mm(&mm(20, 5)).grid(8000.0), 50.0);
        assert_eq!(Ranges::Mm(&mm(19, 5)).grid(8000.0), 0.0);
        let codes = |kinds: usize| -> std::vec::Vec<u16> {
            (0..40).map(|i| 100 + 5 * (i % kinds) as u16).collect()
        };
        let raw = |c: &[u16]| {
            Ranges::Raw {
                values: c,
                mm_per_unit: 10.0,
                max_valid: LMS_MAX_VALID_8M,
            }
            .grid(81_820.0)
        };
        assert_eq!(raw(&codes(4)), 0.0);
        assert_eq!(raw(&codes(5)), 50.0);
    }

    /// Codes of a unit within 1 to 100 mm that is not whole mm: their readings `code · unit`
    /// (here exact in f32) are on the grid that divides them all, or on none when some is not
    /// whole mm. 2.5 mm × even codes 400 + 2k are 1 000 + 5k mm: 5 mm; 2.5 mm × codes 400 + k
    /// include 1 002.5 mm: 0; 1.5 mm × even codes are 600 + 3k mm: 1 mm (3 mm is no grid). The
    /// same as the readings in mm say.
    #[test]
    fn grid_of_codes_of_a_fractional_unit_is_that_of_their_mm() {
        let even: std::vec::Vec<u16> = (0..40).map(|k| 400 + 2 * k).collect();
        let all: std::vec::Vec<u16> = (0..40).map(|k| 400 + k).collect();
        for (codes, unit, want) in [(&even, 2.5f32, 5.0f32), (&all, 2.5, 0.0), (&even, 1.5, 1.0)] {
            let raw = Ranges::Raw {
                values: codes,
                mm_per_unit: unit,
                max_valid: LMS_MAX_VALID_8M,
            };
            let mm: std::vec::Vec<f32> = codes
                .iter()
                .map(|&c| (f64::from(c) * f64::from(unit)) as f32)
                .collect();
            assert_eq!(Ranges::Mm(&mm).grid(20_000.0), want, "{unit} mm, in mm");
            assert_eq!(raw.grid(20_000.0), want, "{unit} mm, as codes");
        }
    }

    /// The sweeps declared, at least one; with odometry, its timing's.
    #[test]
    fn the_sweep_count_is_the_declared_or_the_timings() {
        let ranges = [1000.0f32; 361];
        let scan = Scan::from_mm(ScanGeometry::LMS200_180_050, &ranges);
        assert_eq!(scan.sweep_count(), 1);
        assert_eq!(scan.with_sweeps(0).sweep_count(), 1);
        assert_eq!(scan.with_sweeps(4).sweep_count(), 4);
        let motion = Motion::uniform(100.0, 0.0, 1e-4);
        assert_eq!(scan.with_sweeps(4).with_motion(motion).sweep_count(), 1);
        let m = Motion {
            timing: crate::BeamTiming::lms2xx(0.5),
            ..motion
        };
        assert_eq!(scan.with_motion(m).sweep_count(), 2);
    }
}
