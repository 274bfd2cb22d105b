//! One extraction's work state, whatever the extractor's capacity: the beam table, the scan's
//! points, ranges and flags, and the statistics. Every step is a function of it, compiled
//! once in this crate.

use crate::beams::Beams;
use crate::flags::VALID;
use crate::geometry::Point;
use crate::motion::Motion;
use crate::output::Stats;
use crate::predict::{Prediction, WindowLine};
#[cfg(test)]
use crate::{config::Config, preprocess, scan::Scan};

/// The work state of one extraction. `points`, `ranges` and `flags` hold one slot per reading.
pub(crate) struct Pass<'a> {
    /// The beam table of the scan's geometry.
    pub beams: Beams<'a>,
    /// Points (after correction and de-skew); invalid readings are [`Point::INVALID`].
    pub points: &'a [Point],
    /// Corrected measured range of each valid point, mm (its distance from the scanner).
    pub ranges: &'a [f32],
    /// Flags of each point (see [`crate::flags`]).
    pub flags: &'a mut [u8],
    /// Motion during the scan, when de-skewing.
    pub motion: Option<Motion>,
    /// What the extraction did so far (the steps count into it).
    pub stats: &'a mut Stats,
}

impl<'a> Pass<'a> {
    /// The work state of `scan` over the beam table `beams` and the slots (points, ranges,
    /// flags) of its readings, which it fills (§2: range correction, de-skew).
    #[cfg(test)]
    pub(crate) fn load(
        beams: Beams<'a>,
        (points, ranges, flags): (&'a mut [Point], &'a mut [f32], &'a mut [u8]),
        scan: &Scan<'_>,
        config: &Config,
        stats: &'a mut Stats,
    ) -> Self {
        let motion = scan.deskewing();
        let slots = (&mut *points, &mut *ranges, &mut *flags);
        preprocess::load(slots, &beams, motion, scan, config, stats);
        Self::over(beams, (points, ranges, flags), motion, stats)
    }

    /// The work state over slots already loaded.
    pub(crate) fn over(
        beams: Beams<'a>,
        (points, ranges, flags): (&'a [Point], &'a [f32], &'a mut [u8]),
        motion: Option<Motion>,
        stats: &'a mut Stats,
    ) -> Self {
        Self {
            beams,
            points,
            ranges,
            flags,
            motion,
            stats,
        }
    }

    /// Number of readings.
    pub(crate) fn len(&self) -> usize {
        self.flags.len()
    }

    pub(crate) fn flag(&self, i: usize) -> u8 {
        self.flags.get(i).copied().unwrap_or(0)
    }

    pub(crate) fn set(&mut self, i: usize, bit: u8) {
        if let Some(f) = self.flags.get_mut(i) {
            *f |= bit;
        }
    }

    pub(crate) fn clear(&mut self, i: usize, bit: u8) {
        if let Some(f) = self.flags.get_mut(i) {
            *f &= !bit;
        }
    }

    pub(crate) fn valid(&self, i: usize) -> bool {
        self.flag(i) & VALID != 0
    }

    pub(crate) fn point(&self, i: usize) -> Point {
        point_at(self.points, i)
    }

    /// Scanner position when beam `i` was taken (origin unless de-skewing).
    pub(crate) fn origin(&self, i: usize) -> Point {
        match self.motion {
            Some(m) => moved_origin(m, i),
            None => Point::new(0.0, 0.0),
        }
    }

    pub(crate) fn range(&self, i: usize) -> f32 {
        self.ranges.get(i).copied().unwrap_or(f32::NAN)
    }

    /// Predicts point `k` from points `from..to` (all valid).
    pub(crate) fn predict(&mut self, from: usize, to: usize, k: usize) -> Option<Prediction> {
        let line = self.window_line(from, to, k)?;
        self.predict_with(&line, k)
    }

    /// Predicts point `k` from the points `from..k` right before it (all valid): the window
    /// and the point with one bounds check.
    #[inline(never)]
    pub(crate) fn predict_next(&mut self, from: usize, k: usize) -> Option<Prediction> {
        self.stats.predictions += 1;
        let (p, window) = self.points.get(from..=k)?.split_last()?;
        let r = *self.ranges.get(k)?;
        let o = self.origin(k);
        match &WindowLine::fit(window, o) {
            Some(line) => predict_point(line, o, *p, r),
            None => None,
        }
    }

    /// The line of points `from..to`, seen from the origin of beam `k` (one prediction).
    pub(crate) fn window_line(&mut self, from: usize, to: usize, k: usize) -> Option<WindowLine> {
        self.stats.predictions += 1;
        WindowLine::fit(self.points.get(from..to)?, self.origin(k))
    }

    /// Predicts point `k` from a window's line.
    #[inline(never)]
    pub(crate) fn predict_with(&self, line: &WindowLine, k: usize) -> Option<Prediction> {
        let (Some(&p), Some(&r)) = (self.points.get(k), self.ranges.get(k)) else {
            return None;
        };
        predict_point(line, self.origin(k), p, r)
    }
}

/// Predicts the point `p` at measured range `r` seen from `origin` by `line` (`None` unless
/// `r > 0`).
#[inline(never)]
fn predict_point(line: &WindowLine, origin: Point, p: Point, r: f32) -> Option<Prediction> {
    if !(r > 0.0) {
        return None;
    }
    Some(line.predict(origin, p.x - origin.x, p.y - origin.y, r))
}

/// [`Pass::origin`] when de-skewing (not inlined: one copy for every caller).
#[inline(never)]
fn moved_origin(m: Motion, i: usize) -> Point {
    m.pose(i).origin
}

/// Point `i` of `points` ([`Point::INVALID`] past their end).
pub(crate) fn point_at(points: &[Point], i: usize) -> Point {
    points.get(i).copied().unwrap_or(Point::INVALID)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::extractor::Extractor;
    use crate::motion::BeamTiming;
    use crate::output::Stats;
    use crate::scan::ScanGeometry;
    use core::f32::consts::{FRAC_PI_2, FRAC_PI_4};

    /// Runs `f` on a pass over `points` and `ranges` (an LMS200 scan, 180° at 0.5°; valid where
    /// the range is finite), taken with `motion`.
    fn with_pass(
        (points, ranges): (&[Point; 361], &[f32; 361]),
        motion: Option<Motion>,
        f: impl FnOnce(&mut Pass<'_>),
    ) {
        let g = ScanGeometry::LMS200_180_050;
        let mut flags: [u8; 361] = core::array::from_fn(|i| match ranges[i].is_finite() {
            true => VALID,
            false => 0,
        });
        let mut ex = Extractor::<361, 8>::new();
        let loading = [1000.0f32; 361];
        ex.with_pass(
            &Scan::from_mm(g, &loading),
            &Config::default(),
            |loaded, _| {
                let mut stats = Stats::default();
                f(&mut Pass::over(
                    loaded.beams,
                    (points, ranges, &mut flags),
                    motion,
                    &mut stats,
                ));
            },
        );
    }

    /// On the move (3 m/s, 2 rad/s, two sweeps one mirror turn apart: beams up to 40 mm and
    /// 27 mrad apart in pose), a point of a wall (ahead, beside, at 45°; cast from its own
    /// beam's pose) is predicted on the wall from the ten before it, each seen from the pose of
    /// the beam predicted: error below 0.05 mm.
    #[test]
    fn a_point_of_a_wall_is_predicted_on_it_from_its_own_pose() {
        let g = ScanGeometry::LMS200_180_050;
        let motion = Motion {
            v: 3000.0,
            omega: 2.0,
            timing: BeamTiming::lms2xx(0.5),
        };
        // Walls x cos α + y sin α = ρ: ahead, to the left, and at 45° to the right.
        for (alpha, rho) in [
            (0.0f32, 2500.0f32),
            (FRAC_PI_2, 2000.0),
            (-FRAC_PI_4, 1800.0),
        ] {
            let (sa, ca) = crate::math::sin_cos(alpha);
            let (mut points, mut ranges) = ([Point::INVALID; 361], [f32::NAN; 361]);
            for i in 0..361 {
                let pose = motion.pose(i);
                let (s, c) = crate::math::sin_cos(g.bearing(i) + pose.theta);
                // The beam from the pose meets the wall at r = (ρ − o·n) / (d·n).
                let dn = c * ca + s * sa;
                let r = (rho - pose.origin.x * ca - pose.origin.y * sa) / dn;
                if dn > 0.3 {
                    points[i] = Point::new(pose.origin.x + r * c, pose.origin.y + r * s);
                    ranges[i] = r;
                }
            }
            with_pass((&points, &ranges), Some(motion), |pass| {
                let mut tested = 0;
                for k in 10..361 {
                    if (k - 10..=k).all(|i| pass.valid(i)) {
                        let Some(p) = pass.predict(k - 10, k, k) else {
                            panic!("wall {alpha}, beam {k}: no prediction")
                        };
                        assert!(
                            p.error < 0.05,
                            "wall {alpha}, beam {k}: error {} mm",
                            p.error
                        );
                        tested += 1;
                    }
                }
                assert!(tested > 100, "wall {alpha}: {tested}");
            });
        }
    }
}
