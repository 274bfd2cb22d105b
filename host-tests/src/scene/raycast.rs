//! Ray casting: every beam of a scan geometry into a scene.

use pfe_core::ScanGeometry;
use std::f64::consts::PI;

use super::vec2::dir;
use super::Shape;

/// Casts every beam of `geometry` from the origin into `shapes`: nearest hit per beam
/// (range, primitive id), `None` beyond `geometry.r_max`.
pub fn cast(shapes: &[Shape], geometry: &ScanGeometry) -> Vec<Option<(f64, usize)>> {
    let n = beam_count(geometry);
    (0..n)
        .map(|i| {
            let d = dir(bearing(geometry, i));
            let mut best: Option<(f64, usize)> = None;
            for (id, s) in shapes.iter().enumerate() {
                if let Some(t) = s.ray_hit([0.0, 0.0], d) {
                    if best.is_none_or(|(bt, _)| t < bt) {
                        best = Some((t, id));
                    }
                }
            }
            best.filter(|(t, _)| *t <= f64::from(geometry.r_max))
        })
        .collect()
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
