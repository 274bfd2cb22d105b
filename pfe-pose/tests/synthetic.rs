//! Registration and odometry against analytic truth: synthetic scenes (a convex room of walls
//! and pillars, a corridor) seen from known poses, with noise drawn from the covariance each
//! feature states (a small deterministic generator, so every run sees the same numbers).
#![allow(clippy::needless_range_loop)]

use pfe_pose::{
    register, register_with, wrap, Config, Cov3, Failure, LineObs, Observation, Odometry, PointObs,
    Pose, Status, ROTATION_SCALE, UNOBSERVABLE_VARIANCE,
};

mod common;
use common::{corridor, Rng, World};

/// Stated covariances of the synthetic features.
const SIGMA_ALPHA: f64 = 0.004;
const SIGMA_RHO: f64 = 10.0;
const CORR: f64 = 0.3;
const SIGMA_POINT: f64 = 15.0;

/// An irregular convex room about 9 m × 7 m (no wall hides another from inside) with pillars.
fn room() -> World {
    let corners = common::ROOM;
    let walls = (0..corners.len())
        .map(|i| (corners[i], corners[(i + 1) % corners.len()]))
        .collect();
    World {
        walls,
        pillars: vec![[2000.0, 1000.0], [-1500.0, -1200.0], [3500.0, -800.0]],
    }
}

/// Draws a 2-vector from N(0, [[a, b], [b, c]]).
fn draw2(rng: &mut Rng, a: f64, b: f64, c: f64) -> (f64, f64) {
    let l11 = a.sqrt();
    let l21 = b / l11;
    let l22 = (c - l21 * l21).max(0.0).sqrt();
    let (z1, z2) = (rng.normal(), rng.normal());
    (l11 * z1, l21 * z1 + l22 * z2)
}

/// The features of `world` seen by a scanner at `pose` (world frame), with noise per the
/// stated covariances; walls farther than 12 m are not seen.
fn observe(world: &World, pose: &Pose, rng: &mut Rng) -> Vec<Observation> {
    let inv = pose.inverse();
    let mut out = Vec::new();
    let (va, vr) = (SIGMA_ALPHA * SIGMA_ALPHA, SIGMA_RHO * SIGMA_RHO);
    let car = CORR * SIGMA_ALPHA * SIGMA_RHO;
    for (s, e) in &world.walls {
        let (s, e) = (inv.transform_point(*s), inv.transform_point(*e));
        let d = [e[0] - s[0], e[1] - s[1]];
        // Normal of the segment's line, towards it from the scanner.
        let len = d[0].hypot(d[1]);
        let n = [d[1] / len, -d[0] / len];
        let rho = s[0] * n[0] + s[1] * n[1];
        let (alpha, rho) = if rho < 0.0 {
            ((-n[1]).atan2(-n[0]), -rho)
        } else {
            (n[1].atan2(n[0]), rho)
        };
        if rho > 12_000.0 {
            continue;
        }
        let (da, dr) = draw2(rng, va, car, vr);
        let (a2, r2) = (alpha + da as f32, rho + dr as f32);
        // Ends: the true ends' projections on the noisy line.
        let (sa, ca) = (a2.sin(), a2.cos());
        let proj = |p: [f32; 2]| {
            let t = -sa * p[0] + ca * p[1];
            [r2 * ca - t * sa, r2 * sa + t * ca]
        };
        out.push(Observation::Line(
            LineObs::new(a2, r2, [[va as f32, car as f32], [car as f32, vr as f32]])
                .with_extent(proj(s), proj(e)),
        ));
    }
    let vp = SIGMA_POINT * SIGMA_POINT;
    for p in &world.pillars {
        let q = inv.transform_point(*p);
        let (dx, dy) = draw2(rng, vp, 0.0, vp);
        out.push(Observation::Point(PointObs::new(
            q[0] + dx as f32,
            q[1] + dy as f32,
            [[vp as f32, 0.0], [0.0, vp as f32]],
        )));
    }
    out
}

/// Registration settings whose model noise is exactly the features' stated covariance.
fn exact() -> Config {
    let mut c = Config::default();
    c.line_floor = [0.0, 0.0];
    c.point_floor = 0.0;
    c
}

fn error(got: &Pose, truth: &Pose) -> [f64; 3] {
    [
        f64::from(got.x - truth.x),
        f64::from(got.y - truth.y),
        f64::from(wrap(got.theta - truth.theta)),
    ]
}

/// `eᵀ C⁻¹ e` in f64.
fn nis(c: &Cov3, e: &[f64; 3]) -> f64 {
    let c: [[f64; 3]; 3] = c.map(|r| r.map(f64::from));
    let det = c[0][0] * (c[1][1] * c[2][2] - c[1][2] * c[2][1])
        - c[0][1] * (c[1][0] * c[2][2] - c[1][2] * c[2][0])
        + c[0][2] * (c[1][0] * c[2][1] - c[1][1] * c[2][0]);
    let mut s = 0.0;
    for i in 0..3 {
        for j in 0..3 {
            let (a, b) = ((j + 1) % 3, (j + 2) % 3);
            let (p, q) = ((i + 1) % 3, (i + 2) % 3);
            let inv = (c[a][p] * c[b][q] - c[a][q] * c[b][p]) / det;
            s += e[i] * inv * e[j];
        }
    }
    s
}

/// A random scanner pose inside the room and a motion of up to 1.8 m and 1.4 rad that stays
/// inside.
fn random_pair(rng: &mut Rng) -> (Pose, Pose) {
    let p0 = Pose::new(
        rng.range(-1500.0, 1500.0),
        rng.range(-1200.0, 1200.0),
        rng.range(-3.1, 3.1),
    );
    let dist = rng.range(0.0, 1800.0);
    let dir = rng.range(-3.1, 3.1);
    let rel = Pose::new(dist * dir.cos(), dist * dir.sin(), rng.range(-1.4, 1.4));
    (p0, rel)
}

#[test]
fn room_pairs_within_three_sigma_and_consistent() {
    let world = room();
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let cfg = exact();
    let trials = 400;
    let (mut inside95, mut beyond3, mut ok) = (0, 0, 0);
    for _ in 0..trials {
        let (p0, rel) = random_pair(&mut rng);
        let p1 = p0.compose(&rel);
        let a = observe(&world, &p0, &mut rng);
        let b = observe(&world, &p1, &mut rng);
        let reg = register_with(&a, &b, None, &cfg);
        assert_eq!(reg.status, Status::Ok, "truth {rel:?}: {reg:?}");
        ok += 1;
        let e = error(&reg.rel, &rel);
        for (k, ek) in e.iter().enumerate() {
            let sd = f64::from(reg.cov[k][k]).sqrt();
            assert!(
                ek.abs() < 5.0 * sd,
                "axis {k}: error {ek} vs σ {sd} ({rel:?})"
            );
            if ek.abs() > 3.0 * sd {
                beyond3 += 1;
            }
        }
        if nis(&reg.cov, &e) < 7.815 {
            inside95 += 1;
        }
    }
    let frac = inside95 as f64 / ok as f64;
    // 3 axes × 400 trials: 0.27 % expected beyond 3σ if consistent.
    assert!(beyond3 <= 12, "{beyond3} components beyond 3σ");
    assert!(
        (0.90..=0.99).contains(&frac),
        "{frac} inside the 95 % ellipsoid"
    );
}

#[test]
fn default_settings_recover_large_motions() {
    // The default settings (with their model-noise floor) on the largest motions of the
    // shared logs: 1.8 m and 1.4 rad, no prior.
    let world = room();
    let mut rng = Rng(7);
    for (x, y, th) in [
        (1800.0, 0.0, 1.4),
        (-1200.0, 1300.0, -1.4),
        (0.0, -1800.0, 0.7),
        (500.0, 200.0, -1.2),
    ] {
        let p0 = Pose::new(-300.0, 200.0, 0.3);
        let rel = Pose::new(x, y, th);
        let a = observe(&world, &p0, &mut rng);
        let b = observe(&world, &p0.compose(&rel), &mut rng);
        let reg = register(&a, &b, None);
        assert_eq!(reg.status, Status::Ok);
        let e = error(&reg.rel, &rel);
        for (k, ek) in e.iter().enumerate() {
            assert!(
                ek.abs() < 3.0 * f64::from(reg.cov[k][k]).sqrt(),
                "{rel:?}: {reg:?}"
            );
        }
    }
}

#[test]
fn outliers_and_moving_objects_tolerated() {
    let world = room();
    let mut rng = Rng(42);
    let cfg = exact();
    for _ in 0..100 {
        let (p0, rel) = random_pair(&mut rng);
        let p1 = p0.compose(&rel);
        let mut a = observe(&world, &p0, &mut rng);
        let mut b = observe(&world, &p1, &mut rng);
        // Features seen in one scan only: a box in the previous scan, another in the current.
        let cov = [[1e-5, 0.0], [0.0, 100.0]];
        a.push(Observation::Line(
            LineObs::new(0.3, 900.0, cov).with_extent([850.0, -100.0], [600.0, 700.0]),
        ));
        b.push(Observation::Line(
            LineObs::new(-2.0, 1300.0, cov).with_extent([-500.0, -1200.0], [-900.0, -1000.0]),
        ));
        // Two people walking: points that moved by a metre between the scans.
        let pc = [[225.0, 0.0], [0.0, 225.0]];
        let inv = p1.inverse();
        for (x, y) in [(500.0f32, 500.0f32), (-800.0, 300.0)] {
            a.push(Observation::Point(PointObs::new(x, y, pc)));
            let q = inv.transform_point(p0.transform_point([x + 1000.0, y - 300.0]));
            b.push(Observation::Point(PointObs::new(q[0], q[1], pc)));
        }
        let reg = register_with(&a, &b, None, &cfg);
        assert_eq!(reg.status, Status::Ok, "{rel:?}");
        let e = error(&reg.rel, &rel);
        for (k, ek) in e.iter().enumerate() {
            let sd = f64::from(reg.cov[k][k]).sqrt();
            assert!(ek.abs() < 4.0 * sd, "axis {k}: {ek} vs σ {sd}");
        }
    }
}

#[test]
fn corridor_is_degenerate_never_ok() {
    let world = corridor();
    let mut rng = Rng(3);
    let cfg = exact();
    for _ in 0..200 {
        let p0 = Pose::new(rng.range(-2000.0, 2000.0), rng.range(-500.0, 500.0), 0.0);
        let p0 = Pose::new(p0.x, p0.y, rng.range(-0.3, 0.3));
        let rel = Pose::new(
            rng.range(-1500.0, 1500.0),
            rng.range(-300.0, 300.0),
            rng.range(-0.3, 0.3),
        );
        let p1 = p0.compose(&rel);
        let a = observe(&world, &p0, &mut rng);
        let b = observe(&world, &p1, &mut rng);
        let reg = register_with(&a, &b, None, &cfg);
        let Status::Degenerate { direction } = reg.status else {
            panic!("corridor registered as {:?} (truth {rel:?})", reg.status);
        };
        // The unobservable direction: along the corridor (x in the previous frame), up to
        // the previous scan's heading.
        let along = [p0.theta.cos(), -p0.theta.sin()];
        let dot = (direction[0] * along[0] + direction[1] * along[1]).abs();
        assert!(dot > 0.95, "direction {direction:?}, along {along:?}");
        // Variance along it: unbounded (the sentinel), and finite.
        let v = direction[0] * direction[0] * reg.cov[0][0]
            + 2.0 * direction[0] * direction[1] * reg.cov[0][1]
            + direction[1] * direction[1] * reg.cov[1][1];
        assert!(v > 0.5 * UNOBSERVABLE_VARIANCE && v.is_finite(), "{v}");
        // Across and in heading it is measured.
        let e = error(&reg.rel, &rel);
        let across = [-along[1], along[0]];
        let e_across = e[0] * f64::from(across[0]) + e[1] * f64::from(across[1]);
        assert!(e_across.abs() < 60.0 && e[2].abs() < 0.02, "{e:?}");
    }
}

/// Issue 40: a corridor seen at headings tilted from the scanner's axes (±0.5 rad) puts the
/// unobservable variance into every entry of the covariance; across the unobservable
/// `direction` (the two directions completing it, x and y in mm and θ·[`ROTATION_SCALE`])
/// the stated covariance must still be positive definite and hold the errors: 80–99 % of
/// them inside its 95 % ellipse (χ²₂ 5.991).
#[test]
fn degenerate_covariance_keeps_the_measured_directions() {
    let world = corridor();
    let mut rng = Rng(40);
    let cfg = exact();
    let scale = [1.0, 1.0, f64::from(ROTATION_SCALE)];
    let (mut n, mut inside) = (0usize, 0usize);
    for k in 0..200 {
        let heading = if k % 2 == 0 { 0.5 } else { -0.5 };
        let p0 = Pose::new(
            rng.range(-2000.0, 2000.0),
            rng.range(-500.0, 500.0),
            heading,
        );
        let rel = Pose::new(
            rng.range(-1000.0, 1000.0),
            rng.range(-200.0, 200.0),
            rng.range(-0.1, 0.1),
        );
        let a = observe(&world, &p0, &mut rng);
        let b = observe(&world, &p0.compose(&rel), &mut rng);
        let reg = register_with(&a, &b, None, &cfg);
        let Status::Degenerate { direction } = reg.status else {
            panic!("corridor registered as {:?} (truth {rel:?})", reg.status);
        };
        let d = direction.map(f64::from);
        // Two unit directions completing `d`: the axis least along it, orthogonalised, and
        // their cross product.
        let m = (0..3)
            .min_by(|&i, &j| d[i].abs().total_cmp(&d[j].abs()))
            .unwrap_or(0);
        let mut u = [0.0f64; 3];
        u[m] = 1.0;
        let dot = d[m];
        let u = [u[0] - dot * d[0], u[1] - dot * d[1], u[2] - dot * d[2]];
        let nu = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
        let u = u.map(|x| x / nu);
        let w = [
            d[1] * u[2] - d[2] * u[1],
            d[2] * u[0] - d[0] * u[2],
            d[0] * u[1] - d[1] * u[0],
        ];
        let basis = [u, w];
        // The stated covariance and the error in scaled units, projected on (u, w).
        let c = |i: usize, j: usize| f64::from(reg.cov[i][j]) * scale[i] * scale[j];
        let mut b2 = [[0.0f64; 2]; 2];
        for (p, bp) in basis.iter().enumerate() {
            for (q, bq) in basis.iter().enumerate() {
                for i in 0..3 {
                    for j in 0..3 {
                        b2[p][q] += bp[i] * c(i, j) * bq[j];
                    }
                }
            }
        }
        let det = b2[0][0] * b2[1][1] - b2[0][1] * b2[1][0];
        assert!(
            b2[0][0] > 0.0 && det > 0.0,
            "pair {k}: not positive definite across {direction:?}: {b2:?} from {:?}",
            reg.cov
        );
        let e = error(&reg.rel, &rel);
        let es = [e[0] * scale[0], e[1] * scale[1], e[2] * scale[2]];
        let y = basis.map(|b| b[0] * es[0] + b[1] * es[1] + b[2] * es[2]);
        let q =
            (b2[1][1] * y[0] * y[0] - 2.0 * b2[0][1] * y[0] * y[1] + b2[0][0] * y[1] * y[1]) / det;
        n += 1;
        inside += usize::from(q < 5.991);
    }
    assert!(
        inside * 100 >= n * 80 && inside * 100 <= n * 99,
        "{inside} of {n} inside the 95 % ellipse across the unobservable direction"
    );
}

#[test]
fn corridor_with_prior_takes_the_prior_along() {
    let world = corridor();
    let mut rng = Rng(11);
    let cfg = exact();
    let rel = Pose::new(800.0, 50.0, 0.05);
    let a = observe(&world, &Pose::IDENTITY, &mut rng);
    let b = observe(&world, &rel, &mut rng);
    let prior_cov = [
        [200.0f32 * 200.0, 0.0, 0.0],
        [0.0, 200.0 * 200.0, 0.0],
        [0.0, 0.0, 0.01],
    ];
    let prior = Pose::new(700.0, 0.0, 0.0);
    let reg = register_with(&a, &b, Some((prior, prior_cov)), &cfg);
    assert!(matches!(reg.status, Status::Degenerate { .. }), "{reg:?}");
    // Along the corridor the estimate is the prior's (the scene's information there is only
    // its noise: within a third of the prior's σ) and so is its variance.
    assert!((reg.rel.x - 700.0).abs() < 70.0, "{reg:?}");
    assert!(
        (reg.cov[0][0] / prior_cov[0][0] - 1.0).abs() < 0.1,
        "{reg:?}"
    );
    // Across it, the scene wins over the prior.
    assert!(
        (reg.rel.y - 50.0).abs() < 40.0 && reg.cov[1][1] < 400.0,
        "{reg:?}"
    );
}

#[test]
fn too_few_features_is_none() {
    let cov = [[1e-5, 0.0], [0.0, 100.0]];
    let one = [Observation::Line(LineObs::new(0.0, 2000.0, cov))];
    assert_eq!(
        register(&one, &one, None).status,
        Status::None(Failure::TooFewFeatures)
    );
    assert_eq!(
        register(&[], &[], None).status,
        Status::None(Failure::TooFewFeatures)
    );
    // Two lines each: fewer matches than needed for a registration.
    let two = [
        Observation::Line(LineObs::new(0.0, 2000.0, cov)),
        Observation::Line(LineObs::new(1.5, 1000.0, cov)),
    ];
    let reg = register(&two, &two, None);
    assert!(matches!(reg.status, Status::None(_)), "{reg:?}");
    // No registration: identity and the sentinel without a prior, the prior with one.
    assert_eq!(reg.rel, Pose::IDENTITY);
    assert_eq!(reg.cov[0][0], UNOBSERVABLE_VARIANCE);
    let prior = (
        Pose::new(100.0, 0.0, 0.1),
        [[1e4, 0.0, 0.0], [0.0, 1e4, 0.0], [0.0, 0.0, 0.01]],
    );
    let reg = register(&two, &two, Some(prior));
    assert!(matches!(reg.status, Status::None(_)));
    assert_eq!((reg.rel, reg.cov), prior);
}

#[test]
fn never_panics_on_bad_input() {
    let mut rng = Rng(99);
    let specials = [
        f32::NAN,
        f32::INFINITY,
        -f32::INFINITY,
        0.0,
        -1.0,
        1e30,
        -1e30,
        1e-30,
    ];
    let pick = |rng: &mut Rng| -> f32 {
        if rng.uniform() < 0.3 {
            specials[(rng.next_u64() % specials.len() as u64) as usize]
        } else {
            rng.range(-5000.0, 5000.0)
        }
    };
    for _ in 0..300 {
        let mut sets: [Vec<Observation>; 2] = [Vec::new(), Vec::new()];
        for s in sets.iter_mut() {
            let n = (rng.next_u64() % 80) as usize;
            for _ in 0..n {
                let o = if rng.uniform() < 0.7 {
                    let v = [
                        pick(&mut rng),
                        pick(&mut rng),
                        pick(&mut rng),
                        pick(&mut rng),
                    ];
                    Observation::Line(
                        LineObs::new(v[0], v[1].abs(), [[v[2].abs(), 0.0], [0.0, v[3].abs()]])
                            .with_extent(
                                [pick(&mut rng), pick(&mut rng)],
                                [pick(&mut rng), pick(&mut rng)],
                            ),
                    )
                } else {
                    let c = pick(&mut rng);
                    Observation::Point(PointObs::new(
                        pick(&mut rng),
                        pick(&mut rng),
                        [[c, 0.0], [0.0, c]],
                    ))
                };
                s.push(o);
            }
        }
        let prior = if rng.uniform() < 0.5 {
            let c = pick(&mut rng);
            Some((
                Pose::new(pick(&mut rng), pick(&mut rng), pick(&mut rng)),
                [[c, 0.0, 0.0], [0.0, c, 0.0], [0.0, 0.0, pick(&mut rng)]],
            ))
        } else {
            None
        };
        let reg = register(&sets[0], &sets[1], prior);
        if reg.is_registered() {
            assert!(reg.rel.is_finite(), "{reg:?}");
            assert!(reg.cov.iter().flatten().all(|v| v.is_finite()), "{reg:?}");
        }
    }
    // Identical degenerate inputs: every line the same.
    let cov = [[1e-6, 0.0], [0.0, 25.0]];
    let same = vec![Observation::Line(LineObs::new(0.5, 1000.0, cov)); 70];
    let reg = register(&same, &same, None);
    assert!(!matches!(reg.status, Status::Ok), "{reg:?}");
    assert!(reg.dropped > 0);
    // An invalid prior is an error value.
    let room = observe(&room(), &Pose::IDENTITY, &mut Rng(5));
    let bad = (
        Pose::IDENTITY,
        [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]],
    );
    assert_eq!(
        register(&room, &room, Some(bad)).status,
        Status::None(Failure::InvalidPrior)
    );
    // And the odometry survives garbage too.
    let mut odo = Odometry::<16>::new(Config::default());
    odo.update(&sets_garbage(), None);
    odo.update(&[], None);
    let s = odo.update(
        &sets_garbage(),
        Some((Pose::new(f32::NAN, 0.0, 0.0), [[0.0; 3]; 3])),
    );
    assert!(
        s.pose.is_finite() && s.cov.iter().flatten().all(|v| v.is_finite()),
        "{s:?}"
    );
}

fn sets_garbage() -> Vec<Observation> {
    let cov = [[f32::NAN, 0.0], [0.0, 1.0]];
    vec![
        Observation::Line(LineObs::new(f32::NAN, 1.0, cov)),
        Observation::Point(PointObs::new(f32::INFINITY, 0.0, [[1.0, 0.0], [0.0, 1.0]])),
    ]
}

#[test]
fn odometry_tracks_a_room_better_than_chained_pairs() {
    let world = room();
    let cfg = exact();
    let (mut err_odo, mut err_chain) = (0.0f64, 0.0f64);
    for seed in 1..=6u64 {
        let mut rng = Rng(seed * 7919);
        let mut odo = Odometry::<48>::new(cfg);
        let mut truth = Pose::new(-2000.0, -1000.0, 0.2);
        let mut chained = Pose::IDENTITY;
        let start = truth;
        let mut prev = observe(&world, &truth, &mut rng);
        odo.update(&prev, None);
        let mut last = odo.update(&prev, None);
        // Drive around the room's middle.
        for k in 0..40 {
            let step = Pose::new(150.0, 0.0, if k % 10 < 5 { 0.16 } else { 0.0 });
            truth = truth.compose(&step);
            let obs = observe(&world, &truth, &mut rng);
            last = odo.update(&obs, None);
            assert_eq!(last.status, Status::Ok, "seed {seed} step {k}");
            let reg = register_with(&prev, &obs, None, &cfg);
            chained = chained.compose(&reg.rel);
            prev = obs;
        }
        let rel_truth = start.inverse().compose(&truth);
        let e = error(&last.pose, &rel_truth);
        // The pose's stated covariance covers its error (it bounds it from above).
        assert!(
            nis(&last.cov, &e) < 16.27,
            "seed {seed}: {e:?} vs {:?}",
            last.cov
        );
        err_odo += e[0].hypot(e[1]);
        let e = error(&chained, &rel_truth);
        err_chain += e[0].hypot(e[1]);
    }
    assert!(
        err_odo < err_chain,
        "odometry {err_odo} mm vs chained pairs {err_chain} mm"
    );
}

#[test]
fn prior_gates_the_hypotheses() {
    // A rectangular room seen from its centre looks the same turned by π: without a prior
    // the motion bounds pick the small rotation; a prior near the truth (a turn of π − 0.1)
    // gates the hypotheses to the right one.
    let world = World {
        walls: vec![
            ([-4000.0, -2500.0], [4000.0, -2500.0]),
            ([4000.0, -2500.0], [4000.0, 2500.0]),
            ([4000.0, 2500.0], [-4000.0, 2500.0]),
            ([-4000.0, 2500.0], [-4000.0, -2500.0]),
        ],
        pillars: Vec::new(),
    };
    let mut rng = Rng(17);
    let cfg = exact();
    let rel = Pose::new(0.0, 0.0, std::f32::consts::PI - 0.1);
    let a = observe(&world, &Pose::IDENTITY, &mut rng);
    let b = observe(&world, &rel, &mut rng);
    let free = register_with(&a, &b, None, &cfg);
    assert!((free.rel.theta + 0.1).abs() < 0.01, "{free:?}");
    let prior = (
        Pose::new(100.0, -100.0, rel.theta + 0.15),
        [
            [200.0f32 * 200.0, 0.0, 0.0],
            [0.0, 200.0 * 200.0, 0.0],
            [0.0, 0.0, 0.04],
        ],
    );
    let reg = register_with(&a, &b, Some(prior), &cfg);
    assert_eq!(reg.status, Status::Ok, "{reg:?}");
    let e = error(&reg.rel, &rel);
    for (k, ek) in e.iter().enumerate() {
        assert!(ek.abs() < 4.0 * f64::from(reg.cov[k][k]).sqrt(), "{reg:?}");
    }
}
