//! A line needs `min_points` beams that are its own ([`hands_over`]). At a corner without a
//! range jump the walk keeps the first beam of the next surface in the segment before it (and
//! a segment can start one beam early): a face seen over three beams then comes out as a
//! four-point line, and the next face's segment lacks that beam (three beams of a four-beam
//! face are no line). Near the corner the beam lies within the noise of both surfaces, so its
//! range cannot say whose it is; where the two lines meet can. A segment that has
//! `min_points` points only by counting such a beam gives it to the segment next to it.

use core::ops::RangeInclusive;

use crate::classify;
use crate::config::Config;
use crate::feature::Feature;
use crate::fit::line::{fit_line, LineFit};
use crate::flags::JUMP;
use crate::geometry::Point;
use crate::pass::Pass;

/// Points of the neighbouring surface whose line an end beam is tested against.
const NEIGHBOUR: usize = 3;
/// Most points of the neighbouring surface fitted.
const NEIGHBOUR_MAX: usize = 3;
/// 99 % of χ²₁: the neighbour's points lie on one line, and its first point off the
/// segment's (a corner, not the same surface).
const LINE_CHI2: f32 = 6.63;
/// 95 % of χ²₁: an end beam this near the neighbour's line (in its residual's σ) may be the
/// neighbour's.
const SHARED_CHI2: f32 = 3.84;
/// σ of the corner's position by which it must pass an end beam for the beam to be the
/// neighbour's ([`past_corner`]).
const CORNER_SIGMAS: f32 = 0.5;

/// Which end beams of the segment `s..=e` (first, last) are not its own when it has fewer
/// than `min_points` beams of its own: each end beam next to another surface (no invalid
/// beam, no range jump, [`NEIGHBOUR`] points on one line that meets the segment's at a corner)
/// that lies within [`SHARED_CHI2`] of that surface's line and past the corner is not counted;
/// a beam beyond the other end within [`SHARED_CHI2`] of the own beams' line is.
fn shared_ends(pass: &Pass<'_>, s: usize, e: usize, config: &Config) -> Option<(bool, bool)> {
    let min = config.min_points;
    let n = e + 1 - s;
    if n < min || n > min + 1 || n < 3 {
        return None;
    }
    let var = config.sigma_r * config.sigma_r;
    let before = shared(pass, s, s + 1..=e, false, var);
    let after = shared(pass, e, s..=e - 1, true, var);
    let own = n - usize::from(before) - usize::from(after);
    if own >= min {
        return None;
    }
    // A beam next to the other end, within the noise of the own beams' line, may be the face's
    // (the corner beam the neighbour kept): the face may have `min_points` beams.
    let (a, b) = (s + usize::from(before), e - usize::from(after));
    let fit = pass.points.get(a..=b).and_then(|p| fit_line(p).ok())?;
    let claims = |j: usize, flagged: usize| {
        j < pass.len()
            && pass.valid(j)
            && pass.flag(flagged) & JUMP == 0
            && chi2(&fit, pass.point(j), var) <= SHARED_CHI2
    };
    let claimed = (!before && s > 0 && claims(s - 1, s)) || (!after && claims(e + 1, e + 1));
    (own + usize::from(claimed) < min).then_some((before, after))
}

/// Whether the segment `s..=e`, typed a line, has too few beams of its own and its last
/// (`last`) or first beam is the neighbouring surface's: the segment next to it takes the beam.
pub(super) fn hands_over(pass: &Pass<'_>, s: usize, e: usize, last: bool, config: &Config) -> bool {
    shared_ends(pass, s, e, config).is_some_and(|(b, a)| if last { a } else { b })
        && matches!(
            classify::feature::<true>(pass, s, e, config),
            Some(Feature::Line(_))
        )
}

/// Whether the end beam `i` of a segment (its other points `rest`) is past the corner of its
/// line and the neighbouring surface's (on the side after `i` when `after`) and within the
/// noise of that surface's line: the line of the [`NEIGHBOUR`] to [`NEIGHBOUR_MAX`] points next
/// to `i` that are valid, without a range jump from `i` or between them, and on one line,
/// whose point next to `i` is off the line of `rest` (a corner, not the same surface).
fn shared(pass: &Pass<'_>, i: usize, rest: RangeInclusive<usize>, after: bool, var: f32) -> bool {
    let Some(rf) = pass.points.get(rest.clone()).and_then(|p| fit_line(p).ok()) else {
        return false;
    };
    // The rest's point next to `i`.
    let own = if after { *rest.end() } else { *rest.start() };
    let mut nf = None;
    for k in 1..=NEIGHBOUR_MAX {
        // The k-th neighbour, and the beam whose jump flag marks a jump before it (a jump flag
        // at j is one between j − 1 and j).
        let (j, flagged) = if after {
            (i + k, i + k)
        } else {
            let Some(j) = i.checked_sub(k) else { break };
            (j, j + 1)
        };
        if j >= pass.len() || !pass.valid(j) || pass.flag(flagged) & JUMP != 0 {
            break;
        }
        if k < NEIGHBOUR {
            continue;
        }
        let nb = if after { i + 1..=j } else { j..=i - 1 };
        let Some(f) = pass.points.get(nb).and_then(|p| fit_line(p).ok()) else {
            break;
        };
        let dof = f.n.saturating_sub(2).max(1) as f32;
        if !(residual(&f) <= LINE_CHI2 * dof * var) {
            break;
        }
        nf = Some(f);
    }
    let Some(nf) = nf else {
        return false;
    };
    let next = if after { i + 1 } else { i.saturating_sub(1) };
    // Non-finite values fail every test.
    chi2(&rf, pass.point(next), var) > LINE_CHI2
        && {
            let on = chi2(&nf, pass.point(i), var);
            on <= SHARED_CHI2 && on < chi2(&rf, pass.point(i), var)
        }
        && past_corner(&rf, &nf, pass.point(i), pass.point(own), var)
}

/// Sum of the squared distances of a fit's points from its line.
fn residual(f: &LineFit) -> f32 {
    let (s, c) = (f.sin_alpha, f.cos_alpha);
    c * c * f.sxx + s * s * f.syy + 2.0 * s * c * f.sxy
}

/// The squared distance of `p` from the line `f` in its σ: the range noise's (`var`) and that
/// of the line carried to `p`, `var (1/n + u²/Σu²)`, u its position along the line.
fn chi2(f: &LineFit, p: Point, var: f32) -> f32 {
    let (s, c) = (f.sin_alpha, f.cos_alpha);
    let u = (p.y - f.centroid.y) * c - (p.x - f.centroid.x) * s;
    let suu = s * s * f.sxx + c * c * f.syy - 2.0 * s * c * f.sxy;
    let d = p.x * c + p.y * s - f.rho;
    d * d / (var * (1.0 + 1.0 / f.n as f32 + u * u / suu))
}

/// Whether the corner where the lines `r` (the segment's other points) and `n` (the
/// neighbour's) meet lies in front of the scanner between the beams of `p` (the end point) and
/// `q` (the segment's point next to it), off `p`'s beam by more than [`CORNER_SIGMAS`] times
/// its σ there: `p`'s beam passes the corner on the neighbour's side. Which surface a beam near
/// the corner hit shows in its direction, known exactly, rather than in its range. The
/// corner's σ across the beam is that of each line there (`var` (1/n + u²/Σu²)) carried along
/// the other.
fn past_corner(r: &LineFit, n: &LineFit, p: Point, q: Point, var: f32) -> bool {
    let (s1, c1, s2, c2) = (r.sin_alpha, r.cos_alpha, n.sin_alpha, n.cos_alpha);
    // n₁·x = ρ₁, n₂·x = ρ₂ by Cramer's rule.
    let det = c1 * s2 - s1 * c2;
    let c = Point::new(
        (r.rho * s2 - n.rho * s1) / det,
        (c1 * n.rho - c2 * r.rho) / det,
    );
    let cross = |a: Point, b: Point| a.x * b.y - a.y * b.x;
    let norm = p.norm();
    let (ux, uy) = (p.x / norm, p.y / norm);
    // A shift of one line by δ moves the corner along the other by δ / |det|; across the beam
    // that is δ |u·n| / |det|, n the normal of the line it moves along.
    let (across_r, across_n) = (ux * c1 + uy * s1, ux * c2 + uy * s2);
    let var_c = (line_var(n, c, var) * across_r * across_r
        + line_var(r, c, var) * across_n * across_n)
        / (det * det);
    let off = cross(p, c) / norm * cross(p, q).signum();
    // Non-finite values fail every test.
    p.x * c.x + p.y * c.y > 0.0
        && off > 0.0
        && off * off > CORNER_SIGMAS * CORNER_SIGMAS * var_c
        && cross(q, c) * cross(q, p) > 0.0
}

/// The variance of the fitted line `f` at `p`, `var` (1/n + u²/Σu²).
fn line_var(f: &LineFit, p: Point, var: f32) -> f32 {
    let (s, c) = (f.sin_alpha, f.cos_alpha);
    let u = (p.y - f.centroid.y) * c - (p.x - f.centroid.x) * s;
    let suu = s * s * f.sxx + c * c * f.syy - 2.0 * s * c * f.sxy;
    var * (1.0 / f.n as f32 + u * u / suu)
}

#[cfg(test)]
#[allow(clippy::indexing_slicing)]
mod tests {
    use crate::config::Config;
    use crate::extractor::Extractor;
    use crate::feature::Feature;
    use crate::scan::{Scan, ScanGeometry};

    /// [`super::chi2`] is the point's squared distance from the line in the σ of its residual,
    /// σ_r² (1 + 1/n + u²/Σu²), u its position along the line from the centroid: points spaced
    /// 100 mm on a line at 0.3 rad, a point 12 mm off it 250 mm along from their centroid,
    /// against the same computed in f64 from the construction (3 and 10 points).
    #[test]
    fn chi2_is_the_distance_in_the_residual_s_sigma() {
        let (theta, h, d, u, var) = (0.3f64, 100.0f64, 12.0f64, 250.0f64, 25.0f64);
        let (t, nrm) = ((theta.cos(), theta.sin()), (-theta.sin(), theta.cos()));
        for n in [3usize, 10] {
            let pts: heapless::Vec<crate::geometry::Point, 16> = (0..n)
                .map(|k| {
                    let s = h * k as f64;
                    crate::geometry::Point::new((2000.0 + s * t.0) as f32, (500.0 + s * t.1) as f32)
                })
                .collect();
            let Ok(f) = crate::fit::line::fit_line(&pts) else {
                panic!("a line of {n} points")
            };
            let mean = h * (n as f64 - 1.0) / 2.0;
            let suu: f64 = (0..n).map(|k| (h * k as f64 - mean).powi(2)).sum();
            let c = (2000.0 + mean * t.0, 500.0 + mean * t.1);
            let p = crate::geometry::Point::new(
                (c.0 + u * t.0 + d * nrm.0) as f32,
                (c.1 + u * t.1 + d * nrm.1) as f32,
            );
            let expected = d * d / (var * (1.0 + 1.0 / n as f64 + u * u / suu));
            let got = f64::from(super::chi2(&f, p, var as f32));
            assert!(
                (got - expected).abs() <= 1e-3 * expected,
                "n {n}: {got} against {expected}"
            );
        }
    }

    /// [`super::residual`] is the sum of the squared distances of the fit's points from its
    /// line: four points 100 mm apart along a line at 0.3 rad through (2000, 500), set off it
    /// by +d, −d, −d, +d (their mean and their moment along the line zero, so the fitted line
    /// is the construction's), the sum 4 d² computed in f64 (d = 10 and 25 mm).
    #[test]
    fn residual_is_the_sum_of_the_squared_distances() {
        let (theta, h) = (0.3f64, 100.0f64);
        let (t, nrm) = ((theta.cos(), theta.sin()), (-theta.sin(), theta.cos()));
        for d in [10.0f64, 25.0] {
            let off = [d, -d, -d, d];
            let pts: [crate::geometry::Point; 4] = core::array::from_fn(|k| {
                let s = h * k as f64;
                crate::geometry::Point::new(
                    (2000.0 + s * t.0 + off[k] * nrm.0) as f32,
                    (500.0 + s * t.1 + off[k] * nrm.1) as f32,
                )
            });
            let Ok(f) = crate::fit::line::fit_line(&pts) else {
                panic!("a line of 4 points")
            };
            let expected: f64 = off.iter().map(|o| o * o).sum();
            let got = f64::from(super::residual(&f));
            assert!(
                (got - expected).abs() <= 1e-3 * expected,
                "d {d}: {got} against {expected}"
            );
        }
    }

    /// The features (kind, first beam, last beam) of an LMS200 scan (180°, 0.5°) whose beams
    /// from `first` have the ranges `run` and the others no return.
    fn lines(first: usize, run: &[f32]) -> heapless::Vec<(usize, usize), 16> {
        let ranges: [f32; 361] = core::array::from_fn(|i| {
            i.checked_sub(first)
                .and_then(|k| run.get(k))
                .map_or(0.0, |r| *r)
        });
        let mut ex = Extractor::<361, 16>::new();
        assert!(ex
            .extract(
                &Scan::from_mm(ScanGeometry::LMS200_180_050, &ranges),
                &Config::default()
            )
            .is_ok());
        ex.features()
            .iter()
            .filter(|f| matches!(f, Feature::Line(_)))
            .map(|f| (f.first(), f.last()))
            .collect()
    }

    /// Corridor (seed 2, σ_r 5 mm) scan 57, beams 150..=215 as simulated: a face seen over
    /// beams 168..=170 (the simulator's truth; no return before it) meets at a corner the
    /// face of beams 171..=175, whose walk segment is 172..=174. Beam 171, past the corner,
    /// is the second face's: the first face's three beams are no line, and the second face's
    /// segment takes the beam and is a line of four.
    #[test]
    fn a_corner_beam_goes_to_the_face_it_hit() {
        let run = [
            6829.0, 6843.0, 6867.0, 6879.0, 6878.0, 6668.0, 6487.0, 6295.0, 6120.0, 5953.0, 5801.0,
            0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 4808.0, 4710.0, 4610.0, 4541.0, 4566.0, 4575.0,
            4609.0, 4640.0, 4552.0, 4471.0, 4405.0, 4330.0, 4261.0, 4195.0, 4130.0, 4053.0, 4001.0,
            3943.0, 3902.0, 3484.0, 3434.0, 3382.0, 3336.0, 3302.0, 3256.0, 3218.0, 3175.0, 3138.0,
            3101.0, 3070.0, 3031.0, 2989.0, 2957.0, 2927.0, 2904.0, 2877.0, 2844.0, 2816.0, 2787.0,
            2752.0, 2729.0, 2705.0, 2683.0, 2652.0, 2628.0, 2616.0, 2592.0, 2564.0,
        ];
        let l = lines(150, &run);
        assert!(l.iter().all(|&(a, _)| a != 168), "{l:?}");
        assert!(l.contains(&(171, 174)), "{l:?}");
    }

    /// Mixed (seed 1, σ_r 5 mm) scan 72, beams 70..=119 as simulated: a face of four beams
    /// (76..=79 in the simulator's truth) between two walls, whose corner beam 76 the wall
    /// before keeps; its segment 77..=80 ends on the next wall's first beam. It stays a line:
    /// beam 76 may be its own.
    #[test]
    fn a_four_beam_face_stays_a_line() {
        let run = [
            3837.0, 3823.0, 3798.0, 3780.0, 3769.0, 3733.0, 3728.0, 3782.0, 3847.0, 3908.0, 3957.0,
            3941.0, 3926.0, 3920.0, 3897.0, 3872.0, 3855.0, 3841.0, 3824.0, 3823.0, 3806.0, 3787.0,
            3777.0, 3766.0, 3759.0, 3736.0, 3716.0, 3710.0, 3704.0, 3697.0, 3687.0, 3674.0, 3662.0,
            3654.0, 3642.0, 3634.0, 3626.0, 3624.0, 3616.0, 3605.0, 3604.0, 3593.0, 3596.0, 3577.0,
            3570.0, 3566.0, 3568.0, 3554.0, 3550.0, 3543.0,
        ];
        let l = lines(70, &run);
        assert!(
            l.iter()
                .any(|&(a, b)| (76..=77).contains(&a) && (79..=80).contains(&b)),
            "{l:?}"
        );
    }

    /// A wall grazed by the beams (10° off them) meets at a corner a wall the beams hit head on
    /// (the scene turned 0.5 rad about the scanner); exact points, σ_r 5 mm. The corner's σ across the beam is that of each line there
    /// carried along the other (`line_var` (u·n_other)² / det²): 0.49 σ_r here, where the
    /// grazed wall's own σ along the beam would give 0.91 σ_r. A beam of the second wall
    /// 2.65 or 3.5 mm past the corner is past it by more than half that σ (2.43 mm); one
    /// 1.5 mm past is not.
    #[test]
    fn the_corner_is_passed_by_half_its_sigma_across_the_beam() {
        use super::{fit_line, past_corner, Point};
        let (sf, cf) = 0.5f32.sin_cos();
        let turn = |x: f32, y: f32| Point::new(cf * x - sf * y, sf * x + cf * y);
        let (s10, c10) = 10f32.to_radians().sin_cos();
        // The grazed wall before the corner (8 points, 100..450 mm from it) and 3 points of
        // the head-on wall after it (30, 60, 90 mm).
        let grazed: [Point; 8] = core::array::from_fn(|k| {
            let t = 100.0 + 50.0 * k as f32;
            turn(3000.0 - t * c10, -t * s10)
        });
        let head_on: [Point; 3] = core::array::from_fn(|k| turn(3000.0, 30.0 * (k + 1) as f32));
        let (r, n) = (fit_line(&grazed).unwrap(), fit_line(&head_on).unwrap());
        let var = 25.0;
        let past = |d: f32| past_corner(&r, &n, turn(3000.0, d), grazed[0], var);
        assert!(past(3.5));
        assert!(past(2.65));
        assert!(!past(1.5));
        assert!(!past(-3.5));
    }

    /// Ranges at 1° of a wall 3 m ahead (x = 3000 mm) over beams 80..=97 and, from a corner
    /// `past`° past beam 97's bearing, a face at 45° running from the wall towards the scanner
    /// over beams 98..=100; exact, other beams see nothing.
    fn wall_then_face(past: f32) -> [f32; 181] {
        let g = ScanGeometry::lms200(180.0, 1.0);
        let (sc, cc) = (g.bearing(97) + past.to_radians()).sin_cos();
        let (cx, cy) = (3000.0, 3000.0 * sc / cc);
        let h = core::f32::consts::FRAC_1_SQRT_2;
        // The face's normal (1, 1)/√2 and distance from the scanner.
        let rho = h * (cx + cy);
        core::array::from_fn(|i| {
            let (s, c) = g.bearing(i).sin_cos();
            match i {
                80..=97 => 3000.0 / c,
                98..=100 => rho / (h * (c + s)),
                _ => f32::NAN,
            }
        })
    }

    /// The features (first beam, last beam) of [`wall_then_face`] after the segment step, the
    /// walk's marks starting segments at beams 80 and 97 (the wall's last beam counted into the
    /// face's segment), and whether the face's segment 97..=100 has its first beam shared.
    fn after_segments(past: f32) -> (Option<bool>, heapless::Vec<(usize, usize), 8>) {
        use crate::flags::START;
        let config = Config::default();
        let ranges = wall_then_face(past);
        let mut ex = Extractor::<181, 8>::new();
        ex.with_pass(
            &Scan::from_mm(ScanGeometry::lms200(180.0, 1.0), &ranges),
            &config,
            |pass, rule| {
                let shared = super::shared_ends(pass, 97, 100, &config).map(|(b, _)| b);
                pass.set(80, START);
                pass.set(97, START);
                let mut out: heapless::Vec<Feature, 8> = heapless::Vec::new();
                super::super::segments(pass, rule, &config, &mut out);
                (shared, out.iter().map(|f| (f.first(), f.last())).collect())
            },
        )
    }

    /// A segment's first beam is the previous surface's: a wall (beams 80..=97) meets a face
    /// of three beams (98..=100) at a corner 0.15° or 0.5° past beam 97, exact ranges, and the
    /// walk starts the face's segment at 97. Beam 97 lies on the wall's line, past the corner
    /// of the wall's and the face's lines fitted to the other beams: it goes back to the wall,
    /// and the face's three beams are no line. At 0.15° (7.9 mm across the beam at 3 m) only
    /// the hand-over sees it; the corner point's move (1 σ) does not.
    #[test]
    fn a_segment_s_first_beam_goes_back_to_the_surface_before() {
        for past in [0.15, 0.5] {
            let (shared, lines) = after_segments(past);
            assert_eq!(shared, Some(true), "{past}");
            assert_eq!(lines.as_slice(), [(80, 97)], "{past}");
        }
    }

    /// A face of four beams (90..=93, LMS200 180° at 1°) meeting a wall at a corner 3 m away,
    /// 0.6 of a beam step past beam 90 (exact points, σ_r 5 mm): beam 90 is the wall's, so the
    /// face has three beams of its own. The beam after it (94) lies on the face's line: counted
    /// as the face's, it makes four, and the face keeps beam 90 ([`super::shared_ends`] is
    /// `None`). Across a range jump (flagged at 94, as the walk flags a grazing wall's far
    /// points) it is not the face's beam: three, and beam 90 goes to the wall.
    #[test]
    fn a_beam_across_a_jump_is_not_the_face_s() {
        use crate::geometry::Point;
        let g = ScanGeometry::lms200(180.0, 1.0);
        let config = Config::default();
        let beta = g.bearing(90) + 0.6 * g.angle_step;
        let corner = Point::new(3000.0 * libm::cosf(beta), 3000.0 * libm::sinf(beta));
        // Each surface's line through the corner: normal angle and distance.
        let line = |alpha: f32| {
            (
                alpha,
                corner.x * libm::cosf(alpha) + corner.y * libm::sinf(alpha),
            )
        };
        let (wall, face) = (line(beta - 0.7), line(beta + 0.7));
        let ranges: [f32; 181] = core::array::from_fn(|i| {
            let (alpha, rho) = match i {
                60..=90 => wall,
                91..=120 => face,
                _ => return f32::NAN,
            };
            rho / libm::cosf(g.bearing(i) - alpha)
        });
        for jump in [false, true] {
            let mut ex = Extractor::<181, 8>::new();
            let shared = ex.with_pass(&Scan::from_mm(g, &ranges), &config, |pass, _| {
                if jump {
                    pass.set(94, crate::flags::JUMP);
                }
                super::shared_ends(pass, 90, 93, &config)
            });
            let expected = jump.then_some((true, false));
            assert_eq!(shared, expected, "jump {jump}");
        }
    }
}
