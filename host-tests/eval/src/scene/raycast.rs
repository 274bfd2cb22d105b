//! Ray casting: every beam of a scan geometry into a scene, from a fixed or a moving scanner.

use pfe_core::ScanGeometry;
use std::f64::consts::PI;

use super::vec2::{add, dir, dot, norm, scale, sub, V2};
use super::Shape;

/// The nearest hit of one beam.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Range from the scanner's position when the beam was taken, mm.
    pub range: f64,
    /// Index of the primitive hit.
    pub primitive: usize,
    /// Incidence angle β between the beam and the surface normal, rad (0: head-on, π/2:
    /// grazing).
    pub incidence: f64,
}

/// Casts every beam of `geometry` from the origin into `shapes`: nearest hit per beam
/// (range, primitive id), `None` beyond `geometry.r_max`.
pub fn cast(shapes: &[Shape], geometry: &ScanGeometry) -> Vec<Option<(f64, usize)>> {
    cast_moving(shapes, geometry, |_| [0.0, 0.0, 0.0])
        .into_iter()
        .map(|h| h.map(|h| (h.range, h.primitive)))
        .collect()
}

/// Casts beam `i` of `geometry` from the scanner pose `pose(i) = [x, y, θ]` (mm, mm, rad, in
/// the frame of `shapes`), at the nominal bearing turned by θ; `None` beyond `geometry.r_max`.
pub fn cast_moving(
    shapes: &[Shape],
    geometry: &ScanGeometry,
    pose: impl Fn(usize) -> [f64; 3],
) -> Vec<Option<Hit>> {
    let n = beam_count(geometry);
    (0..n)
        .map(|i| {
            let [x, y, theta] = pose(i);
            let b = bearing(geometry, i);
            let d = dir(if theta == 0.0 { b } else { b + theta });
            let origin = [x, y];
            let mut best: Option<(f64, usize)> = None;
            for (id, s) in shapes.iter().enumerate() {
                if let Some(t) = s.ray_hit(origin, d) {
                    if best.is_none_or(|(bt, _)| t < bt) {
                        best = Some((t, id));
                    }
                }
            }
            let (range, primitive) = best.filter(|(t, _)| *t <= f64::from(geometry.r_max))?;
            let hit = add(origin, scale(d, range));
            let incidence = shapes.get(primitive).map_or(0.0, |s| incidence(s, hit, d));
            Some(Hit {
                range,
                primitive,
                incidence,
            })
        })
        .collect()
}

/// Angle between the ray direction `d` (unit) and the normal of `shape` at `hit`, in [0, π/2].
fn incidence(shape: &Shape, hit: V2, d: V2) -> f64 {
    let normal = match *shape {
        Shape::Segment { a, b } => {
            let e = sub(b, a);
            [-e[1], e[0]]
        }
        Shape::Circle { center, .. } => sub(hit, center),
    };
    let l = norm(normal);
    if l > 0.0 {
        (dot(d, normal).abs() / l).min(1.0).acos()
    } else {
        0.0
    }
}

/// Bearing of beam `i` in f64.
pub fn bearing(geometry: &ScanGeometry, i: usize) -> f64 {
    f64::from(geometry.start_angle) + f64::from(geometry.angle_step) * i as f64
}

/// Beams of an LMS200-style geometry over 180°.
fn beam_count(geometry: &ScanGeometry) -> usize {
    let step = f64::from(geometry.angle_step).abs();
    if step > 0.0 {
        (PI / step).round() as usize + 1
    } else {
        0
    }
}
