//! The walk's arc continuation ([`continues_arc`]): whether the arc of a segment's last points
//! predicts the next point along its beam.

use crate::arc::arc_fit;
use crate::geometry::{ray_circle_intersection, Point};
use crate::math;
use crate::pass::Pass;
use crate::rule::NoiseRule;

/// Arc continuation test for point `k` of the segment starting at `s` (see
/// [`crate::NoiseModel::arc_window`]): the circle through the segment's last points must
/// explain them significantly better than a line and predict `k` along its beam.
pub(crate) fn continues_arc(pass: &mut Pass<'_>, s: usize, k: usize, rule: &NoiseRule) -> bool {
    let m = &rule.model;
    let c = k - s;
    if m.arc_window < 5 || c < 5 {
        return false;
    }
    let window = pass.points.get(k - c.min(m.arc_window)..k);
    let Some(circle) = window.and_then(|pts| arc_fit(pts, rule)) else {
        return false;
    };
    pass.stats.predictions += 1;
    let (target, origin) = (pass.point(k), pass.origin(k));
    let (bx, by) = (target.x - origin.x, target.y - origin.y);
    let r = math::hypot(bx, by);
    if !(r > 0.0) {
        return false;
    }
    let (dx, dy) = (bx / r, by / r);
    match ray_circle_intersection(origin, dx, dy, circle.center, circle.radius) {
        Some(t) => {
            // The circle's position error (about σ_r across it) is stretched along the beam by
            // 1/cos γ, γ between the beam and the circle's normal there.
            let hit = Point::new(origin.x + dx * t, origin.y + dy * t);
            let (nx, ny) = (hit.x - circle.center.x, hit.y - circle.center.y);
            let cos_g = math::abs(nx * dx + ny * dy) / circle.radius;
            let f = math::sqrt(1.0 + 1.0 / cos_g.max(0.1) / cos_g.max(0.1));
            math::abs(r - t) <= rule.k_sigma * f + m.floor
        }
        // The beam passes just outside the fitted circle (a point at the very edge).
        None => {
            math::abs(target.distance(&circle.center) - circle.radius) <= rule.k_sigma + m.floor
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Config;
    use crate::extractor::Extractor;
    use crate::scan::{Scan, ScanGeometry};

    /// The arc continuation's tolerance along a beam that meets the circle head on is
    /// `k σ_r √(1 + 1/cos²γ) + floor` = `√2 k σ_r + floor` (γ = 0): the point in the middle of
    /// a pillar 3 m ahead (radius 500 mm), predicted from the 24 exact points before it, is
    /// taken 1.38 `k σ_r` + floor from the circle and refused at 1.45; 7° off the centre, where
    /// the beam meets the circle at γ with 1/cos γ ≈ 1.6, between 0.97 and 1.03 times its
    /// factor; a beam that misses the fitted circle, by the point's distance from it.
    #[test]
    fn an_arc_continues_within_root_two_k_sigma_head_on() {
        let g = ScanGeometry::LMS200_180_050;
        let config = Config::default().with_sigma_r(5.0);
        let exact: [f32; 361] = core::array::from_fn(|i| {
            let (s, c) = math::sin_cos(g.bearing(i));
            ray_circle_intersection(Point::new(0.0, 0.0), c, s, Point::new(3000.0, 0.0), 500.0)
                .unwrap_or(f32::NAN)
        });
        let (first, k) = (exact.iter().position(|r| r.is_finite()).unwrap_or(0), 180);
        assert!(k - first > 10, "{first}");
        let mut ex = Extractor::<361, 8>::new();
        let scan = Scan::from_mm(g, &exact);
        let (k_sigma, floor) = ex.with_pass(&scan, &config, |_, rule| {
            rule.noise()
                .map_or((0.0, 0.0), |r| (r.k_sigma, r.model.floor))
        });
        assert!(k_sigma > 0.0);
        let continues = |ex: &mut Extractor<361, 8>, off: f32| {
            let mut ranges = exact;
            if off != 0.0 {
                ranges[k] += off.signum() * (off.abs() * k_sigma + floor);
            }
            let scan = Scan::from_mm(g, &ranges);
            ex.with_pass(&scan, &config, |pass, rule| {
                rule.noise()
                    .is_some_and(|r| continues_arc(pass, first, k, r))
            })
        };
        assert!(continues(&mut ex, 0.0));
        assert!(continues(&mut ex, 1.38));
        assert!(!continues(&mut ex, 1.45));
        assert!(continues(&mut ex, -1.38));
        assert!(!continues(&mut ex, -1.45));
        // Obliquely, 7° off the centre: the tolerance grows with 1/cos γ (f64, ±3 %).
        let k2 = 194;
        let b = f64::from(g.bearing(k2));
        let (d, c, r) = ((b.cos(), b.sin()), (3000.0f64, 0.0f64), 500.0f64);
        let along = d.0 * c.0 + d.1 * c.1;
        let t = along - (along * along - (c.0 * c.0 + c.1 * c.1 - r * r)).sqrt();
        let cos_g = ((t * d.0 - c.0) * d.0 + (t * d.1 - c.1) * d.1).abs() / r;
        let f = (1.0 + 1.0 / (cos_g * cos_g)).sqrt() as f32;
        assert!(f > 1.6, "{f}");
        let at = |ex: &mut Extractor<361, 8>, off: f32| {
            let mut ranges = exact;
            ranges[k2] += off * f * k_sigma + floor;
            ex.with_pass(&Scan::from_mm(g, &ranges), &config, |pass, rule| {
                rule.noise()
                    .is_some_and(|r| continues_arc(pass, first, k2, r))
            })
        };
        assert!(at(&mut ex, 0.97));
        assert!(!at(&mut ex, 1.03));
        // Beam 200 passes 20.9 mm outside the pillar: a point on it 22 mm from the circle is
        // taken (within k σ_r + floor = 23 mm of it), one 30 mm from it is not.
        let edge = |ex: &mut Extractor<361, 8>, delta: f64| {
            let b = f64::from(g.bearing(200));
            let along = 3000.0 * b.cos();
            let r = along - (along * along - 3000.0f64.powi(2) + (500.0 + delta).powi(2)).sqrt();
            let mut ranges = exact;
            ranges[200] = r as f32;
            ex.with_pass(&Scan::from_mm(g, &ranges), &config, |pass, rule| {
                rule.noise()
                    .is_some_and(|r| continues_arc(pass, first, 200, r))
            })
        };
        assert!(exact[200].is_nan() && exact[199].is_finite());
        assert!(edge(&mut ex, 22.0));
        assert!(!edge(&mut ex, 30.0));
    }

    /// From a moving scanner (1 m/s, turning at 1 rad/s, beams 2.666 ms apart: by the pillar's
    /// middle beam it has moved sideways by more than 50 mm) the arc is continued along each
    /// beam from where it was taken: the pillar's exact ranges from each beam's pose (f64)
    /// continue the arc at its middle beam, as does the same point 1.3 `k σ_r` + floor further
    /// out (the head-on tolerance is √2 `k σ_r` + floor, the beam at 48° to the axes), and not
    /// 1.45 `k σ_r` + floor.
    #[test]
    fn an_arc_continues_along_the_beam_of_a_moving_scanner() {
        use crate::motion::Motion;
        let g = ScanGeometry::LMS200_180_050;
        let config = Config::default().with_sigma_r(5.0);
        let (v, w, dt) = (1000.0f64, 1.0f64, 0.002_666f64);
        let (c, radius) = ((2000.0f64, 2200.0f64), 500.0f64);
        let exact: [f32; 361] = core::array::from_fn(|i| {
            let t = i as f64 * dt;
            let (ox, oy, th) = (v / w * (w * t).sin(), v / w * (1.0 - (w * t).cos()), w * t);
            let b = f64::from(g.bearing(i)) + th;
            let d = (libm::cos(b), libm::sin(b));
            let (px, py) = (c.0 - ox, c.1 - oy);
            let along = d.0 * px + d.1 * py;
            let disc = along * along - (px * px + py * py - radius * radius);
            if disc >= 0.0 && along > 0.0 {
                (along - libm::sqrt(disc)) as f32
            } else {
                f32::NAN
            }
        });
        let first = exact.iter().position(|r| r.is_finite()).unwrap_or(0);
        let k = (first..361)
            .take_while(|&i| exact[i].is_finite())
            .last()
            .unwrap_or(0)
            / 2
            + first / 2;
        assert!(k > first + 10, "{first} {k}");
        let motion = Motion::uniform(v as f32, w as f32, dt as f32);
        let mut ex = Extractor::<361, 8>::new();
        let mut continues = |off: f32| {
            let mut ranges = exact;
            ranges[k] += off;
            let scan = Scan::from_mm(g, &ranges).with_motion(motion);
            ex.with_pass(&scan, &config, |pass, rule| {
                let o = pass.origin(k);
                assert!(o.y > 50.0, "{o:?}");
                rule.noise()
                    .is_some_and(|r| continues_arc(pass, first, k, r))
            })
        };
        assert!(continues(0.0));
        assert!(continues(1.3 * 20.0 + 3.0));
        assert!(!continues(1.45 * 20.0 + 3.0));
    }
}
