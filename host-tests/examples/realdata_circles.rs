//! Why circle centres move more than their covariance says: the real-data benchmark's circle
//! centre NIS after the lines' pose refit (`pfe realdata`, docs/REALDATA.md "circ NIS refit")
//! for pfe `default` on one CARMEN log, split by class of circle.
//!
//! `cargo run -p host-tests --release --example realdata_circles -- LOG [--sigma-r MM]`
//!
//! Classes: the circle's radius, its points, and the reduced χ² of its fit against σ_r
//! (`Σ (|p − c| − r)² / (σ_r² (n − 3))` over its valid beams; what the noise model does not
//! explain). Per class: the median NIS (χ²₂ median 1.39 when consistent) and its two parts,
//! the squared normalised difference along the line of sight to the centre and across it
//! (each χ²₁, median 0.45), with the median differences in mm. A range bias moves a centre
//! along the line of sight; a shape that is not a circle, seen from elsewhere, moves it
//! either way.

use anyhow::Result;
use pfe_core::Feature;
use pfe_eval::methods::Extraction;
use pfe_eval::realdata::compare::{matched_lines, refit_centre, GATE_CENTER_MM};
use pfe_eval::realdata::frame::nis;
use pfe_eval::realdata::refit::{correction, correction_covariance};
use pfe_eval::realdata::{methods, FrameChange, Seen};
use pfe_eval::score::quantile;
use pfe_formats::{Format, Record};

mod common;
use common::{for_each_pair_with, LogArgs};

/// A class of circles: its name and whether a circle (radius mm, points, reduced χ²) is in it.
type Class = (&'static str, fn(f64, usize, f64) -> bool);

const CLASSES: [Class; 12] = [
    ("radius < 150 mm", |r, _, _| r < 150.0),
    ("radius 150–400 mm", |r, _, _| (150.0..400.0).contains(&r)),
    ("radius ≥ 400 mm", |r, _, _| r >= 400.0),
    ("points < 8", |_, n, _| n < 8),
    ("points 8–11", |_, n, _| (8..12).contains(&n)),
    ("points 12–19", |_, n, _| (12..20).contains(&n)),
    ("points ≥ 20", |_, n, _| n >= 20),
    ("χ²red < 1", |_, _, c| c < 1.0),
    ("χ²red 1–2", |_, _, c| (1.0..2.0).contains(&c)),
    ("χ²red 2–4", |_, _, c| (2.0..4.0).contains(&c)),
    ("χ²red ≥ 4", |_, _, c| c >= 4.0),
    ("all", |_, _, _| true),
];

/// A circle's radius (mm), points and reduced χ².
type Traits = (f64, usize, f64);

/// One matched circle of scan k: its traits and (NIS, z² along, z² across, |d| along,
/// |d| across).
type Sample = (Traits, [f64; 5]);

fn main() -> Result<()> {
    let Some(args) = LogArgs::parse("realdata_circles", &["--sigma-r"])? else {
        return Ok(());
    };
    let sigma_r: f32 = args.get("--sigma-r", Format::Carmen.sigma_r())?;
    let log = &args.log;
    let mut ms = methods(sigma_r);
    ms.truncate(1);
    let var = f64::from(sigma_r) * f64::from(sigma_r);
    let mut samples: Vec<Sample> = Vec::new();
    // Per circle of a scan, in the order of its `Seen::circles`.
    let traits = |record: &Record, ex: &Extraction| -> Vec<Traits> {
        ex.features
            .iter()
            .filter_map(|f| match f {
                Feature::Circle(c) => Some(c),
                _ => None,
            })
            .map(|c| {
                let (mut sse, mut n) = (0.0f64, 0usize);
                for i in usize::from(c.first)..=usize::from(c.last) {
                    if let Some((x, y)) = record.point(i) {
                        let d = f64::from(x - c.center.x).hypot(f64::from(y - c.center.y));
                        sse += (d - f64::from(c.radius)).powi(2);
                        n += 1;
                    }
                }
                let chi2 = sse / (var * (n as f64 - 3.0).max(1.0));
                (f64::from(c.radius), n, chi2)
            })
            .collect()
    };
    for_each_pair_with(log, &mut ms, traits, |_, (a, a_traits), (b, _)| {
        samples.extend(pair_samples(a, a_traits, b));
    })?;
    println!("{log}: σ_r {sigma_r} mm; pfe-default's matched circles after the lines' pose refit");
    println!(
        "{:18} {:>6} {:>6} | {:>8} {:>8} | {:>8} {:>8}",
        "class", "n", "NIS", "z² along", "z² acr.", "|d| along", "|d| acr."
    );
    for (name, holds) in CLASSES {
        let of: Vec<&[f64; 5]> = samples
            .iter()
            .filter(|((r, n, c), _)| holds(*r, *n, *c))
            .map(|(_, v)| v)
            .collect();
        let med = |k: usize| {
            let v: Vec<f64> = of.iter().filter_map(|s| s.get(k).copied()).collect();
            quantile(&v, 0.5)
        };
        println!(
            "{name:18} {:>6} {:>6.2} | {:>8.2} {:>8.2} | {:>6.1} mm {:>6.1} mm",
            of.len(),
            med(0),
            med(1),
            med(2),
            med(3),
            med(4)
        );
    }
    Ok(())
}

/// The matched circles of scan `a` (classes `a_classes`) in scan `b`, refitted by the pair's
/// lines as the benchmark does; none when the pair has no refit.
fn pair_samples(a: &Seen, a_classes: &[Traits], b: &Seen) -> Vec<Sample> {
    let change = FrameChange::between(a.pose, b.pose);
    let lines: Vec<_> = matched_lines(a, b, &change)
        .into_iter()
        .map(|(_, inn)| inn)
        .collect();
    let Some(delta) = correction(&lines).zip(correction_covariance(&lines)) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for (c, &class) in a.circles.iter().zip(a_classes) {
        let moved = change.circle(c);
        let best = b
            .circles
            .iter()
            .map(|o| {
                let d = (moved.center[0] - o.center[0]).hypot(moved.center[1] - o.center[1]);
                (d, o)
            })
            .filter(|(d, _)| *d < GATE_CENTER_MM)
            .min_by(|x, y| x.0.total_cmp(&y.0));
        let Some((_, o)) = best else { continue };
        let (d, s) = refit_centre(&moved, o, &delta);
        let Some(n) = nis(d, &s) else { continue };
        // Along the line of sight from scan k+1's scanner to the centre, and across it.
        let range = o.center[0].hypot(o.center[1]);
        if range.is_nan() || range <= 0.0 {
            continue;
        }
        let u = [o.center[0] / range, o.center[1] / range];
        let v = [-u[1], u[0]];
        let part = |w: [f64; 2]| {
            let dd = d[0] * w[0] + d[1] * w[1];
            let sd =
                w[0] * (s[0][0] * w[0] + s[0][1] * w[1]) + w[1] * (s[1][0] * w[0] + s[1][1] * w[1]);
            (dd * dd / sd, dd.abs())
        };
        let ((zu, du), (zv, dv)) = (part(u), part(v));
        out.push((class, [n, zu, zv, du, dv]));
    }
    out
}
