//! Line ends reach over the neighbouring beams that lie on them (default mode, after the
//! fits). The walk marks the point where a prediction from a short window fails and pairs the
//! marks into segments; at a corner or a step this leaves one to three beams between two
//! features, in a segment too short to fit, though most of them lie on one of the two lines
//! well within the noise (the fitted line, from all the segment's points, is far better known
//! than the walk's window). A line's span grows over such beams, one at a time outwards, while
//! each is valid, is not across a jump, lies within `k σ f + floor` of the line (`f²` = 1 +
//! the line's own variance at the point over σ²) and is not closer to the next feature. The
//! fit stands: `points` still counts the fitted points; the end points move to the new ends.

use crate::feature::{CircleFeature, Feature, LineFeature};
use crate::flags::{END, JUMP, START};
use crate::geometry::Point;
use crate::math;
use crate::pass::Pass;
use crate::rule::NoiseRule;

/// Extends every line of `features` (in scan order; a feature out of order is left as it is)
/// over the beams of `pass` next to its ends that lie on it. The marks follow: a line's ends
/// stay the ends of its segment, and what is left of a short segment beside it keeps its own.
#[inline(never)]
pub(crate) fn extend(pass: &mut Pass<'_>, rule: &NoiseRule, features: &mut [Feature]) {
    for i in 0..features.len() {
        let (before, rest) = features.split_at_mut(i);
        let Some((this, after)) = rest.split_first_mut() else {
            return;
        };
        let Feature::Line(line) = this else {
            continue;
        };
        let prev = before.last();
        let next = after.first();
        // Beams between the neighbours' spans, when the three are in order.
        let lo = prev.map_or(0, |p| p.last() + 1);
        let hi = next.map_or(pass.len(), Feature::first);
        let (first, last) = (usize::from(line.first), usize::from(line.last));
        if lo > first || hi <= last {
            continue;
        }
        let reach = Reach::of(line, rule);
        // Forwards, each beam not closer to the next feature.
        let mut j = last + 1;
        while j < hi && pass.flag(j) & JUMP == 0 {
            let p = pass.point(j);
            let Some(d) = reach.offset(pass, j, &p) else {
                break;
            };
            let Ok(end) = u16::try_from(j) else { break };
            if next.is_some_and(|n| distance(n, &p) < d) {
                break;
            }
            line.last = end;
            line.end = reach.project(&p);
            j += 1;
        }
        if j > last + 1 {
            remark(pass, (last, j - 1), END, j < hi);
        }
        // Backwards (the feature before has taken what lies closer to it).
        let mut j = first;
        while j > lo && pass.flag(j) & JUMP == 0 {
            let b = j - 1;
            let p = pass.point(b);
            let (Some(_), Ok(start)) = (reach.offset(pass, b, &p), u16::try_from(b)) else {
                break;
            };
            line.first = start;
            line.start = reach.project(&p);
            j = b;
        }
        if j < first {
            remark(pass, (j, first), START, j > lo);
        }
    }
}

/// Moves a segment's end mark `end` (`END` or `START`) over the beams `a..=b` it reached: from
/// `b` (`END`) or `a` (`START`) to the other; the beam beyond, when `rest` (what is left of the
/// short segment there), gets the mark of its own end.
fn remark(pass: &mut Pass<'_>, (a, b): (usize, usize), end: u8, rest: bool) {
    for i in a..=b {
        pass.clear(i, START | END);
    }
    if end == END {
        pass.set(b, END);
        if rest && pass.valid(b + 1) {
            pass.set(b + 1, START);
        }
    } else {
        pass.set(a, START);
        if rest && pass.valid(a - 1) {
            pass.set(a - 1, END);
        }
    }
}

/// A line's test of further points.
struct Reach {
    /// Unit normal (cos α, sin α).
    normal: (f32, f32),
    rho: f32,
    var_alpha: f32,
    var_rho: f32,
    cov: f32,
    /// σ².
    var: f32,
    /// k².
    k2: f32,
    floor: f32,
}

impl Reach {
    fn of(line: &LineFeature, rule: &NoiseRule) -> Self {
        let (s, c) = math::sin_cos(line.alpha);
        Self {
            normal: (c, s),
            rho: line.rho,
            var_alpha: line.var_alpha,
            var_rho: line.var_rho,
            cov: line.cov_alpha_rho,
            var: rule.sigma_r * rule.sigma_r,
            k2: rule.model.k * rule.model.k,
            floor: rule.model.floor,
        }
    }

    /// The distance of point `p` (beam `i`, valid) from the line, when within the test.
    fn offset(&self, pass: &Pass<'_>, i: usize, p: &Point) -> Option<f32> {
        if !pass.valid(i) {
            return None;
        }
        let (c, s) = self.normal;
        let d = p.x * c + p.y * s - self.rho;
        // ∂d/∂α: the point's position along the line.
        let t = p.y * c - p.x * s;
        let var = self.var + t * t * self.var_alpha - 2.0 * t * self.cov + self.var_rho;
        let e = math::abs(d) - self.floor;
        (e <= 0.0 || e * e <= self.k2 * var).then_some(math::abs(d))
    }

    /// The foot of `p` on the line.
    fn project(&self, p: &Point) -> Point {
        let (c, s) = self.normal;
        let d = p.x * c + p.y * s - self.rho;
        Point::new(p.x - d * c, p.y - d * s)
    }
}

/// The distance of `p` from feature `f` (a line's or a circle's).
fn distance(f: &Feature, p: &Point) -> f32 {
    match f {
        Feature::Line(l) => {
            let (s, c) = math::sin_cos(l.alpha);
            math::abs(p.x * c + p.y * s - l.rho)
        }
        Feature::Circle(CircleFeature { center, radius, .. }) => {
            math::abs(p.distance(center) - radius)
        }
        // Objects are made after the reach.
        Feature::Object(o) => p.distance(&o.center),
    }
}

#[cfg(test)]
#[cfg(test)]
#[allow(clippy::indexing_slicing)]
mod tests {
    use super::*;
    use crate::config::Config;
    use crate::extractor::Extractor;
    use crate::feature::LineFeature;
    use crate::scan::{Scan, ScanGeometry};

    const G: ScanGeometry = ScanGeometry::LMS200_180_050;
    /// Normal angles of the walls tried, rad.
    const ALPHAS: [f32; 3] = [0.0, 0.5, -0.4];
    /// No covariance of its own.
    const EXACT: (f32, f32, f32) = (0.0, 0.0, 0.0);

    /// Bearing of beam `i` from the wall's normal `alpha`.
    fn off_normal(i: usize, alpha: f32) -> f64 {
        f64::from(G.bearing(i)) - f64::from(alpha)
    }

    /// Ranges of the wall `x cos α + y sin α = 3000 + offset(i)` mm, seen by the beams within
    /// 1 rad of its normal (no return beyond).
    fn wall_ranges(alpha: f32, offset: impl Fn(usize) -> f64) -> [f32; 361] {
        core::array::from_fn(|i| {
            let b = off_normal(i, alpha);
            if b.abs() < 1.0 {
                ((3000.0 + offset(i)) / b.cos()) as f32
            } else {
                f32::NAN
            }
        })
    }

    /// The beams that see the wall of normal `alpha`.
    fn wall(alpha: f32) -> (usize, usize) {
        let seen: heapless::Vec<usize, 361> = (0..361)
            .filter(|&i| off_normal(i, alpha).abs() < 1.0)
            .collect();
        (seen[0], seen[seen.len() - 1])
    }

    /// The line `x cos α + y sin α = rho` over beams `first..=last`, with the covariance
    /// (σ_α², σ_ρ², cov).
    fn line(first: u16, last: u16, alpha: f32, rho: f32, (va, vr, c): (f32, f32, f32)) -> Feature {
        Feature::Line(LineFeature {
            first,
            last,
            points: last - first + 1,
            alpha,
            rho,
            var_alpha: va,
            var_rho: vr,
            cov_alpha_rho: c,
            start: Point::new(rho, 0.0),
            end: Point::new(rho, 0.0),
        })
    }

    /// `features` after [`extend`] over the scan `ranges` (σ_r 5 mm: k σ_r + floor = 23 mm),
    /// with `jumps` flagged.
    fn extended<const M: usize>(
        ranges: &[f32],
        jumps: &[usize],
        features: [Feature; M],
    ) -> [Feature; M] {
        let mut features = features;
        let scan = Scan::from_mm(G, ranges);
        Extractor::<361, 8>::new().with_pass(&scan, &Config::default(), |pass, rule| {
            for &j in jumps {
                pass.set(j, JUMP);
            }
            extend(pass, rule.noise().unwrap(), &mut features);
        });
        features
    }

    /// [`extended`] from `marks` (START at `.0`, END at `.1`), with the beams marked after it:
    /// (START, END) lists.
    fn remarked<const M: usize>(
        ranges: &[f32],
        jumps: &[usize],
        marks: &[(usize, usize)],
        features: [Feature; M],
    ) -> (
        [Feature; M],
        heapless::Vec<usize, 16>,
        heapless::Vec<usize, 16>,
    ) {
        let mut features = features;
        let scan = Scan::from_mm(G, ranges);
        Extractor::<361, 8>::new().with_pass(&scan, &Config::default(), |pass, rule| {
            for &j in jumps {
                pass.set(j, JUMP);
            }
            for &(s, e) in marks {
                pass.set(s, START);
                pass.set(e, END);
            }
            extend(pass, rule.noise().unwrap(), &mut features);
            let flagged = |bit: u8| {
                (0..pass.len())
                    .filter(|&i| pass.flag(i) & bit != 0)
                    .collect()
            };
            (features, flagged(START), flagged(END))
        })
    }

    /// The marks move with the ends: the segment's START and END go to the new first and last
    /// beams; the rest of a short segment beyond keeps its own marks; an end the reach does not
    /// move keeps its marks as they were.
    #[test]
    fn the_marks_move_with_the_ends() {
        let r = wall_ranges(0.0, |_| 0.0);
        // Marks of the line (150–200) and of short segments beside it, 140–149 and 201–212.
        let marks = [(140, 149), (150, 200), (201, 212)];
        // Jumps between 144 and 145 and between 204 and 205: the reach takes 145–149 and
        // 201–204.
        let (f, starts, ends) = remarked(
            &r,
            &[145, 205],
            &marks,
            [line(150, 200, 0.0, 3000.0, EXACT)],
        );
        assert_eq!(span(&f[0]), (145, 204));
        assert_eq!(
            (&starts[..], &ends[..]),
            (&[140, 145, 205][..], &[144, 204, 212][..])
        );
        // Nothing to take (jumps right beside it): the marks stay as they were.
        let (f, starts, ends) = remarked(
            &r,
            &[150, 201],
            &marks,
            [line(150, 200, 0.0, 3000.0, EXACT)],
        );
        assert_eq!(span(&f[0]), (150, 200));
        assert_eq!(
            (&starts[..], &ends[..]),
            (&[140, 150, 201][..], &[149, 200, 212][..])
        );
    }

    /// A beam with no return beyond the reached beams gets no mark: the reach backwards stops
    /// at beam 144 (no return) and leaves 140–143 of the short segment before the line with
    /// its START only, not an END on 144; forwards, up to the jump at 205, the rest 205–212
    /// gets its START as before.
    #[test]
    fn no_mark_goes_to_a_beam_without_a_return() {
        let mut r = wall_ranges(0.0, |_| 0.0);
        r[144] = f32::NAN;
        let marks = [(140, 149), (150, 200), (201, 212)];
        let (f, starts, ends) = remarked(&r, &[205], &marks, [line(150, 200, 0.0, 3000.0, EXACT)]);
        assert_eq!(span(&f[0]), (145, 204));
        assert_eq!(
            (&starts[..], &ends[..]),
            (&[140, 145, 205][..], &[204, 212][..])
        );
    }

    fn span(f: &Feature) -> (usize, usize) {
        (f.first(), f.last())
    }

    fn ends(f: &Feature) -> (Point, Point) {
        match f {
            Feature::Line(l) => (l.start, l.end),
            _ => panic!("a line"),
        }
    }

    /// The foot on the wall of normal `alpha` of beam `i`'s point lying `offset` mm off it.
    fn foot(i: usize, alpha: f32, offset: f64) -> (f64, f64) {
        let (b, a) = (f64::from(G.bearing(i)), f64::from(alpha));
        let range = (3000.0 + offset) / off_normal(i, alpha).cos();
        (
            range * b.cos() - offset * a.cos(),
            range * b.sin() - offset * a.sin(),
        )
    }

    /// `p` is within 0.01 mm of `(x, y)`.
    fn assert_at(p: Point, (x, y): (f64, f64), alpha: f32) {
        assert!(
            (f64::from(p.x) - x).abs() < 0.01 && (f64::from(p.y) - y).abs() < 0.01,
            "α {alpha}: {p:?} ({x}, {y})"
        );
    }

    #[test]
    fn a_line_reaches_every_beam_on_it_up_to_a_missing_return_and_its_ends_move_there() {
        for alpha in ALPHAS {
            let r = wall_ranges(alpha, |_| 0.0);
            let [f] = extended(&r, &[], [line(150, 200, alpha, 3000.0, EXACT)]);
            let (first, last) = wall(alpha);
            assert_eq!(span(&f), (first, last), "α {alpha}");
            // The ends are the end beams' points, on the wall.
            let (s, e) = ends(&f);
            for (p, i) in [(s, first), (e, last)] {
                assert_at(p, foot(i, alpha, 0.0), alpha);
            }
        }
    }

    #[test]
    fn the_reach_stops_at_the_first_point_beyond_k_sigma_plus_floor() {
        // No variance of its own: the test is |d| ≤ 4 · 5 + 3 = 23 mm.
        for alpha in ALPHAS {
            let r = wall_ranges(alpha, |i| match i {
                211 => 22.8,
                212 => 23.2,
                140 => -22.8,
                138 => -23.2,
                _ => 0.0,
            });
            let [f] = extended(&r, &[], [line(150, 200, alpha, 3000.0, EXACT)]);
            assert_eq!(span(&f), (139, 211), "α {alpha}");
            // The new end is the foot on the line of beam 211's point, 22.8 mm off it.
            assert_at(ends(&f).1, foot(211, alpha, 22.8), alpha);
        }
    }

    #[test]
    fn the_reach_starts_past_the_lines_ends_whatever_they_are() {
        // The line's own last point lies off it (the fit took it): the beams past it still count.
        for alpha in ALPHAS {
            let r = wall_ranges(alpha, |i| if i == 200 { 40.0 } else { 0.0 });
            let [f] = extended(&r, &[], [line(150, 200, alpha, 3000.0, EXACT)]);
            assert_eq!(span(&f), wall(alpha), "α {alpha}");
        }
    }

    #[test]
    fn the_reach_widens_with_the_lines_own_variance_at_the_point() {
        // At beam i, t (along the line) = (3000 + d) tan(bearing − α): σ² = 25 + t² σ_α²
        // − 2 t cov + σ_ρ², solved for d at the bound; the points at beams 230 and 100 lie
        // 0.3 mm inside, those at 232 and 98 0.3 mm outside.
        let cov = (1e-5f32, 30.0f32, 0.02f32);
        for alpha in [0.0f32, 0.2] {
            let tol = |i: usize| {
                let mut d = 0.0;
                for _ in 0..20 {
                    let t = (3000.0 + d) * off_normal(i, alpha).tan();
                    let var = 25.0 + t * t * f64::from(cov.0) - 2.0 * t * f64::from(cov.2)
                        + f64::from(cov.1);
                    d = 4.0 * var.sqrt() + 3.0;
                }
                d
            };
            let r = wall_ranges(alpha, |i| match i {
                230 | 100 => tol(i) - 0.3,
                232 | 98 => tol(i) + 0.3,
                _ => 0.0,
            });
            // The cross term matters: without it the two sides' tolerances differ by > 10 mm.
            assert!((tol(230) - tol(100)).abs() > 10.0);
            let [f] = extended(&r, &[], [line(150, 200, alpha, 3000.0, cov)]);
            assert_eq!(span(&f), (99, 231), "α {alpha}");
        }
    }

    #[test]
    fn the_reach_stops_at_a_jump_and_at_an_invalid_point() {
        // A jump flagged at 205 lies between 204 and 205; at 145, between 144 and 145.
        let r = wall_ranges(0.0, |_| 0.0);
        let [f] = extended(&r, &[205, 145], [line(150, 200, 0.0, 3000.0, EXACT)]);
        assert_eq!(span(&f), (145, 204));
        let mut r = r;
        r[190] = f32::NAN;
        r[120] = 0.0;
        let [f] = extended(&r, &[], [line(150, 180, 0.0, 3000.0, EXACT)]);
        assert_eq!(span(&f), (121, 189));
    }

    #[test]
    fn a_beam_closer_to_the_next_feature_is_left_to_it_which_reaches_back_over_it() {
        for alpha in ALPHAS {
            // The beams from 220 on lie 10 mm further: within A's 23 mm, but on B.
            let r = wall_ranges(alpha, |i| if i >= 220 { 10.0 } else { 0.0 });
            let a = line(150, 200, alpha, 3000.0, EXACT);
            let b = line(230, 240, alpha, 3010.0, EXACT);
            let [a, b] = extended(&r, &[], [a, b]);
            let (first, last) = wall(alpha);
            assert_eq!(span(&a), (first, 219), "α {alpha}");
            // B reaches back to 220 and on to the wall's end.
            assert_eq!(span(&b), (220, last), "α {alpha}");
        }
    }

    #[test]
    fn a_line_right_after_another_still_reaches_forwards() {
        let r = wall_ranges(0.0, |_| 0.0);
        let a = line(100, 149, 0.0, 3000.0, EXACT);
        let b = line(150, 200, 0.0, 3000.0, EXACT);
        let [a, b] = extended(&r, &[], [a, b]);
        assert_eq!(
            (span(&a), span(&b)),
            ((wall(0.0).0, 149), (150, wall(0.0).1))
        );
    }

    #[test]
    fn features_out_of_scan_order_are_left_as_they_are() {
        let r = wall_ranges(0.0, |_| 0.0);
        let a = line(150, 200, 0.0, 3000.0, EXACT);
        let b = line(230, 260, 0.0, 3000.0, EXACT);
        assert_eq!(extended(&r, &[], [b, a]), [b, a]);
        // Overlapping spans too.
        let c = line(190, 240, 0.0, 3000.0, EXACT);
        assert_eq!(extended(&r, &[], [a, c]), [a, c]);
    }

    #[test]
    fn a_circle_is_not_extended_and_distances_are_from_its_rim_or_the_line() {
        let c = Feature::Circle(CircleFeature {
            first: 150,
            last: 200,
            points: 51,
            center: Point::new(0.0, 0.0),
            radius: 100.0,
            cov: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            start_angle: 0.0,
            end_angle: 1.0,
        });
        let r = wall_ranges(0.0, |_| 0.0);
        assert_eq!(extended(&r, &[], [c]), [c]);
        assert_eq!(distance(&c, &Point::new(300.0, 400.0)), 400.0);
        assert_eq!(distance(&c, &Point::new(30.0, 40.0)), 50.0);
        // The line 0.6 x + 0.8 y = 1000: (1000, 500) lies on it, (700, 600) 100 mm off.
        let alpha = libm::atan2f(0.8, 0.6);
        let l = line(0, 1, alpha, 1000.0, EXACT);
        assert!((distance(&l, &Point::new(1000.0, 500.0)) - 0.0).abs() < 1e-3);
        assert!((distance(&l, &Point::new(700.0, 600.0)) - 100.0).abs() < 1e-3);
    }
}
