//! Odometry given (`Scan::with_motion`) against analytic truth: rooms ray-cast with every beam
//! from the exact pose (f64 arc of a circle) of a robot at 0.6 m/s turning at 0.45 rad/s when
//! that beam was taken, the LMS200's interleaved sweeps one mirror turn (13.33 ms) apart.
//! De-skewed, interleaved sweeps are exact but not evenly spaced in bearing (a short and a
//! long step in turn; close to the scanner one sweep's point passes the other's), and the
//! walk must hold up on them; a scanner standing still must give what it gives without
//! odometry, bit for bit.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

mod common;

use common::{cast, Noise, Prim};
use pfe_core::{BeamTiming, Config, Extractor, Feature, Motion, Scan, ScanGeometry};

const TURN_S: f64 = 1.0 / 75.0;

/// When beam `i` of a scan of `sweeps` interleaved 1° sweeps is taken, s after beam 0.
fn beam_time(i: usize, sweeps: usize) -> f64 {
    (i % sweeps) as f64 * TURN_S + (i / sweeps) as f64 * TURN_S / 360.0
}

/// Pose (x, y, θ) at time `t` of a robot starting at the origin heading along x, at forward
/// speed `v` mm/s turning at `omega` rad/s.
fn pose_at(v: f64, omega: f64, t: f64) -> (f64, f64, f64) {
    let th = omega * t;
    if omega == 0.0 {
        return (v * t, 0.0, 0.0);
    }
    (v / omega * th.sin(), v / omega * (1.0 - th.cos()), th)
}

/// Ranges of `prims` (frame of beam 0) with beam `i` cast from its own pose, σ_r noise, and
/// the primitive each beam hits.
fn render(
    prims: &[Prim],
    g: ScanGeometry,
    n: usize,
    sweeps: usize,
    (v, omega): (f64, f64),
    sigma: f64,
    noise: &mut Noise,
) -> (Vec<f32>, Vec<Option<usize>>) {
    (0..n)
        .map(|i| {
            let local = common::seen_from(prims, pose_at(v, omega, beam_time(i, sweeps)));
            match cast(&local, f64::from(g.bearing(i))) {
                Some((t, p)) if t < 7900.0 => ((t + sigma * noise.gauss()) as f32, Some(p)),
                _ => (f32::NAN, None),
            }
        })
        .unzip()
}

/// A room 5–9 × 4–7 m with a pillar and a box near the robot, seen from a random pose
/// inside it.
fn room(noise: &mut Noise) -> Vec<Prim> {
    let u = |n: &mut Noise| n.gauss().clamp(-2.0, 2.0) / 4.0 + 0.5;
    let mut prims = common::room(noise);
    // A box 0.6–1.2 m from the robot, at any bearing: close enough for the sweeps to pass
    // each other.
    let (d, b, side) = (
        600.0 + 600.0 * u(noise),
        6.0 * u(noise),
        300.0 + 400.0 * u(noise),
    );
    let (bs, bc) = b.sin_cos();
    let (cx, cy) = (d * bc, d * bs);
    let box_corners = [(0.0, 0.0), (side, 0.0), (side, side), (0.0, side)]
        .map(|(ex, ey)| (cx + bc * ex - bs * ey, cy + bs * ex + bc * ey));
    for k in 0..4 {
        let (a, e) = (box_corners[k], box_corners[(k + 1) % 4]);
        prims.push(Prim::Seg(a.0, a.1, e.0, e.1));
    }
    prims
}

/// Marks and features of `ranges` with `sweeps` declared and, when given, the odometry.
fn extract(
    ex: &mut Extractor<361, 64>,
    g: ScanGeometry,
    ranges: &[f32],
    sweeps: u8,
    motion: Option<Motion>,
) -> (Vec<usize>, Vec<Feature>) {
    let mut scan = Scan::from_mm(g, ranges).with_sweeps(sweeps);
    if let Some(m) = motion {
        scan = scan.with_motion(m);
    }
    ex.extract(&scan, &Config::default().with_sigma_r(5.0))
        .unwrap();
    (ex.marks().collect(), ex.features().to_vec())
}

/// The odometry of the robot of this file at `resolution_deg`.
fn moving(resolution_deg: f32) -> Motion {
    Motion {
        v: 600.0,
        omega: 0.45,
        timing: BeamTiming::lms2xx(resolution_deg),
    }
}

/// Odometry of a scanner standing still (v = ω = 0) changes nothing: the same marks and
/// features, bit for bit, at 0.5° (two sweeps declared) and 1°, over 100 rooms.
#[test]
fn odometry_of_a_scanner_standing_still_changes_nothing() {
    let mut noise = Noise::new(41);
    let mut ex = Extractor::<361, 64>::new();
    for (g, n, sweeps) in [
        (ScanGeometry::LMS200_180_050, 361, 2u8),
        (ScanGeometry::lms200(180.0, 1.0), 181, 1),
    ] {
        let res = g.angle_step.to_degrees();
        let still = Motion {
            v: 0.0,
            omega: 0.0,
            timing: BeamTiming::lms2xx(res),
        };
        for _ in 0..100 {
            let prims = room(&mut noise);
            let (ranges, _) = render(&prims, g, n, 1, (0.0, 0.0), 5.0, &mut noise);
            let without = extract(&mut ex, g, &ranges, sweeps, None);
            let with = extract(&mut ex, g, &ranges, sweeps, Some(still));
            assert_eq!(with, without, "{res}°");
        }
    }
}

/// A wall 0.5–2.5 m to the right or the left of a robot driving along it at 0.6 m/s, turning
/// at 0.45 rad/s: de-skewed, each point of the second sweep lies past the next point of the
/// first within 3 m (8 mm forward and 6 mrad turned against the 8.7 mrad beam step), so the
/// points go back and forth along the wall. With the odometry given the wall is one line over
/// every beam on it, with no mark inside, at the wall's (ρ, α) in the frame of beam 0 within
/// 2 mm and 5 mrad.
#[test]
fn sweeps_that_pass_each_other_close_to_the_scanner_are_one_wall() {
    let g = ScanGeometry::LMS200_180_050;
    let mut ex = Extractor::<361, 64>::new();
    let mut noise = Noise::new(47);
    for d in [500.0, 800.0, 1500.0, 2500.0] {
        for side in [-1.0, 1.0] {
            let wall = [Prim::Seg(-3000.0, side * d, 3000.0, side * d)];
            for _ in 0..10 {
                let (ranges, hits) = render(&wall, g, 361, 2, (600.0, 0.45), 5.0, &mut noise);
                let on: Vec<usize> = (0..361).filter(|&i| hits[i].is_some()).collect();
                let (first, last) = (on[0], *on.last().unwrap());
                let (marks, features) = extract(&mut ex, g, &ranges, 2, Some(moving(0.5)));
                let inside: Vec<usize> = marks
                    .iter()
                    .copied()
                    .filter(|&m| m > first + 1 && m + 1 < last)
                    .collect();
                assert!(
                    inside.is_empty(),
                    "{d} mm, {side}: marks in {first}..{last}: {inside:?}"
                );
                let lines: Vec<_> = features
                    .iter()
                    .filter_map(|f| match f {
                        Feature::Line(l) => Some(l),
                        _ => None,
                    })
                    .collect();
                assert_eq!(lines.len(), 1, "{d} mm, {side}: {features:?}");
                let l = lines[0];
                assert!(usize::from(l.first) <= first + 1 && usize::from(l.last) + 1 >= last);
                assert!((f64::from(l.rho) - d).abs() < 2.0, "{d} mm: ρ {}", l.rho);
                let da = (f64::from(l.alpha) - side * std::f64::consts::FRAC_PI_2).abs();
                assert!(da < 5e-3, "{d} mm, {side}: α {}", l.alpha);
            }
        }
    }
}

/// A pillar 0.4–0.8 m ahead of a wall 2–3 m away, seen by the robot of this file: at the
/// pillar's edges the two sweeps take the pillar and the wall in turn (pillar, wall, pillar
/// one beam apart). With the odometry given, no feature holds, between its ends, a beam of
/// another surface than most of its beams or a beam without a return (its two end beams are
/// not tested): the check step does not join the pillar's points across a wall point because a
/// line through such a window predicts the next pillar point. Over 300 placements; with the
/// check step's out-and-back test removed, 11 features fail.
#[test]
fn no_feature_holds_a_beam_of_the_surface_behind_an_edge() {
    let g = ScanGeometry::LMS200_180_050;
    let mut ex = Extractor::<361, 64>::new();
    let mut noise = Noise::new(53);
    let u = |n: &mut Noise| n.gauss().clamp(-2.0, 2.0) / 4.0 + 0.5;
    let mut edges = 0;
    for _ in 0..300 {
        let (d, b, r) = (
            400.0 + 400.0 * u(&mut noise),
            2.0 * u(&mut noise) - 1.0,
            150.0 + 150.0 * u(&mut noise),
        );
        let wall = 2000.0 + 1000.0 * u(&mut noise);
        let prims = [
            Prim::Seg(wall, -6000.0, wall, 6000.0),
            Prim::Circle(d * b.cos(), d * b.sin(), r),
        ];
        let (ranges, hits) = render(&prims, g, 361, 2, (600.0, 0.45), 5.0, &mut noise);
        edges += (1..360)
            .filter(|&i| hits[i - 1] == Some(1) && hits[i] == Some(0) && hits[i + 1] == Some(1))
            .count();
        let (_, features) = extract(&mut ex, g, &ranges, 2, Some(moving(0.5)));
        for f in &features {
            let (first, last) = (f.first(), f.last());
            let on = |p: usize| (first..=last).filter(|&i| hits[i] == Some(p)).count();
            let most = if on(1) > on(0) { Some(1) } else { Some(0) };
            let strays: Vec<usize> = (first + 1..last).filter(|&i| hits[i] != most).collect();
            assert!(
                strays.is_empty(),
                "pillar at {d:.0} mm, {b:.2} rad, r {r:.0}; wall {wall:.0}: feature {first}..{last} holds {strays:?}"
            );
        }
    }
    // The scenes do have pillar, wall, pillar edges.
    assert!(edges > 50, "{edges}");
}
