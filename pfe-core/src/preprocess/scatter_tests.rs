use super::*;

/// Points of a wall `rho` mm ahead, bearings ±45° at 0.5°, with range offsets `off(i)`.
fn wall(rho: f32, off: impl Fn(usize) -> f32) -> [Point; 181] {
    core::array::from_fn(|i| {
        let b = (i as f32 - 90.0) * 0.5f32.to_radians();
        let (s, c) = math::sin_cos(b);
        let r = rho / c + off(i);
        Point::new(r * c, r * s)
    })
}

/// Deterministic 24-bit integers from an LCG seeded with `seed`.
fn lcg24(seed: u32) -> impl FnMut() -> u32 {
    let mut s = seed;
    move || {
        s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        s >> 8
    }
}

/// Deterministic uniform samples in (0, 1) from [`lcg24`].
fn uniforms(seed: u32) -> impl FnMut() -> f32 {
    let mut u = lcg24(seed);
    move || (u() as f32 + 0.5) / 16_777_216.0
}

/// Deterministic standard normal samples (Box–Muller over an LCG).
fn normals(seed: u32) -> impl FnMut() -> f32 {
    let mut u = uniforms(seed);
    move || {
        let (u1, u2) = (u(), u());
        libm::sqrtf(-2.0 * libm::logf(u1)) * libm::cosf(core::f32::consts::TAU * u2)
    }
}

/// The one-pass scatter and [`at_span`] count the residuals of exactly the triples of
/// valid points (each point's validity tested): walls with rough noise, points NaN,
/// infinite or half infinite in x or y at random, at spans 1, 2 and 4.
#[test]
fn the_one_pass_scatter_skips_every_triple_with_a_point_not_finite() {
    let mut n = normals(3);
    let mut u = lcg24(17);
    let bad = [
        Point::INVALID,
        Point::new(f32::INFINITY, 100.0),
        Point::new(-3000.0, f32::NEG_INFINITY),
        Point::new(f32::NAN, 5.0),
        Point::new(0.0, f32::INFINITY),
        Point::new(f32::INFINITY, f32::INFINITY),
    ];
    let mut estimated = 0;
    for t in 0..200u32 {
        let sigma = [4.0f32, 12.0, 25.0][t as usize % 3];
        let noise: [f32; 181] = core::array::from_fn(|_| sigma * n());
        let mut p = wall(2500.0, |i| noise[i]);
        let every = 3 + t % 20;
        for q in p.iter_mut() {
            if u() % every == 0 {
                *q = bad[(u() % 6) as usize];
            }
        }
        let got = Scatter::of(&p, 4.0);
        let want = Scatter {
            one: valid_only(&p, 1, 4.0),
            two: valid_only(&p, 2, 4.0),
        };
        assert_eq!(got, want, "wall {t}");
        for span in [1, 2, 4] {
            assert_eq!(
                at_span(&p, span, 4.0),
                valid_only(&p, span, 4.0),
                "wall {t}"
            );
        }
        estimated += usize::from(got.one.is_some() && got.two.is_some());
    }
    assert!(estimated > 60, "{estimated}");
}

/// The scatter by blocks (residuals computed branch-free, then counted) and the one over
/// windows of five points equal the one-pass scatter bit for bit: rough walls with points NaN, infinite or half infinite at random,
/// cut to every length from 0 to 140 (blocks of 64 windows: full, partial and none) and to
/// 361, 401 and 721 points, at σ_r from 0.5 to 30 mm.
#[test]
fn the_scatter_by_blocks_is_the_one_pass_scatter() {
    let mut n = normals(23);
    let mut u = lcg24(29);
    let bad = [
        Point::INVALID,
        Point::new(f32::INFINITY, 100.0),
        Point::new(-3000.0, f32::NEG_INFINITY),
        Point::new(f32::NAN, 5.0),
        Point::new(0.0, 0.0),
    ];
    let (mut compared, mut estimated) = (0, 0);
    for t in 0..300u32 {
        let sigma = [0.5f32, 4.0, 12.0, 30.0][t as usize % 4];
        // Also scales no configuration gives: infinite (0 · ∞ is NaN) and negative.
        let sigma_r = match t % 25 {
            7 => 1e-40,
            8 => -4.0,
            9 => -0.02,
            _ => sigma,
        };
        let points: [Point; 721] = core::array::from_fn(|i| {
            let b = (i as f32 - 360.0) * 0.25f32.to_radians();
            let (sb, cb) = math::sin_cos(b);
            let r = 2500.0 / math::abs(cb).max(0.3)
                + 3.0 * sigma * n()
                + if i / 97 % 2 == 0 { 0.0 } else { 400.0 };
            Point::new(r * cb, r * sb)
        });
        let mut p = points;
        let every = 2 + t % 40;
        for q in p.iter_mut() {
            if u() % every == 0 {
                *q = bad[(u() % 5) as usize];
            }
        }
        let len = match t % 6 {
            0 => 361,
            1 => 401,
            2 => 721,
            _ => (u() % 141) as usize,
        };
        let p = &p[..len];
        let (blocks, stream) = (
            Scatter::of_blocks(p, sigma_r),
            Scatter::of_stream(p, sigma_r),
        );
        let bits = |s: Scatter| (s.one.map(f32::to_bits), s.two.map(f32::to_bits));
        assert_eq!(bits(blocks), bits(stream), "scan {t}, {len} points");
        let windows = Scatter::of_windows(p, sigma_r);
        assert_eq!(bits(windows), bits(stream), "scan {t}, {len} points");
        compared += 1;
        estimated += usize::from(blocks.sigma().is_some());
    }
    assert!(compared == 300 && estimated > 30, "{estimated}");
}

/// The board's count of a residual or a non-finite value puts every value in the bin
/// [`count`] gives it after [`residual_at`]'s finiteness test, and skips what that skips:
/// the bins' edges, values beyond the last bin (up to overflowing `|e| · scale`), ±∞ and
/// NaN, at positive finite scales.
#[test]
fn the_count_of_finite_residuals_bins_as_count_does() {
    let values = |scale: f32| {
        let edge = |b: f32| b / scale;
        [
            0.0,
            -0.0,
            1e-30,
            edge(1.0),
            edge(1.0).next_down(),
            edge(1.0).next_up(),
            -edge(7.5),
            edge(511.0),
            edge(511.0).next_down(),
            edge(512.0),
            edge(512.0).next_down(),
            -edge(512.0).next_up(),
            edge(9000.0),
            3e38,
            -f32::MAX,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ]
    };
    for sigma_r in [0.3f32, 1.0, 5.0, 33.0, 1e-30] {
        let scale = PER_SIGMA / sigma_r;
        assert!(scale > 0.0 && math::finite(scale));
        let (mut want, mut got) = ([0u16; BINS], [0u16; BINS]);
        let (mut n_want, mut n_got) = (0usize, 0usize);
        for e in values(scale) {
            if math::finite(e) {
                count(&mut want, &mut n_want, e, scale);
            }
            count_finite(&mut got, &mut n_got, e, scale);
            assert_eq!((got, n_got), (want, n_want), "{e} at scale {scale}");
        }
        assert_eq!(n_got, 15, "at scale {scale}");
    }
}

/// The quantiles and inlier sums in integers are the f32 ones: histograms of 0 to 1500
/// residuals, sparse and dense, with empty bins first, at every quarter and half count.
#[test]
fn the_quantile_in_integers_is_the_quantile() {
    let mut u = lcg24(41);
    for t in 0..150u32 {
        let mut hist = [0u16; BINS];
        let (spread, count) = (1 + u() % 500, u() % 1500);
        let skip = (u() % 40) as usize;
        for _ in 0..count {
            let b = skip + (u() % spread) as usize * (u() % 3) as usize / 2;
            if let Some(h) = hist.get_mut(b.min(BINS - 1)) {
                *h += 1;
            }
        }
        let total: usize = hist.iter().map(|&h| usize::from(h)).sum();
        for q in 0..=4 * total + 2 {
            let half = q as f32 * 0.25;
            let (want, got) = (quantile_bin(&hist, half), quantile_bin_counted(&hist, half));
            assert_eq!(got.to_bits(), want.to_bits(), "hist {t}, half {half}");
        }
        for cut in [0, 1, 7, 8, 9, 100, BINS] {
            let want: usize = hist.iter().take(cut).map(|&h| usize::from(h)).sum();
            assert_eq!(sum(&hist[..cut]), want, "hist {t}, cut {cut}");
        }
    }
}

/// [`at_span`] over the triples of valid points only, each point's validity tested.
fn valid_only(points: &[Point], span: usize, sigma_r: f32) -> Option<f32> {
    let mut hist = [0u16; BINS];
    let mut total = 0usize;
    for w in points.windows(2 * span + 1) {
        let (a, m, b) = (w[0], w[span], w[2 * span]);
        if a.is_valid() && m.is_valid() && b.is_valid() {
            if let Some(e) = chord_residual(a, m, b) {
                count(&mut hist, &mut total, e, PER_SIGMA / sigma_r);
            }
        }
    }
    estimate(&hist, total, sigma_r)
}

#[test]
fn noise_at_the_configured_sigma_keeps_it() {
    for seed in 0..50 {
        let mut n = normals(seed);
        let noise: [f32; 181] = core::array::from_fn(|_| 5.0 * n());
        let p = wall(3000.0, |i| noise[i]);
        assert_eq!(sigma(&p, 5.0), None, "seed {seed}");
    }
}

#[test]
fn larger_noise_is_measured() {
    // One scan's estimate within 40 %, the mean of 20 within 5 %.
    for true_sigma in [8.0f32, 12.0, 16.0] {
        let mut sum = 0.0;
        for seed in 0..20 {
            let mut n = normals(seed);
            let noise: [f32; 181] = core::array::from_fn(|_| true_sigma * n());
            let p = wall(4000.0, |i| noise[i]);
            let s = sigma(&p, 2.5).unwrap_or(0.0) / true_sigma;
            assert!((s - 1.0).abs() < 0.4, "σ {true_sigma}, seed {seed}: {s}");
            sum += s;
        }
        assert!(
            (sum / 20.0 - 1.0).abs() < 0.05,
            "σ {true_sigma}: {}",
            sum / 20.0
        );
    }
}

#[test]
fn a_noise_free_wall_at_any_incidence_has_no_scatter() {
    // Bearings to ±45° on a wall at 1 m: incidence up to 45°, ranges 1000–1414 mm.
    let p = wall(1000.0, |_| 0.0);
    assert_eq!(sigma(&p, 1.0), None);
    let mut worst = 0.0f32;
    for w in p.windows(5) {
        if let [a, _, m, _, b] = *w {
            worst = worst.max(math::abs(chord_residual(a, m, b).unwrap_or(1e9)));
        }
    }
    assert!(worst < 0.01, "{worst}");
}

#[test]
fn the_lower_quartile_start_resists_clutter() {
    // 100 walls at 3 m with uniform noise of σ 3 mm (σ_r 2.5) and 15 % of the beams
    // 15–40 mm off either way (clutter within the histogram). Starting the cut from the
    // lower quartile keeps σ_r on 31 of them; from all residuals (the median's), on 16.
    let mut u = uniforms(11);
    let mut kept = 0;
    for _ in 0..100 {
        let off: [f32; 181] = core::array::from_fn(|_| {
            let noise = (u() - 0.5) * 3.0 * 3.46;
            if u() < 0.15 {
                let m = 15.0 + 25.0 * u();
                if u() < 0.5 {
                    noise + m
                } else {
                    noise - m
                }
            } else {
                noise
            }
        });
        kept += usize::from(sigma(&wall(3000.0, |i| off[i]), 2.5).is_none());
    }
    assert!(kept >= 25, "{kept}");
}

#[test]
fn corners_and_gaps_are_a_minority_the_median_ignores() {
    // Alternate 40-beam runs on walls at 2 m and 3 m: an edge every 40 beams; every tenth
    // beam invalid.
    let mut n = normals(9);
    let noise: [f32; 181] = core::array::from_fn(|_| 5.0 * n());
    let mut p = wall(2000.0, |i| {
        noise[i] + if i / 40 % 2 == 0 { 0.0 } else { 1000.0 }
    });
    for q in p.iter_mut().step_by(10) {
        *q = Point::INVALID;
    }
    assert_eq!(sigma(&p, 5.0), None);
}

#[test]
fn offsets_between_interleaved_sweeps_count_as_scatter() {
    let mut n = normals(5);
    let noise: [f32; 181] = core::array::from_fn(|_| 5.0 * n());
    // Two sweeps 20 mm apart: each point 20 mm off its neighbours' chord.
    let two = wall(3000.0, |i| noise[i] + if i % 2 == 0 { 20.0 } else { 0.0 });
    let s = sigma(&two, 5.0).unwrap_or(0.0);
    // |residual| ≈ 20 mm each: the median's σ is 20 mm / (0.6745 √1.5), noise aside.
    let expected = 20.0 * MEDIAN_TO_SIGMA;
    assert!((s / expected - 1.0).abs() < 0.15, "{s} vs {expected}");
    // 4 mm apart: within the noise.
    let close = wall(3000.0, |i| noise[i] + if i % 2 == 0 { 4.0 } else { 0.0 });
    assert_eq!(sigma(&close, 5.0), None);
}

#[test]
fn sweeps_apart_only_when_one_beam_scatters_beyond_two() {
    let mut n = normals(7);
    let noise: [f32; 181] = core::array::from_fn(|_| n());
    // Noise at σ_r, rough (white, 4 σ_r): not apart; the odd sweep 20 mm away: apart.
    assert!(!sweeps_apart(&wall(3000.0, |i| 5.0 * noise[i]), 2, 5.0));
    assert!(!sweeps_apart(&wall(3000.0, |i| 20.0 * noise[i]), 2, 5.0));
    assert!(!sweeps_apart(&wall(3000.0, |i| 20.0 * noise[i]), 4, 5.0));
    let odd = |i: usize| if i % 2 == 1 { 20.0 } else { 0.0 };
    assert!(sweeps_apart(
        &wall(3000.0, |i| 5.0 * noise[i] + odd(i)),
        2,
        5.0
    ));
    // Also on a rough wall, when the offset dominates.
    let far = |i: usize| if i % 2 == 1 { 60.0 } else { 0.0 };
    assert!(sweeps_apart(
        &wall(3000.0, |i| 10.0 * noise[i] + far(i)),
        2,
        5.0
    ));
    // Four sweeps: points two beams apart are of different sweeps.
    let four = |i: usize| [0.0, 20.0, -15.0, 30.0][i % 4];
    let p = wall(3000.0, |i| 5.0 * noise[i] + four(i));
    assert!(sweeps_apart(&p, 4, 5.0));
    // Drifting by equal steps: 8 mm a sweep.
    let p = wall(3000.0, |i| 5.0 * noise[i] + 8.0 * (i % 4) as f32);
    assert!(sweeps_apart(&p, 4, 5.0));
}

#[test]
fn the_larger_scale_wins_and_both_sides_of_apart_are_seen() {
    let mut n = normals(11);
    let noise: [f32; 181] = core::array::from_fn(|_| n());
    // Sweeps 30 mm apart over 10 mm of noise, σ_r 3 mm: both scales significant, the
    // one-beam scatter far larger.
    let p = wall(3000.0, |i| {
        10.0 * noise[i] + if i % 2 == 0 { 30.0 } else { 0.0 }
    });
    let (one, two) = (at_span(&p, 1, 3.0), at_span(&p, 2, 3.0));
    let (Some(one), Some(two)) = (one, two) else {
        panic!("{one:?} {two:?}");
    };
    assert!(one > 1.5 * two, "{one} {two}");
    assert_eq!(sigma(&p, 3.0), Some(one));
    assert!(sweeps_apart(&p, 2, 3.0));
}

#[test]
fn a_chord_along_the_beam_gives_no_residual() {
    // Three points on a line through (0, 3000) at angle φ to the beam along +y.
    let along = |phi: f32, e: f32| {
        let (s, c) = math::sin_cos(phi);
        let at = |t: f32| Point::new(t * s, 3000.0 + t * c);
        chord_residual(at(-100.0), Point::new(0.0, 3000.0 + e), at(100.0))
    };
    // sin 3° = 0.052 < 0.1: refused; at 10°, 30° and 90° the residual is the offset.
    assert_eq!(along(3f32.to_radians(), 5.0), None);
    for deg in [10.0f32, 30.0, 90.0] {
        let e = along(deg.to_radians(), 5.0).unwrap_or(f32::NAN);
        assert!((e - 5.0).abs() < 0.01, "{deg}°: {e}");
    }
}

/// At the sine's bound the one-pass residual and the branch-free one agree: a chord whose
/// sine to the beam is MIN_SINE to the last bit (|m × c| = MIN_SINE · r · |c| in f32) gives
/// no residual from either; one bit steeper, both give the residual (0: the point lies on
/// the chord).
#[test]
fn a_chord_at_the_sine_bound_gives_no_residual_in_either_path() {
    let m = Point::new(0.0, 1000.0);
    // The chord from (−h, 950) to (h, 1050), its x extent 2h, near 0.1005 of its y extent.
    let tie = f32::from_bits(0x40a0_ce59);
    for (h, at_bound) in [(tie, true), (f32::from_bits(tie.to_bits() + 1), false)] {
        let (a, b) = (Point::new(-h, 950.0), Point::new(h, 1050.0));
        let (cx, cy) = (b.x - a.x, b.y - a.y);
        let den = math::abs(m.x * cy - m.y * cx);
        let bound = MIN_SINE * 1000.0 * math::sqrt(cx * cx + cy * cy);
        assert_eq!(den == bound, at_bound, "{den} {bound}");
        assert!(den >= bound, "{den} {bound}");
        let one = chord_residual(a, m, b);
        let lanes = residual_or_nan(a, m, b, 1000.0);
        match at_bound {
            true => assert!(one.is_none() && lanes.is_nan(), "{one:?} {lanes}"),
            false => assert!(
                one.is_some_and(|e| math::abs(e) < 1e-3) && math::abs(lanes) < 1e-3,
                "{one:?} {lanes}"
            ),
        }
    }
}

#[test]
fn roughness_correlated_over_two_beams_shows_at_the_wider_chord() {
    // Each pair of beams shares one offset (σ 20 mm): the one-beam chords see it only
    // at every other point, the two-beam chords at every point.
    let mut n = normals(6);
    let noise: [f32; 181] = core::array::from_fn(|_| 20.0 * n());
    let p = wall(3000.0, |i| noise[i / 2 * 2]);
    let (one, two) = (at_span(&p, 1, 2.0), at_span(&p, 2, 2.0));
    let two = two.unwrap_or(0.0);
    assert!(one.unwrap_or(0.0) < two, "{one:?} {two}");
    assert_eq!(sigma(&p, 2.0), Some(two));
}

#[test]
fn clutter_is_capped_or_refused_and_few_points_give_nothing() {
    // 12 σ_r is capped at MAX_FACTOR; 100 σ_r is clutter, not noise.
    let mut n = normals(4);
    let noise: [f32; 181] = core::array::from_fn(|_| n());
    let p = wall(4000.0, |i| 60.0 * noise[i]);
    assert_eq!(sigma(&p, 5.0), Some(MAX_FACTOR * 5.0));
    let p = wall(4000.0, |i| 500.0 * noise[i]);
    assert_eq!(sigma(&p, 5.0), None);
    // Every other pair of beams 6 mm nearer: every two-beam residual 12 mm; MIN_SAMPLES - 1
    // triples give nothing.
    let p = wall(2000.0, |i| if i / 2 % 2 == 0 { 6.0 } else { -6.0 });
    let few = MIN_SAMPLES + 3;
    assert_eq!(at_span(&p[..few], 2, 1.0), None);
    assert_eq!(at_span(&p[..few + 1], 2, 1.0), Some(MAX_FACTOR));
    let s = at_span(&p[..few + 1], 2, 4.0).unwrap_or(0.0);
    // Within the histogram's bin (σ_r / 16 of median, 0.3 mm of σ here; the bound for
    // 24 residuals is 3.04 σ_r).
    assert!((s - 12.0 * MEDIAN_TO_SIGMA).abs() < 0.4, "{s}");
    // Non-finite points never count.
    let nan = [Point::new(f32::NAN, 0.0); 40];
    assert_eq!(sigma(&nan, 5.0), None);
}
