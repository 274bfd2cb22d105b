//! The resumable registration ([`Resumable`]) against [`register_with`]: run to completion
//! with any sequence of budgets it gives the same registration, bit for bit, on many synthetic
//! pairs (rooms with pillars, clutter, periodic pillars, corridors; with and without priors;
//! the lazy and the full judgement of the runner-up).

use pfe_pose::register::{Progress, Resumable};
use pfe_pose::{register_with, Config, Cov3, LineObs, Observation, PointObs, Pose, Registration};

mod common;
use common::{corridor, Rng, World};

/// Random walls and pillars within 8 m of the origin; `periodic`: pillars on a 1 m grid.
fn world(rng: &mut Rng, periodic: bool) -> World {
    let n = (rng.uniform() * 30.0) as usize + 2;
    let walls = (0..n)
        .map(|_| {
            let c = [rng.range(-6000.0, 6000.0), rng.range(-6000.0, 6000.0)];
            let (len, dir) = (rng.range(300.0, 5000.0), rng.range(-3.2, 3.2));
            let h = [0.5 * len * dir.cos(), 0.5 * len * dir.sin()];
            ([c[0] - h[0], c[1] - h[1]], [c[0] + h[0], c[1] + h[1]])
        })
        .collect();
    let pillars = if periodic {
        (0..9)
            .map(|k| {
                [
                    1000.0 * (k % 3) as f32 - 1000.0,
                    1000.0 * (k / 3) as f32 + 1500.0,
                ]
            })
            .collect()
    } else {
        let m = (rng.uniform() * 14.0) as usize;
        (0..m)
            .map(|_| [rng.range(-5000.0, 5000.0), rng.range(-5000.0, 5000.0)])
            .collect()
    };
    World { walls, pillars }
}

/// The features of `world` seen from `pose`, with noise, a few dropped and a few spurious.
fn observe(world: &World, pose: &Pose, rng: &mut Rng) -> Vec<Observation> {
    let inv = pose.inverse();
    let (sa, sr, sp) = (0.004f32, 10.0f32, 15.0f32);
    let cov = [[sa * sa, 0.0], [0.0, sr * sr]];
    let mut out = Vec::new();
    for (s, e) in &world.walls {
        if rng.uniform() < 0.1 {
            continue;
        }
        let (s, e) = (inv.transform_point(*s), inv.transform_point(*e));
        let d = [e[0] - s[0], e[1] - s[1]];
        let len = d[0].hypot(d[1]);
        let n = [d[1] / len, -d[0] / len];
        let rho = s[0] * n[0] + s[1] * n[1];
        let (alpha, rho) = if rho < 0.0 {
            ((-n[1]).atan2(-n[0]), -rho)
        } else {
            (n[1].atan2(n[0]), rho)
        };
        let a = alpha + sa * rng.normal() as f32;
        let r = rho + sr * rng.normal() as f32;
        let (sn, cs) = (a.sin(), a.cos());
        let proj = |p: [f32; 2]| {
            let t = -sn * p[0] + cs * p[1];
            [r * cs - t * sn, r * sn + t * cs]
        };
        out.push(Observation::Line(
            LineObs::new(a, r, cov).with_extent(proj(s), proj(e)),
        ));
    }
    let pc = [[sp * sp, 0.0], [0.0, sp * sp]];
    for p in &world.pillars {
        if rng.uniform() < 0.1 {
            continue;
        }
        let q = inv.transform_point(*p);
        let q = [
            q[0] + sp * rng.normal() as f32,
            q[1] + sp * rng.normal() as f32,
        ];
        out.push(Observation::Point(PointObs::new(q[0], q[1], pc)));
    }
    for _ in 0..(rng.uniform() * 3.0) as usize {
        out.push(Observation::Point(PointObs::new(
            rng.range(-5000.0, 5000.0),
            rng.range(-5000.0, 5000.0),
            pc,
        )));
    }
    out
}

/// Bit for bit (`{:?}` of f32 is exact, and tells NaN and −0 apart).
fn same(a: &Registration, b: &Registration) -> bool {
    format!("{a:?}") == format!("{b:?}")
}

/// Runs `search` to completion with budgets from `budget`; the result and the calls taken.
fn run(mut search: Resumable, mut budget: impl FnMut() -> u32) -> (Registration, usize) {
    let mut calls = 1;
    loop {
        if let Progress::Done(r) = search.step(budget()) {
            // Done stays done.
            assert_eq!(search.step(1), Progress::Done(r));
            return (r, calls);
        }
        calls += 1;
        assert!(calls < 100_000, "the search never completed");
    }
}

#[test]
fn resumable_equals_register_for_any_budget() {
    let mut rng = Rng(0x0dd_b1a5_e5ca_1ab1);
    let mut lazy_cfg = Config::default();
    lazy_cfg.max_translation = 3000.0;
    let mut full_cfg = Config::default();
    full_cfg.ambiguity = 1.1; // the runner-up judged at every refined pose
    let corridor = corridor();
    let (mut most_calls, mut pending) = (0usize, 0usize);
    let mut statuses = std::collections::BTreeSet::new();
    for trial in 0..300 {
        let w = match trial % 5 {
            4 => None,
            3 => Some(world(&mut rng, true)),
            _ => Some(world(&mut rng, false)),
        };
        let w = w.as_ref().unwrap_or(&corridor);
        let p0 = Pose::new(
            rng.range(-1500.0, 1500.0),
            rng.range(-1000.0, 1000.0),
            rng.range(-3.1, 3.1),
        );
        let (dist, dir) = (rng.range(0.0, 1800.0), rng.range(-3.2, 3.2));
        let rel = Pose::new(dist * dir.cos(), dist * dir.sin(), rng.range(-1.4, 1.4));
        let a = observe(w, &p0, &mut rng);
        let b = observe(w, &p0.compose(&rel), &mut rng);
        let prior: Option<(Pose, Cov3)> = match trial % 3 {
            0 => Some((
                Pose::new(rel.x + 100.0, rel.y - 50.0, rel.theta + 0.02),
                [[4e4, 0.0, 0.0], [0.0, 4e4, 0.0], [0.0, 0.0, 0.01]],
            )),
            _ => None,
        };
        let mut cfg = if trial % 2 == 0 { lazy_cfg } else { full_cfg };
        if trial % 7 == 1 {
            cfg.scored = 2; // fewer clusters scored than formed
        }
        let want = register_with(&a, &b, prior, &cfg);
        statuses.insert(
            format!("{:?}", want.status)
                .chars()
                .take(8)
                .collect::<String>(),
        );
        let mut seq = Rng(trial);
        let runs = [
            run(Resumable::new(&a, &b, prior, &cfg), || 1),
            run(Resumable::new(&a, &b, prior, &cfg), || 0),
            run(Resumable::new(&a, &b, prior, &cfg), || 3),
            run(Resumable::new(&a, &b, prior, &cfg), || u32::MAX),
            run(Resumable::new(&a, &b, prior, &cfg), || {
                (seq.uniform() * 12.0) as u32
            }),
        ];
        for (k, (got, calls)) in runs.iter().enumerate() {
            assert!(
                same(got, &want),
                "trial {trial}, run {k} ({calls} calls): {got:?} != {want:?}"
            );
        }
        // Without a limit, one call.
        assert_eq!(runs[3].1, 1, "trial {trial}");
        most_calls = most_calls.max(runs[0].1);
        pending += usize::from(runs[0].1 > 1);
    }
    // The searches were spread over many calls, and every kind of outcome was met.
    assert!(most_calls > 100, "{most_calls}");
    assert!(pending > 250, "{pending}");
    assert!(statuses.len() >= 3, "{statuses:?}");
}

/// Degenerate inputs complete at once with [`register_with`]'s failure.
#[test]
fn resumable_fails_like_register() {
    let cfg = Config::default();
    let line = Observation::Line(LineObs::new(0.3, 2000.0, [[1e-5, 0.0], [0.0, 25.0]]));
    let bad_prior = Some((Pose::new(f32::NAN, 0.0, 0.0), [[1.0; 3]; 3]));
    for (a, b, prior) in [
        (vec![], vec![], None),
        (vec![line], vec![line, line], None),
        (vec![line, line], vec![line, line], bad_prior),
    ] {
        let want = register_with(&a, &b, prior, &cfg);
        let (got, calls) = run(Resumable::new(&a, &b, prior, &cfg), || 1);
        assert!(same(&got, &want), "{got:?} != {want:?}");
        assert!(calls <= 2, "{calls}");
    }
}
