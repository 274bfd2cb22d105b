//! The check step (§3.3): wherever `Np` mark points follow each other, predict the next point
//! from them; when it fits, the marks after the first were caused by a window straddling the
//! boundary and are removed. Runs of 2..Np marks (a straddling window can fit by chance, e.g.
//! when the boundary point lies on both surfaces, as at a corner) get the same test with the
//! run's own points as the window; a run longer than `Np` is tested at its last `Np` points, so
//! its first marks stay. Runs at the end of a valid stretch are left alone.

use crate::config::NP;
use crate::flags::{next_flag, Seek, JUMP, START};
use crate::geometry::Point;
use crate::math;
use crate::pass::Pass;
use crate::rule::Rule;

/// Applies the check step to the marks of `pass`. `noted`: the segment starts the default
/// mode's walk set right after another one, in increasing order, when it noted them all (else
/// every flag is read); `moved`: interleaved sweeps were moved onto sweep 0 by an estimate of
/// their offset (see [`out_and_back`]).
#[inline(never)]
pub(crate) fn check(pass: &mut Pass<'_>, rule: &Rule, noted: Option<&[u16]>, moved: bool) {
    match noted {
        // The default mode's walk noted every start next to another (in increasing order):
        // the runs of marks are where they are.
        Some(list) => {
            let mut done = 0usize;
            for i in list.iter().map(|&i| usize::from(i)) {
                if i < done || pass.flag(i) & Seek::MARK != Seek::MARK {
                    continue;
                }
                let mut j = i;
                while j > done && pass.flag(j - 1) & Seek::MARK == Seek::MARK {
                    j -= 1;
                }
                done = check_run(pass, j, rule, moved);
            }
        }
        None => {
            let mut j = 0usize;
            while let Some(start) = next_flag(pass.flags, j, Seek::Mark) {
                j = check_run(pass, start, rule, moved);
            }
        }
    }
}

/// The check step for the run of marks starting at `j`; returns the point after it.
#[inline(always)]
fn check_run(pass: &mut Pass<'_>, j: usize, rule: &Rule, moved: bool) -> usize {
    let len = pass.len();
    let next = next_flag(pass.flags, j + 1, Seek::NotMark).unwrap_or(len);
    let e = next - 1;
    if e > j && next < len && pass.valid(next) {
        let from = (e + 1).saturating_sub(NP).max(j);
        let pred = pass.predict_next(from, next);
        let fits = !rule.marks(pred, pass.range(next));
        if fits && (moved || !out_and_back(pass, rule, from, e, next)) {
            for i in from + 1..next {
                pass.clear(i, START);
            }
        }
    }
    next
}

/// Whether the window `from ..= e` with the point `next` after it jumps away and back (a
/// point of it starts a segment by a jump and a step goes back along the window by more than
/// the noise): not one surface, whatever line fits it. The interleaved sweeps of a turning
/// scanner, de-skewed by its odometry, take the foreground and the background in turn at an
/// occluding edge, and a line through two nearly coincident foreground points and a background
/// one may well predict the next foreground point; in one sweep, a jump onto a surface that
/// comes back towards the scanner does the same. Not where sweeps were moved by an estimate of
/// their offset: its error zigzags their points along one surface, and the prediction alone
/// decides there ([`check_run`] does not ask).
fn out_and_back(pass: &Pass<'_>, rule: &Rule, from: usize, e: usize, next: usize) -> bool {
    let tol = rule.noise().map_or(0.0, |n| n.k_sigma + n.model.floor);
    (from + 1..=e).any(|i| pass.flag(i) & JUMP != 0)
        && !pass
            .points
            .get(from..=next)
            .is_none_or(|pts| onward(pts, tol))
}

/// Whether no step of `points` goes back by more than `tol` mm along the chord from the first
/// to the last, as consecutive beams along one surface do not.
fn onward(points: &[Point], tol: f32) -> bool {
    let (Some(a), Some(b)) = (points.first(), points.last()) else {
        return true;
    };
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    let back = tol * math::sqrt(dx * dx + dy * dy);
    points
        .iter()
        .zip(points.iter().skip(1))
        .all(|(p, q)| (q.x - p.x) * dx + (q.y - p.y) * dy >= -back)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Config;
    use crate::extractor::Extractor;
    use crate::flags::VALID;
    use crate::math;
    use crate::scan::{Scan, ScanGeometry};

    /// The flags after the check step over a wall 3 m ahead (beams within ±60°, none beyond)
    /// whose only marks are `marks`, reading every flag and (when `noted`) only the noted
    /// neighbours.
    fn checked(marks: &[usize], noted: bool) -> [u8; 361] {
        let g = ScanGeometry::LMS200_180_050;
        let ranges: [f32; 361] = core::array::from_fn(|i| {
            let b = g.bearing(i);
            if math::abs(b) < 1.05 {
                3000.0 / math::sin_cos(b).1
            } else {
                f32::NAN
            }
        });
        let scan = Scan::from_mm(g, &ranges);
        Extractor::<361, 8>::new().with_pass(&scan, &Config::default(), |pass, rule| {
            for &i in marks {
                pass.set(i, START);
            }
            let mut list = heapless::Vec::<u16, 16>::new();
            for w in marks.windows(2).filter(|w| w[1] == w[0] + 1) {
                let _ = list.push(w[1] as u16);
            }
            check(pass, rule, Some(&list[..]).filter(|_| noted), false);
            let mut flags = [0u8; 361];
            flags.copy_from_slice(pass.flags);
            flags
        })
    }

    /// Steps along the chord of a window go on; one step back along it by more than `tol`
    /// (here 10 mm) does not, by 9 mm does, whatever the chord's length, direction and place;
    /// sideways steps of any size go on; fewer than two points go on.
    #[test]
    fn a_window_goes_on_unless_a_step_goes_back_by_more_than_tol() {
        for (sx, turn, (ox, oy)) in [
            (1.0f32, 0.0f32, (0.0f32, 0.0f32)),
            (-1.0, 0.7, (700.0, -300.0)),
            (3.0, -2.2, (-1500.0, 2500.0)),
        ] {
            let (s, c) = math::sin_cos(turn);
            // (x, y) along and across the chord, x stretched by sx, turned and moved.
            let at = |x: f32, y: f32| Point::new(ox + c * sx * x - s * y, oy + s * sx * x + c * y);
            assert!(onward(
                &[at(0.0, 0.0), at(50.0, 3.0), at(100.0, -4.0), at(100.0, 0.0)],
                10.0
            ));
            assert!(onward(
                &[at(0.0, 0.0), at(60.0, 900.0), at(100.0, 0.0)],
                10.0
            ));
            let back = |by: f32| {
                [
                    at(0.0, 0.0),
                    at(60.0, 0.0),
                    at(60.0 - by, 0.0),
                    at(100.0, 0.0),
                ]
            };
            assert!(onward(&back(9.0 / sx.abs()), 10.0), "{sx}");
            assert!(!onward(&back(11.0 / sx.abs()), 10.0), "{sx}");
            // Out to the background and back.
            let out = [at(0.0, 0.0), at(40.0, 2000.0), at(10.0, 0.0), at(20.0, 0.0)];
            assert!(!onward(&out, 10.0), "{sx}");
        }
        let p = Point::new(1.0, 2.0);
        assert!(onward(&[p], 0.0) && onward(&[], 0.0));
    }

    /// The marks after the check step of the run `60..=63` (its window 61..=63, the next point
    /// 64) on a wall 800 mm to the right of a scanner driving at 1.2 m/s and turning at 0.9 rad/s
    /// (12 mrad a mirror turn, more than the 8.7 mrad beam step), with its odometry: de-skewed,
    /// the points of the two sweeps change places along the wall, so that from 62 to 63 the
    /// window goes back 39 mm along its chord (σ_r = `sigma_r`: with 5 mm more than the 23 mm
    /// of `k σ + floor`, with 10 mm less than its 43 mm). `jumps` are the marks also set as
    /// jumps.
    fn checked_on_a_passed_wall(sigma_r: f32, jumps: &[usize]) -> heapless::Vec<usize, 64> {
        use crate::motion::{BeamTiming, Motion};
        let g = ScanGeometry::LMS200_180_050;
        let (v, omega, d) = (1200.0f64, 0.9f64, -800.0f64);
        let ranges: [f32; 361] = core::array::from_fn(|i| {
            // Beam i's time: its sweep's mirror turn (1/75 s) and its place in the sweep; the
            // wall y = d seen from the pose then (x does not change the range to it).
            let t = (i % 2) as f64 / 75.0 + (i / 2) as f64 / 75.0 / 360.0;
            let th = omega * t;
            let y = v / omega * (1.0 - libm::cos(th));
            let sin = libm::sin(th + f64::from(g.bearing(i)));
            if sin < -0.2 {
                ((d - y) / sin) as f32
            } else {
                f32::NAN
            }
        });
        let motion = Motion {
            v: v as f32,
            omega: omega as f32,
            timing: BeamTiming::lms2xx(0.5),
        };
        let scan = Scan::from_mm(g, &ranges).with_sweeps(2).with_motion(motion);
        let config = Config::default().with_sigma_r(sigma_r);
        Extractor::<361, 8>::new().with_pass(&scan, &config, |pass, rule| {
            for i in 60..=63 {
                pass.set(i, START);
            }
            for &i in jumps {
                pass.set(i, JUMP);
            }
            check(pass, rule, None, false);
            starts(pass.flags)
        })
    }

    /// On one surface whose de-skewed points go back and forth along it, the prediction alone
    /// decides: a window with no jump, or with jumps only before its second point (where the
    /// surface begins), is cleared after its first point; a jump inside it keeps it, unless
    /// the window goes back by no more than the noise.
    #[test]
    fn only_a_jump_inside_the_window_calls_for_the_out_and_back_test() {
        assert_eq!(checked_on_a_passed_wall(5.0, &[])[..], [60, 61]);
        assert_eq!(checked_on_a_passed_wall(5.0, &[60, 61])[..], [60, 61]);
        for jump in [62, 63] {
            assert_eq!(checked_on_a_passed_wall(5.0, &[jump])[..], [60, 61, 62, 63]);
            assert_eq!(checked_on_a_passed_wall(10.0, &[jump])[..], [60, 61]);
        }
    }

    fn starts(flags: &[u8]) -> heapless::Vec<usize, 64> {
        (0..flags.len())
            .filter(|&i| flags[i] & (VALID | START) == VALID | START)
            .collect()
    }

    /// A run of marks on the wall whose next point its last `NP` points predict keeps only
    /// the marks up to the window's first point (a longer run keeps its first ones); a run
    /// ended by an invalid reading or by the end of the valid beams, and a lone mark, stay.
    #[test]
    fn a_run_of_marks_is_cleared_after_its_last_window_only_where_the_next_point_fits() {
        let valid = (0..361).filter(|&i| checked(&[], false)[i] & VALID != 0);
        let (lo, hi) = (valid.clone().min().unwrap(), valid.max().unwrap());
        assert_eq!((lo, hi), (60, 300));
        for noted in [false, true] {
            // NP + 3 marks: the last NP are the window, the marks after its first go.
            let run: heapless::Vec<usize, 8> = (150..150 + NP + 3).collect();
            let kept: heapless::Vec<usize, 8> = (150..=150 + 3).collect();
            assert_eq!(starts(&checked(&run, noted)), kept, "noted {noted}");
            // Two marks: the window is the run.
            assert_eq!(
                starts(&checked(&[200, 201], noted))[..],
                [200],
                "noted {noted}"
            );
            // A lone mark stays.
            assert_eq!(starts(&checked(&[120], noted))[..], [120], "noted {noted}");
            // Runs ending at the last valid beam stay.
            let end: heapless::Vec<usize, 8> = (hi - 3..=hi).collect();
            assert_eq!(starts(&checked(&end, noted)), end, "noted {noted}");
        }
    }
}
