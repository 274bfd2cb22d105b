//! Where line covariances are too small or too large on real data: the real-data benchmark's
//! line NIS after the per-pair pose refit (`pfe realdata`, docs/REALDATA.md "NIS refit") on one
//! CARMEN log, for pfe `default`, next to what consistent covariances would give on the same
//! lines and refits ("if consistent"), by class of line, with its α and ρ parts.
//!
//! `cargo run -p host-tests --release --example realdata_nis -- LOG [--sigma-r MM] [--sigma-sys MM]`
//!
//! A ratio (measured median / consistent median) above 1: the lines' differences between scans
//! exceed their covariances; below 1: the covariances exceed them. The α and ρ parts are each
//! difference's squared component over its own variance. Scans taken from nearly one place see
//! one wall's roughness and the scanner's systematic error alike: their errors are correlated,
//! which the sum of both covariances ignores, so there the ratio lies below 1 even where each
//! scan's covariance is right.

use std::collections::BTreeMap;

use anyhow::Result;
use pfe_eval::methods::{Method, Pfe};
use pfe_eval::realdata::compare::matched_lines;
use pfe_eval::realdata::frame::nis;
use pfe_eval::realdata::refit::{drawn, refit_residuals};
use pfe_eval::realdata::{FrameChange, LineObs, Seen};
use pfe_eval::score::quantile;
use pfe_formats::Format;
use rand::SeedableRng;

mod common;
use common::{for_each_pair, LogArgs};

/// Consistent draws per refitted pair.
const DRAWS: usize = 8;

/// Measured and consistent values of one class: NIS, its α part, its ρ part.
#[derive(Default)]
struct Class {
    measured: [Vec<f64>; 3],
    consistent: [Vec<f64>; 3],
}

fn main() -> Result<()> {
    let Some(args) = LogArgs::parse("realdata_nis", &["--sigma-r", "--sigma-sys"])? else {
        return Ok(());
    };
    let sigma_r: f32 = args.get("--sigma-r", Format::Carmen.sigma_r())?;
    let sigma_sys: f32 = args.get("--sigma-sys", Format::Carmen.sigma_sys())?;
    let log = &args.log;
    let config = pfe_core::Config::default()
        .with_sigma_r(sigma_r)
        .with_sigma_sys(sigma_sys);
    let mut pfe: [Box<dyn Method>; 1] = [Box::new(Pfe::new("pfe-default", config))];
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let mut classes: BTreeMap<String, Class> = BTreeMap::new();
    for_each_pair(log, &mut pfe, |_, a, b| add(&mut classes, a, b, &mut rng))?;
    println!("{log}: pfe-default, σ_r {sigma_r} mm, σ_sys {sigma_sys} mm; medians, ratio = measured / consistent");
    println!(
        "{:14} {:>6} | {:>6} {:>6} {:>5} | {:>6} {:>6} {:>5} | {:>6} {:>6} {:>5}",
        "class", "lines", "NIS", "cons.", "ratio", "α", "cons.", "ratio", "ρ", "cons.", "ratio"
    );
    for (name, c) in &classes {
        let mut cells = Vec::new();
        for k in 0..3 {
            let (m, s) = (
                quantile(&c.measured[k], 0.5),
                quantile(&c.consistent[k], 0.5),
            );
            cells.push(format!("{m:>6.2} {s:>6.2} {:>5.2}", m / s));
        }
        println!(
            "{name:14} {:>6} | {}",
            c.measured[0].len(),
            cells.join(" | ")
        );
    }
    Ok(())
}

/// The classes of a matched line of `m` matched in its pair.
fn classes_of(l: &LineObs, m: usize) -> [String; 7] {
    let length = (l.end[0] - l.start[0]).hypot(l.end[1] - l.start[1]);
    let mid = [(l.start[0] + l.end[0]) / 2.0, (l.start[1] + l.end[1]) / 2.0];
    let incidence = (l.rho.abs() / mid[0].hypot(mid[1]).max(1.0))
        .min(1.0)
        .acos()
        .to_degrees();
    let sigma_alpha = l.cov[0][0].sqrt();
    let pick = |v: f64, bounds: [f64; 2], names: [&str; 3]| {
        names[usize::from(v >= bounds[0]) + usize::from(v >= bounds[1])].to_string()
    };
    [
        "all".to_string(),
        format!(
            "points {}",
            pick(l.points as f64, [20.0, 40.0], ["10-19", "20-39", "40+"])
        ),
        format!(
            "ρ {}",
            pick(l.rho.abs(), [1500.0, 4000.0], ["<1.5 m", "1.5-4 m", ">4 m"])
        ),
        format!(
            "length {}",
            pick(length, [1000.0, 3000.0], ["<1 m", "1-3 m", ">3 m"])
        ),
        format!(
            "σα {}",
            pick(sigma_alpha, [0.003, 0.010], ["<3 mrad", "3-10", ">10"])
        ),
        format!(
            "pair has {}",
            pick(m as f64, [5.0, 8.0], ["3-4", "5-7", "8+"])
        ),
        format!(
            "incidence {}",
            pick(incidence, [45.0, 70.0], ["<45°", "45-70°", ">70°"])
        ),
    ]
}

/// Scan `a`'s lines matched in `b`, refitted, and the same refitted from consistent draws.
fn add(classes: &mut BTreeMap<String, Class>, a: &Seen, b: &Seen, rng: &mut impl rand::Rng) {
    let matched = matched_lines(a, b, &FrameChange::between(a.pose, b.pose));
    let innovations: Vec<_> = matched.iter().map(|(_, inn)| *inn).collect();
    let Some(residuals) = refit_residuals(&innovations) else {
        return;
    };
    let draws: Vec<Vec<[f64; 2]>> = (0..DRAWS)
        .filter_map(|_| refit_residuals(&drawn(&innovations, rng)))
        .collect();
    let parts = |r: [f64; 2], s: &[[f64; 2]; 2]| {
        [
            nis(r, s),
            Some(r[0] * r[0] / s[0][0]),
            Some(r[1] * r[1] / s[1][1]),
        ]
    };
    for (i, ((l, inn), r)) in matched.iter().zip(&residuals).enumerate() {
        for name in classes_of(l, matched.len()) {
            let c = classes.entry(name).or_default();
            for (k, v) in parts(*r, &inn.s).into_iter().enumerate() {
                c.measured[k].extend(v);
            }
            for d in &draws {
                for (k, v) in parts(d[i], &inn.s).into_iter().enumerate() {
                    c.consistent[k].extend(v);
                }
            }
        }
    }
}
