//! Whether a run of sparse points lies on one line within the noise: the test that joins a
//! distant wall seen at grazing incidence (points too far apart for the walk to predict one
//! from the others) into one segment.

use crate::fit::line::{centre, fit_line, major_axis, smaller_eigenvalue};
use crate::geometry::Point;
use crate::math;

/// Length of the longest prefix of `points` in which every point lies within `2 tol` of the
/// line of the points before it (every prefix of two points does): a cheap screen, O(1) a
/// point, before [`on_one_line`].
pub(crate) fn line_prefix(points: &[Point], tol: f32) -> usize {
    let Some(o) = points.first() else { return 0 };
    let mut s = [0.0f32; 5];
    for (m, p) in points.iter().enumerate() {
        let (ex, ey) = (p.x - o.x, p.y - o.y);
        if m >= 2 {
            let ((mx, my), [sxx, syy, sxy]) = centre(s, 1.0 / m as f32);
            let (_, tx, ty) = major_axis(sxx, syy, sxy);
            // Distance × |t| within 2 tol |t|, squared: no root, no division.
            let d = (ey - my) * tx - (ex - mx) * ty;
            if !(d * d <= 4.0 * tol * tol * (tx * tx + ty * ty)) {
                return m;
            }
        }
        s = [
            s[0] + ex,
            s[1] + ey,
            s[2] + ex * ex,
            s[3] + ey * ey,
            s[4] + ex * ey,
        ];
    }
    points.len()
}

/// Whether `points` (in beam order) lie on their least-squares line within the noise: every
/// distance within `tol`, a residual sum of at most `2.25 var` a point (RMS 1.5 σ), and their
/// positions along the line monotone (a wall seen beam by beam, not a zig-zag of objects).
pub(crate) fn on_one_line(points: &[Point], tol: f32, var: f32) -> bool {
    let Ok(line) = fit_line(points) else {
        return false;
    };
    if !(line.sse() <= 2.25 * var * points.len() as f32) {
        return false;
    }
    let (c, s) = line.normal();
    let along = |p: &Point| p.y * c - p.x * s;
    let mut dir = 0.0f32;
    let mut prev: Option<f32> = None;
    for p in points {
        if !(math::abs(line.signed_distance(p)) <= tol) {
            return false;
        }
        let t = along(p);
        if let Some(q) = prev {
            let step = t - q;
            if dir == 0.0 {
                dir = step;
            }
            if !(step * dir > 0.0) {
                return false;
            }
        }
        prev = Some(t);
    }
    true
}

/// Meeting points tried on either side of the apex.
const REACH: usize = 1;

/// Smallest residual sum of two least-squares lines over `points` (a corner, seen as one
/// segment) that meet at a point within [`REACH`] of the one farthest from the chord (the
/// apex; the meeting point in both runs or ending the first): O(n), two passes. `None` for fewer than 4
/// points.
pub(crate) fn best_split_sse(points: &[Point]) -> Option<f32> {
    two_lines(points).map(|(best, _)| best)
}

/// The best split of `points` into two runs that share no point, near the apex as in
/// [`best_split_sse`]: the points of the first run (at least two, and two left) and the two
/// lines' residual sum. `None` for fewer than 4 points.
pub(crate) fn corner_split(points: &[Point]) -> Option<(usize, f32)> {
    two_lines(points)
        .map(|(_, disjoint)| disjoint)
        .filter(|(_, sse)| math::finite(*sse))
}

/// [`best_split_sse`] and [`corner_split`] from one pass over the sums.
fn two_lines(points: &[Point]) -> Option<(f32, (usize, f32))> {
    let n = points.len();
    let (a, b) = (*points.first().filter(|_| n >= 4)?, *points.last()?);
    let (cx, cy) = (b.x - a.x, b.y - a.y);
    let mut apex = (0usize, 0.0f32);
    for (i, p) in points.iter().enumerate() {
        let d = math::abs((p.x - a.x) * cy - (p.y - a.y) * cx);
        if d > apex.1 {
            apex = (i, d);
        }
    }
    // Apex candidates j with at least two points on each side (j shared).
    let lo = apex.0.saturating_sub(REACH).max(1);
    let hi = (apex.0 + REACH).min(n - 2);
    let o = *points.get(apex.0)?;
    let mut sums = [[0.0f32; 5]; 2 * REACH + 2];
    let add = |s: [f32; 5], p: &Point| {
        let (ex, ey) = (p.x - o.x, p.y - o.y);
        [
            s[0] + ex,
            s[1] + ey,
            s[2] + ex * ex,
            s[3] + ey * ey,
            s[4] + ex * ey,
        ]
    };
    // The prefix sums through lo − 1 ..= hi are kept: the sums in three runs, no test a point
    // outside them.
    let (head, rest) = points.split_at_checked(lo - 1)?;
    let (kept, tail) = rest.split_at_checked(hi + 2 - lo)?;
    let mut s = head.iter().fold([0.0f32; 5], add);
    for (slot, p) in sums.iter_mut().zip(kept) {
        s = add(s, p);
        *slot = s;
    }
    let s = tail.iter().fold(s, add);
    let sse = |s: [f32; 5], m: usize| {
        let (_, [sxx, syy, sxy]) = centre(s, 1.0 / m as f32);
        smaller_eigenvalue(sxx, syy, sxy)
    };
    let mut best = f32::INFINITY;
    let mut disjoint = (0usize, f32::INFINITY);
    for j in lo..=hi {
        let (Some(&through), Some(&before)) = (sums.get(j + 1 - lo), sums.get(j - lo)) else {
            continue;
        };
        let minus = |p: [f32; 5]| {
            [
                s[0] - p[0],
                s[1] - p[1],
                s[2] - p[2],
                s[3] - p[3],
                s[4] - p[4],
            ]
        };
        // j shared by both runs, and j ending the first.
        let shared = sse(through, j + 1) + sse(minus(before), n - j);
        best = best.min(shared);
        if j + 3 <= n {
            let apart = sse(through, j + 1) + sse(minus(through), n - j - 1);
            best = best.min(apart);
            if apart < disjoint.1 {
                disjoint = (j + 1, apart);
            }
        }
    }
    math::finite(best).then_some((best, disjoint))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_zig_zag_is_not_one_line() {
        let line: [Point; 6] = core::array::from_fn(|i| Point::new(1000.0 * i as f32, 5.0));
        assert_eq!(line_prefix(&line, 43.0), 6);
        assert!(on_one_line(&line, 43.0, 100.0));
        // The same points out of order along the line.
        let mut back = line;
        back.swap(2, 3);
        assert!(!on_one_line(&back, 43.0, 100.0));
        // Every other point 100 mm off.
        let zig: [Point; 6] =
            core::array::from_fn(|i| Point::new(1000.0 * i as f32, 100.0 * (i % 2) as f32));
        assert!(line_prefix(&zig, 43.0) < 6 && !on_one_line(&zig, 43.0, 100.0));
    }

    #[test]
    fn a_corner_splits_into_two_exact_lines() {
        let corner: [Point; 9] = core::array::from_fn(|i| {
            let t = i as f32 - 4.0;
            Point::new(1000.0 + 100.0 * t.abs(), 100.0 * t)
        });
        let split = best_split_sse(&corner).unwrap_or(f32::NAN);
        assert!(split < 1.0, "{split}");
        // Apart: the apex (index 4, on both lines) ends the first run or starts the second.
        let (k, apart) = corner_split(&corner).unwrap_or((0, f32::NAN));
        assert!((4..=5).contains(&k) && apart < 1.0, "{k} {apart}");
        // Off-centre: the corner at index 2 of 9.
        let early: [Point; 9] = core::array::from_fn(|i| {
            let t = i as f32 - 2.0;
            Point::new(1000.0 + 100.0 * t.abs(), 100.0 * t)
        });
        let (k, apart) = corner_split(&early).unwrap_or((0, f32::NAN));
        assert!((2..=3).contains(&k) && apart < 1.0, "{k} {apart}");
        assert_eq!(corner_split(&early[..3]), None);
        let bent: [Point; 9] = core::array::from_fn(|i| {
            let a = 0.3 * (i as f32 - 4.0);
            Point::new(1000.0 - 300.0 * a.cos(), 300.0 * a.sin())
        });
        assert!(best_split_sse(&bent).unwrap_or(0.0) > 100.0);
    }

    /// The prefix screen in every direction: points 1 m apart along a line at angle `a` (to
    /// x), alternately 0.3 tol to either side of it, stay one line to the end; one point 2.2
    /// tol off a straight run ends the prefix there. (The screen compares `d |t|` with `2 tol |t|` for the
    /// unnormalised direction `t`, whose length grows with the points' spread.)
    #[test]
    fn the_prefix_screen_holds_in_every_direction() {
        let tol = 40.0f32;
        for k in 0..12 {
            let a = k as f32 * core::f32::consts::PI / 12.0;
            let (s, c) = math::sin_cos(a);
            let at = |i: usize, off: f32| {
                let t = 1000.0 * i as f32;
                Point::new(500.0 + t * c - off * s, -300.0 + t * s + off * c)
            };
            // Off by ±0.3 tol: every point within 2 tol of the line of the ones before it (the
            // worst, the third from the line of the first two: 1.2 tol).
            let pts: [Point; 8] =
                core::array::from_fn(|i| at(i, if i % 2 == 0 { 0.3 } else { -0.3 } * tol));
            assert_eq!(line_prefix(&pts, tol), 8, "angle {a}");
            let mut bad: [Point; 8] = core::array::from_fn(|i| at(i, 0.0));
            bad[5] = at(5, 2.2 * tol);
            assert_eq!(line_prefix(&bad, tol), 5, "angle {a}");
        }
    }

    /// The two-line residual sums do not depend on where the corner lies: the same bent run
    /// (legs of 8 points 100 mm apart, ±3 mm of zig-zag) at the origin and 6.7 m away gives
    /// the same best split and the same sums within 0.1 % (the sums are taken about the apex,
    /// so no large coordinates cancel).
    #[test]
    fn two_line_sums_do_not_depend_on_where_the_corner_is() {
        let at = |ox: f32, oy: f32| -> [Point; 15] {
            core::array::from_fn(|i| {
                let t = i as f32 - 7.0;
                let zig = if i % 2 == 0 { 3.0 } else { -3.0 };
                Point::new(ox + 100.0 * t.abs() + zig, oy + 100.0 * t - zig)
            })
        };
        let (near, far) = (at(0.0, 0.0), at(3000.0, 6000.0));
        let (bn, bf) = (
            best_split_sse(&near).unwrap_or(f32::NAN),
            best_split_sse(&far).unwrap_or(f32::NAN),
        );
        assert!(bn > 10.0 && (bf - bn).abs() <= 1e-3 * bn, "{bn} vs {bf}");
        let (cn, cf) = (corner_split(&near), corner_split(&far));
        let ((kn, sn), (kf, sf)) = (cn.unwrap_or((0, f32::NAN)), cf.unwrap_or((0, f32::NAN)));
        assert!(kn == kf && (sf - sn).abs() <= 1e-3 * sn, "{cn:?} vs {cf:?}");
    }

    /// `n` points 80 mm apart along the line of normal angle `alpha` at ρ 3 m, each off it by
    /// `off(i)` mm.
    fn along_line(alpha: f32, n: usize, off: impl Fn(usize) -> f32) -> heapless::Vec<Point, 64> {
        let (s, c) = (alpha.sin(), alpha.cos());
        (0..n)
            .map(|i| {
                let (t, d) = (80.0 * i as f32 - 400.0, 3000.0 + off(i));
                Point::new(d * c - t * s, d * s + t * c)
            })
            .collect()
    }

    /// [`best_split_sse`] and [`corner_split`] against their definition, by separate fits of
    /// every split (f64 sums): the two lines meet at a point within [`REACH`] of the apex
    /// (shared by both, or ending the first run), each run at least two points. Bent runs of
    /// 5 to 12 points whose bend lies before, at or after the apex (noise of ±3 mm from a
    /// fixed generator), so that the best meeting point is often the one past the apex.
    #[test]
    fn best_split_is_the_least_sum_of_the_splits_near_the_apex() {
        let sse64 = |p: &[Point]| -> f64 {
            let k = p.len() as f64;
            let (mx, my) = p.iter().fold((0.0, 0.0), |a, q| {
                (a.0 + f64::from(q.x) / k, a.1 + f64::from(q.y) / k)
            });
            let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
            for q in p {
                let (dx, dy) = (f64::from(q.x) - mx, f64::from(q.y) - my);
                sxx += dx * dx;
                syy += dy * dy;
                sxy += dx * dy;
            }
            let h = 0.5 * (sxx - syy);
            0.5 * (sxx + syy) - libm::sqrt(h * h + sxy * sxy)
        };
        let mut seed = 0x2545_f491u32;
        let mut noise = || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            (seed % 601) as f32 / 100.0 - 3.0
        };
        let (mut past_apex, mut checked) = (0, 0);
        for n in 5..=12usize {
            for bend in 1..n - 1 {
                for turn in [0.02f32, 0.05, 0.1, 0.3, 1.4] {
                    let pts: heapless::Vec<Point, 12> = (0..n)
                        .map(|i| {
                            let t = 100.0 * (i as f32 - bend as f32);
                            let y = if i < bend { 0.0 } else { t * turn };
                            Point::new(1000.0 + t, 2000.0 + y + noise())
                        })
                        .collect();
                    let (a, b) = (pts[0], pts[n - 1]);
                    let apex = (0..n)
                        .max_by(|&i, &j| {
                            let d = |k: usize| {
                                let p = pts[k];
                                ((p.x - a.x) * (b.y - a.y) - (p.y - a.y) * (b.x - a.x)).abs()
                            };
                            d(i).total_cmp(&d(j))
                        })
                        .unwrap_or(0);
                    let (lo, hi) = (apex.saturating_sub(REACH).max(1), (apex + REACH).min(n - 2));
                    let mut best = (f64::INFINITY, 0usize);
                    let mut apart = (f64::INFINITY, 0usize);
                    for j in lo..=hi {
                        let shared = sse64(&pts[..=j]) + sse64(&pts[j..]);
                        if shared < best.0 {
                            best = (shared, j);
                        }
                        if j + 3 <= n {
                            let sum = sse64(&pts[..=j]) + sse64(&pts[j + 1..]);
                            if sum < best.0 {
                                best = (sum, j);
                            }
                            if sum < apart.0 {
                                apart = (sum, j + 1);
                            }
                        }
                    }
                    past_apex += usize::from(best.1 > apex);
                    let got = best_split_sse(&pts).map(f64::from);
                    let tol = |x: f64| 1e-3 * x + 0.5;
                    assert!(
                        got.is_some_and(|g| (g - best.0).abs() <= tol(best.0)),
                        "n {n} bend {bend} turn {turn}: {got:?} against {}",
                        best.0
                    );
                    if apart.0.is_finite() {
                        let split = corner_split(&pts);
                        // Near-ties in f32 may pick another split of the same sum.
                        let of_k = |k: usize| sse64(&pts[..k]) + sse64(&pts[k..]);
                        assert!(
                            split.is_some_and(|(k, s)| (lo + 1..=hi + 1).contains(&k)
                                && (of_k(k) - apart.0).abs() <= tol(apart.0)
                                && (f64::from(s) - apart.0).abs() <= tol(apart.0)),
                            "n {n} bend {bend} turn {turn}: {split:?} against {apart:?}"
                        );
                    }
                    checked += 1;
                }
            }
        }
        assert!(checked > 200 && past_apex >= 8, "{checked} {past_apex}");
    }

    /// The RMS bound 1.5 σ: residuals of ±1.4 σ pass, ±1.6 σ do not (σ 5 mm, a distance
    /// bound far away); at every normal angle, including 45° and the angle where sin α =
    /// −cos² α (an "along" coordinate built from other products stays constant there).
    #[test]
    fn one_line_within_the_rms_bound_at_any_angle() {
        let var = 25.0f32;
        for alpha in [0.3f32, core::f32::consts::FRAC_PI_4, -0.666_239, 2.0] {
            let pts = |k: f32| along_line(alpha, 12, |i| if i % 2 == 0 { k } else { -k });
            assert!(on_one_line(&pts(7.0), 100.0, var), "{alpha}");
            assert!(!on_one_line(&pts(8.0), 100.0, var), "{alpha}");
        }
        // A point repeated is not a wall seen beam by beam.
        let mut twice = along_line(0.3, 8, |_| 0.0);
        let last = twice.last().copied();
        if let Some(p) = last {
            let _ = twice.push(p);
        }
        assert!(!on_one_line(&twice, 100.0, var));
    }
}
