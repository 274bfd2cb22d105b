//! The beam table: what depends only on the scan geometry, computed when it changes and kept
//! across scans (beam directions, the spreads of runs of beams, the largest gap within one
//! surface).

use crate::fit::line::{fill_spreads, BeamSpan};
use crate::geometry::Point;
use crate::math;
use crate::scan::ScanGeometry;

/// Smallest incidence at which consecutive points of one surface are not a jump (10°, Borges
/// & Aldon's λ), rad.
pub(crate) const MIN_INCIDENCE: f32 = 0.174_532_93;

/// The beam table of up to `N` beams.
pub(crate) struct BeamTable<const N: usize> {
    /// Beam directions (cos, sin).
    dirs: [Point; N],
    /// The [`BeamSpan::spread`] of `k + 1` beams at `k`.
    spreads: [f32; N],
    /// Everything else of the table.
    shape: Shape,
}

/// The table's values that do not depend on `N`.
#[derive(Clone, Copy)]
struct Shape {
    /// Direction of half a step (cos, sin).
    half_step: Point,
    /// Largest gap between consecutive points of one surface per mm of range.
    gap_factor: f32,
    /// The geometry of the table (start angle and step, as bits; a step of 0, never valid,
    /// for none yet).
    key: (u32, u32),
}

impl<const N: usize> BeamTable<N> {
    /// An empty table (all zero bytes: a `static` extractor goes to .bss).
    pub(crate) const fn new() -> Self {
        Self {
            dirs: [Point::new(0.0, 0.0); N],
            spreads: [0.0; N],
            shape: Shape {
                half_step: Point::new(0.0, 0.0),
                gap_factor: 0.0,
                key: (0, 0),
            },
        }
    }

    /// The table of `g` (a valid geometry), filled unless it already is.
    pub(crate) fn of(&mut self, g: ScanGeometry) -> Beams<'_> {
        if self.shape.key != key(g) {
            self.shape = fill(&mut self.dirs, &mut self.spreads, g);
        }
        Beams {
            dirs: &self.dirs,
            spreads: &self.spreads,
            half_step: self.shape.half_step,
            gap_factor: self.shape.gap_factor,
        }
    }
}

fn key(g: ScanGeometry) -> (u32, u32) {
    (g.start_angle.to_bits(), g.angle_step.to_bits())
}

/// Fills `dirs` and `spreads` for `g`: an exact sine and cosine every 64 beams and a rotation
/// recurrence in between (error < 1e-5 rad: 0.1 mm at 8 m).
fn fill(dirs: &mut [Point], spreads: &mut [f32], g: ScanGeometry) -> Shape {
    const EXACT_EVERY: usize = 64;
    let (rs, rc) = math::sin_cos(g.angle_step);
    let (mut s, mut c) = (0.0f32, 1.0f32);
    for (i, d) in dirs.iter_mut().enumerate() {
        if i % EXACT_EVERY == 0 {
            (s, c) = math::sin_cos(g.bearing(i));
        } else {
            (s, c) = (s * rc + c * rs, c * rc - s * rs);
        }
        *d = Point::new(c, s);
    }
    fill_spreads(spreads, g.angle_step);
    let (s, c) = math::sin_cos(0.5 * g.angle_step);
    // Largest gap between consecutive points of one surface: seen at down to 10° incidence
    // (Borges & Aldon's λ); the default mode adds the noise of two readings.
    let (step, lam) = (math::abs(g.angle_step), MIN_INCIDENCE);
    let below = math::sin(lam - step);
    Shape {
        half_step: Point::new(c, s),
        gap_factor: math::sin(step) / if below > 1e-3 { below } else { 1e-3 },
        key: key(g),
    }
}

/// A filled beam table, whatever its capacity.
#[derive(Clone, Copy)]
pub(crate) struct Beams<'a> {
    /// Beam directions (cos, sin).
    pub dirs: &'a [Point],
    /// The [`BeamSpan::spread`] of `k + 1` beams at `k`.
    spreads: &'a [f32],
    /// Direction of half a step (cos, sin).
    half_step: Point,
    /// Largest gap between consecutive points of one surface per mm of range.
    pub gap_factor: f32,
}

impl Beams<'_> {
    /// The beams `s..=e` (a segment's: all valid, consecutive).
    pub(crate) fn span(&self, s: usize, e: usize) -> Option<BeamSpan> {
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
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(a: f64) -> (f64, f64) {
        (a.cos(), a.sin())
    }

    fn near(p: Point, (x, y): (f64, f64), tol: f64) -> bool {
        (f64::from(p.x) - x).abs() < tol && (f64::from(p.y) - y).abs() < tol
    }

    /// Every beam's direction within 1e-5 of its bearing's (f64), exactly `sin_cos` of it
    /// every 64 beams where the recurrence restarts; the largest gap per mm of range is
    /// sin δ / sin(10° − δ) (Borges & Aldon's λ = 10°).
    #[test]
    fn the_table_holds_each_beams_direction_and_the_gap_factor() {
        for g in [
            ScanGeometry::LMS200_180_050,
            ScanGeometry::lms200(100.0, 0.25),
            ScanGeometry::lms200(180.0, 1.0),
        ] {
            let mut table = BeamTable::<401>::new();
            let b = table.of(g);
            let step = f64::from(g.angle_step);
            for (i, &d) in b.dirs.iter().enumerate() {
                let a = f64::from(g.start_angle) + step * i as f64;
                assert!(near(d, dir(a), 1e-5), "beam {i}: {d:?}");
                if i % 64 == 0 {
                    let (s, c) = math::sin_cos(g.bearing(i));
                    assert_eq!((d.x, d.y), (c, s), "beam {i}");
                }
            }
            let lam = 10f64.to_radians();
            let want = step.sin() / (lam - step).sin();
            let got = f64::from(b.gap_factor);
            assert!((got - want).abs() < 1e-6 * want, "{got} vs {want}");
        }
    }

    /// A span's middle direction is its middle beam's (odd count) or halfway between the two
    /// middle beams (even count); its ends are its first and last beams' and its spread the
    /// table's for its count; an empty span is none.
    #[test]
    fn a_span_of_beams_has_its_middle_ends_and_spread() {
        let g = ScanGeometry::LMS200_180_050;
        let mut table = BeamTable::<361>::new();
        let b = table.of(g);
        let step = f64::from(g.angle_step);
        let bearing = |i: f64| f64::from(g.start_angle) + step * i;
        for (s, e) in [(0, 0), (10, 12), (10, 13), (100, 140), (100, 141), (3, 360)] {
            let span = b.span(s, e).unwrap();
            assert_eq!(span.count, e - s + 1);
            let mid = bearing(0.5 * (s + e) as f64);
            assert!(near(span.mid, dir(mid), 2e-6), "{s}..={e}: {:?}", span.mid);
            assert!(near(span.ends[0], dir(bearing(s as f64)), 1e-5));
            assert!(near(span.ends[1], dir(bearing(e as f64)), 1e-5));
            // E = Σ_j 2 sin²(jδ) over the offsets j from the middle.
            let want: f64 = (s..=e)
                .map(|i| 2.0 * ((i as f64 - 0.5 * (s + e) as f64) * step).sin().powi(2))
                .sum();
            let got = f64::from(span.spread);
            assert!(
                (got - want).abs() < 1e-5 * want.max(1e-3),
                "{got} vs {want}"
            );
        }
        assert!(b.span(5, 4).is_none());
        assert!(b.span(5, 361).is_none());
    }
}
