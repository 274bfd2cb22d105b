//! The beam table: what depends only on the scan geometry, computed when it changes and kept
//! across scans (beam directions, the spreads of runs of beams, the largest gap within one
//! surface).

use crate::fit::line::{fill_spreads, BeamSpan};
use crate::geometry::Point;
use crate::math;
use crate::scan::ScanGeometry;

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
    let (step, lam) = (math::abs(g.angle_step), 10.0f32.to_radians());
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
