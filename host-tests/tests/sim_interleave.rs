//! The simulated LMS200's interleaved sweeps, the moving scanner, cm mode and incidence noise,
//! against analytic truth and against pfe-core's beam-timing model.

use pfe_core::{BeamTiming, LMS_MAX_VALID_8M};
use pfe_eval::scene::{
    bearing, incidence_noise_factor, render, RangeMode, Resolution, Scenario, SceneKind, Shape,
    NO_RETURN_CODE,
};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

const TURN: f64 = 1.0 / 75.0;
const WALL_X: f64 = 5000.0;

/// A wall at x = 5 m across the whole field.
fn wall() -> [Shape; 1] {
    [Shape::Segment {
        a: [WALL_X, -30000.0],
        b: [WALL_X, 30000.0],
    }]
}

/// A noiseless 0.5° scenario moving at `v` mm/s and turning at `omega` rad/s.
fn moving(v: f32, omega: f32) -> Scenario {
    Scenario::new(SceneKind::Office, 0)
        .with_sigma(0.0)
        .with_motion(v, omega)
}

/// Beam `i`'s time at 0.5°: sweep `i mod 2` one mirror turn later, 1° per TURN / 360.
fn t_half(i: usize) -> f64 {
    (i % 2) as f64 * TURN + (i / 2) as f64 * TURN / 360.0
}

#[test]
fn driving_at_a_wall_odd_sweep_is_8_mm_closer() {
    let sim = render(
        &wall(),
        &moving(600.0, 0.0),
        &mut ChaCha8Rng::seed_from_u64(1),
    );
    let mut pairs = 0;
    let mut measured = Vec::new();
    for i in 0..sim.true_ranges_mm.len() {
        let r = sim.true_ranges_mm[i];
        if !r.is_finite() {
            continue;
        }
        let b = bearing(&sim.geometry, i);
        // Exact: the scanner is 600 mm/s · t_i further forward.
        let expect = (WALL_X - 600.0 * t_half(i)) / b.cos();
        assert!((r - expect).abs() < 1e-6, "beam {i}: {r} vs {expect}");
        let r_next = sim.true_ranges_mm.get(i + 1).copied().unwrap_or(f64::NAN);
        if i % 2 == 0 && r_next.is_finite() {
            let d_even = r * b.cos();
            let d_odd = r_next * bearing(&sim.geometry, i + 1).cos();
            assert!((d_even - d_odd - 8.0).abs() < 1e-6, "beams {i}, {}", i + 1);
            let m = f64::from(sim.ranges_mm[i]) * b.cos()
                - f64::from(sim.ranges_mm[i + 1]) * bearing(&sim.geometry, i + 1).cos();
            measured.push(m);
            pairs += 1;
        }
    }
    assert!(pairs > 100, "{pairs} even/odd pairs on the wall");
    // The quantised ranges show it too (1 mm quantum, mean over the pairs).
    let mean = measured.iter().sum::<f64>() / measured.len() as f64;
    assert!((mean - 8.0).abs() < 0.3, "measured even - odd {mean} mm");
}

#[test]
fn turning_shifts_the_odd_sweep_30_mm_sideways_at_5_m() {
    let omega = 0.45;
    let sim = render(
        &wall(),
        &moving(0.0, omega),
        &mut ChaCha8Rng::seed_from_u64(1),
    );
    for i in 0..sim.true_ranges_mm.len() {
        let r = sim.true_ranges_mm[i];
        if !r.is_finite() {
            continue;
        }
        // Beam i leaves at its nominal bearing turned by ω t_i.
        let b = bearing(&sim.geometry, i) + f64::from(omega) * t_half(i);
        let expect = WALL_X / b.cos();
        assert!((r - expect).abs() < 1e-6, "beam {i}: {r} vs {expect}");
    }
    // The odd beam at 0.5°, 5 m away: its nominal point, seen from the even sweep (turned
    // back by the rotation between the sweeps), moves sideways by ω · 13.33 ms · 5 m.
    let i = 181;
    assert!((t_half(i) - t_half(i - 1) - TURN).abs() < 1e-12);
    let r = sim.true_ranges_mm[i];
    let b = bearing(&sim.geometry, i);
    let dtheta = f64::from(omega) * TURN;
    let nominal = [r * b.cos(), r * b.sin()];
    let from_even = [r * (b + dtheta).cos(), r * (b + dtheta).sin()];
    let shift = (from_even[0] - nominal[0]).hypot(from_even[1] - nominal[1]);
    assert!((shift - 30.0).abs() < 0.2, "sideways shift {shift} mm");
    assert!((nominal[0] - WALL_X).abs() < 1.0 && (from_even[1] - nominal[1]) > 29.8);
}

#[test]
fn beam_times_agree_with_pfe_core_to_1_us() {
    for res in [Resolution::One, Resolution::Half, Resolution::Quarter] {
        let timing = BeamTiming::lms2xx(res.degrees() as f32);
        assert_eq!(timing.sweep_count(), res.sweeps());
        for i in 0..res.beams() {
            let ours = res.beam_time(i);
            let theirs = f64::from(timing.time(i));
            assert!(
                (ours - theirs).abs() < 1e-6,
                "{res:?} beam {i}: {ours} vs {theirs}"
            );
            assert_eq!(res.sweep_of(i), timing.sweep(i));
        }
        // The last beam (+90°) closes the first sweep, half a turn after beam 0; the last
        // sweep (180 beams when interleaved) ends 179° after its start.
        let last = res.beam_time(res.beams() - 1);
        assert!((last - TURN / 2.0).abs() < 1e-12, "{res:?}: {last}");
        let latest = (0..res.beams())
            .map(|i| res.beam_time(i))
            .fold(0.0, f64::max);
        let expect = match res.sweeps() {
            1 => TURN / 2.0,
            s => (s - 1) as f64 * TURN + 179.0 * TURN / 360.0,
        };
        assert!((latest - expect).abs() < 1e-12, "{res:?}: {latest}");
        // The scan carries the odometry only when the scenario gives it.
        let mut s = moving(600.0, 0.45);
        s.resolution = res;
        let sim = render(&wall(), &s, &mut ChaCha8Rng::seed_from_u64(2));
        assert_eq!(sim.sweeps, res.sweeps());
        assert_eq!(sim.odometry, None);
        s.odometry_given = true;
        let sim = render(&wall(), &s, &mut ChaCha8Rng::seed_from_u64(2));
        let m = sim.odometry.expect("odometry given");
        assert_eq!((m.v, m.omega, m.timing), (600.0, 0.45, timing));
    }
}

/// The one-sweep control: at 0.5° every beam is taken in one mirror turn, beam `i` at
/// `i · 0.5 · TURN / 360` (driving at the wall at 600 mm/s: the scanner `600 t` further on), the
/// scan is declared as one sweep and the odometry carries that timing.
#[test]
fn one_sweep_takes_every_beam_in_one_mirror_turn() {
    let mut s = moving(600.0, 0.0);
    s.one_sweep = true;
    s.odometry_given = true;
    let sim = render(&wall(), &s, &mut ChaCha8Rng::seed_from_u64(1));
    assert_eq!(sim.sweeps, 1);
    let m = sim.odometry.expect("odometry given");
    assert_eq!((m.timing.sweeps, m.timing.sweep_dt), (1, 0.0));
    assert!((f64::from(m.timing.beam_dt) - TURN / 720.0).abs() < 1e-9);
    let mut n = 0;
    for (i, &r) in sim.true_ranges_mm.iter().enumerate() {
        if r.is_finite() {
            let t = i as f64 * TURN / 720.0;
            let b = bearing(&sim.geometry, i);
            let expect = (WALL_X - 600.0 * t) / b.cos();
            assert!((r - expect).abs() < 1e-6, "beam {i}: {r} vs {expect}");
            n += 1;
        }
    }
    assert!(n > 200);
}

#[test]
fn odometry_deskews_both_sweeps_onto_the_wall() {
    let mut s = moving(600.0, 0.45);
    s.odometry_given = true;
    let sim = render(&wall(), &s, &mut ChaCha8Rng::seed_from_u64(1));
    let m = sim.odometry.expect("odometry given");
    let mut n = 0;
    for (i, &r) in sim.true_ranges_mm.iter().enumerate() {
        if r.is_finite() {
            let (p, _) = m.deskew(i, r as f32, sim.geometry.bearing(i));
            assert!(
                (f64::from(p.x) - WALL_X).abs() < 0.5,
                "beam {i}: x = {}",
                p.x
            );
            n += 1;
        }
    }
    assert!(n > 200);
}

#[test]
fn cm_mode_ranges_are_10_mm_codes_up_to_80_m() {
    let mut far = 0.0f32;
    let mut far_lines = 0;
    for seed in 0..8 {
        let mut s = Scenario::new(SceneKind::LongCorridor, seed);
        s.range_mode = RangeMode::Cm;
        let sim = s.simulate();
        assert_eq!(sim.geometry.r_max, 80000.0);
        assert_eq!(sim.mm_per_unit, 10.0);
        for (&r, &code) in sim.ranges_mm.iter().zip(&sim.raw) {
            if r.is_finite() {
                assert!(r > 0.0 && r <= 80000.0, "{r}");
                assert_eq!(r % 10.0, 0.0, "{r}");
                assert_eq!(f32::from(code) * 10.0, r);
                assert!(code <= LMS_MAX_VALID_8M);
                far = far.max(r);
            } else {
                assert_eq!(code, NO_RETURN_CODE);
            }
        }
        far_lines += sim
            .truth
            .iter()
            .filter(|f| {
                f.kind.is_line() && sim.ranges_mm[f.first].min(sim.ranges_mm[f.last]) > 5000.0
            })
            .count();
    }
    assert!(far > 20000.0, "farthest return {far} mm");
    assert!(far_lines >= 8, "{far_lines} truth lines wholly beyond 5 m");
}

#[test]
fn incidence_noise_grows_towards_grazing() {
    assert_eq!(incidence_noise_factor(0.0), 1.0);
    assert!((incidence_noise_factor(60f64.to_radians()) - 1.3).abs() < 1e-9);
    assert_eq!(incidence_noise_factor(89f64.to_radians()), 4.0);
    // A wall along the x axis 1.5 m to the left: head-on at 90°, grazing towards 0°.
    let side = [Shape::Segment {
        a: [-30000.0, 1500.0],
        b: [30000.0, 1500.0],
    }];
    let spread = |incidence: bool, lo: f64, hi: f64| {
        let mut sq = 0.0;
        let mut n = 0;
        for seed in 0..40 {
            let mut s = Scenario::new(SceneKind::Office, 0).with_sigma(5.0);
            s.incidence_noise = incidence;
            let sim = render(&side, &s, &mut ChaCha8Rng::seed_from_u64(seed));
            for i in 0..sim.ranges_mm.len() {
                let beta = (std::f64::consts::FRAC_PI_2 - bearing(&sim.geometry, i)).abs();
                if sim.ranges_mm[i].is_finite() && beta >= lo && beta < hi {
                    sq += (f64::from(sim.ranges_mm[i]) - sim.true_ranges_mm[i]).powi(2);
                    n += 1;
                }
            }
        }
        (sq / f64::from(n)).sqrt()
    };
    let (lo, hi) = (0.0, 20f64.to_radians());
    let (g0, g1) = (70f64.to_radians(), 75f64.to_radians());
    let head_on = spread(true, lo, hi);
    let grazing = spread(true, g0, g1);
    // Factor between 1.75 (70°) and 2.39 (75°) at grazing, ≤ 1.01 head-on.
    assert!((4.6..5.6).contains(&head_on), "head-on σ {head_on}");
    assert!((8.5..12.5).contains(&grazing), "grazing σ {grazing}");
    let off = spread(false, g0, g1);
    assert!((4.5..5.6).contains(&off), "without the option σ {off}");
}
