//! Interleaved sweeps moved onto sweep 0 by an offset estimated from the scan (no odometry):
//! the estimate's own error moves every feature by the share of points its sweep holds, and
//! the features' covariances must carry it. Truth: six rooms (`common::room`), the odd sweep
//! seen from 8 mm ahead and turned 6 mrad, 5 mm noise, 400 scans each; the spread of each
//! long wall's fitted α and ρ and of the pillar's centre against the mean stated variance.
//! Without the offsets' share the long walls' ρ spread is 1.3–3.8× the stated variance.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

mod common;

use common::{cast, room, seen_from, Noise, Prim};
use pfe_core::{Config, Extractor, Feature, Scan, ScanGeometry};
use std::f64::consts::PI;

const SCANS: usize = 400;

fn var(xs: &[f64]) -> f64 {
    let m = xs.iter().sum::<f64>() / xs.len() as f64;
    xs.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (xs.len() - 1) as f64
}

fn wrap(a: f64) -> f64 {
    (a + PI).rem_euclid(2.0 * PI) - PI
}

/// Fitted values and the sum of their stated variances.
#[derive(Default)]
struct Spread {
    values: Vec<f64>,
    stated: f64,
}

impl Spread {
    fn add(&mut self, value: f64, stated: f32) {
        self.values.push(value);
        self.stated += f64::from(stated);
    }

    /// Spread over mean stated variance.
    fn ratio(&self) -> f64 {
        var(&self.values) / (self.stated / self.values.len() as f64)
    }
}

/// (α, ρ) of the wall `x0 y0 – x1 y1`, ρ ≥ 0.
fn wall(x0: f64, y0: f64, x1: f64, y1: f64) -> (f64, f64) {
    let l = (x1 - x0).hypot(y1 - y0);
    let (nx, ny) = (-(y1 - y0) / l, (x1 - x0) / l);
    let rho = nx * x0 + ny * y0;
    let alpha = ny.atan2(nx);
    if rho < 0.0 {
        (wrap(alpha + PI), -rho)
    } else {
        (alpha, rho)
    }
}

#[test]
fn features_of_aligned_sweeps_carry_the_offsets_error() {
    let g = ScanGeometry::LMS200_180_050;
    let mut rooms = Noise::new(3);
    let mut ex = Extractor::<361, 64>::new();
    let mut alpha_ratios = Vec::new();
    for room_no in 0..6 {
        let prims: Vec<Prim> = room(&mut rooms);
        let odd = seen_from(&prims, (8.0, 0.0, 0.006));
        let mut noise = Noise::new(100 + room_no);
        let mut walls: Vec<(Spread, Spread)> = (0..4).map(|_| Default::default()).collect();
        let (mut cx, mut cy) = (Spread::default(), Spread::default());
        let Prim::Circle(px, py, _) = prims[4] else {
            panic!("the room's fifth primitive is its pillar")
        };
        for _ in 0..SCANS {
            let ranges: Vec<f32> = (0..361)
                .map(|i| {
                    let seen = if i % 2 == 1 { &odd } else { &prims };
                    match cast(seen, f64::from(g.bearing(i))) {
                        Some((t, _)) if t < 7900.0 => (t + 5.0 * noise.gauss()) as f32,
                        _ => f32::NAN,
                    }
                })
                .collect();
            let scan = Scan::from_mm(g, &ranges).with_sweeps(2);
            ex.extract(&scan, &Config::default().with_sigma_r(5.0))
                .unwrap();
            assert_eq!(ex.stats().sweeps_aligned, 1, "room {room_no}");
            for f in ex.features() {
                match f {
                    Feature::Line(l) if l.points > 60 => {
                        for (k, p) in prims.iter().take(4).enumerate() {
                            let Prim::Seg(x0, y0, x1, y1) = *p else {
                                continue;
                            };
                            let (alpha, rho) = wall(x0, y0, x1, y1);
                            let da = wrap(f64::from(l.alpha) - alpha);
                            let dr = f64::from(l.rho) - rho;
                            if da.abs() < 0.05 && dr.abs() < 100.0 {
                                walls[k].0.add(da, l.var_alpha);
                                walls[k].1.add(dr, l.var_rho);
                            }
                        }
                    }
                    Feature::Circle(c) => {
                        let (x, y) = (f64::from(c.center.x), f64::from(c.center.y));
                        if (x - px).hypot(y - py) < 100.0 {
                            cx.add(x, c.cov[0][0]);
                            cy.add(y, c.cov[1][1]);
                        }
                    }
                    _ => {}
                }
            }
        }
        for (k, (a, r)) in walls.iter().enumerate() {
            if a.values.len() < SCANS * 3 / 4 {
                continue;
            }
            let (ra, rr) = (a.ratio(), r.ratio());
            eprintln!("room {room_no} wall {k}: spread/stated α {ra:.2}, ρ {rr:.2}");
            assert!(
                (0.6..=1.6).contains(&rr),
                "room {room_no} wall {k}: ρ {rr:.2}"
            );
            alpha_ratios.push(ra);
        }
        assert!(cx.values.len() > SCANS * 3 / 4, "room {room_no}: pillar");
        let (rx, ry) = (cx.ratio(), cy.ratio());
        eprintln!("room {room_no} pillar: spread/stated x {rx:.2}, y {ry:.2}");
        assert!(
            (0.7..=1.4).contains(&rx) && (0.7..=1.4).contains(&ry),
            "room {room_no}: pillar {rx:.2} {ry:.2}"
        );
    }
    alpha_ratios.sort_by(f64::total_cmp);
    assert!(alpha_ratios.len() >= 8, "{alpha_ratios:?}");
    let median = alpha_ratios[alpha_ratios.len() / 2];
    assert!((0.6..=1.4).contains(&median), "α: {alpha_ratios:?}");
}
