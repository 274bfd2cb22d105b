//! Where pfe `default` leaves bare beams on a real log: the real-data benchmark's bare% (`pfe
//! realdata`, docs/REALDATA.md) split by the length of each bare stretch and by what is beside
//! it (`L` a line, `C` a circle, `|` the end of its smooth run: a jump of ≥ 0.3 m or a
//! no-return), and, for stretches between a line's end and a run's end, by how far their
//! farthest beam lies from that line.
//!
//! `cargo run -p host-tests --release --example realdata_bare -- LOG [--show N]`
//!
//! `--show N` prints the first N stretches of two beams or more with the ranges around them
//! (the stretch in brackets).

use std::collections::BTreeMap;

use anyhow::{bail, Context, Result};
use pfe_core::Feature;
use pfe_eval::realdata::coverage::smooth_runs;
use pfe_eval::realdata::{log_scans, methods, LogScan};
use pfe_formats::Format;

mod common;
use common::LogArgs;

/// Bounds of the distance classes, mm.
const OFFSETS_MM: [f32; 4] = [30.0, 60.0, 100.0, 200.0];

fn main() -> Result<()> {
    let Some(args) = LogArgs::parse("realdata_bare", &["--show"])? else {
        return Ok(());
    };
    let mut show: usize = args.get("--show", 0)?;
    let log = &args.log;
    let mut ms = methods(Format::Carmen.sigma_r());
    let pfe = ms.first_mut().context("no method")?;
    let mut by_kind: BTreeMap<String, usize> = BTreeMap::new();
    let mut by_offset = [0usize; 5];
    let (mut valid_all, mut bare_all, mut scans) = (0usize, 0usize, 0usize);
    for (k, scan) in log_scans(std::path::Path::new(log))?.enumerate() {
        let LogScan {
            record: rec,
            context,
            ..
        } = scan?;
        scans += 1;
        let ex = pfe.extract_in(&rec.geometry, &rec.ranges_mm, &context);
        let r = &rec.ranges_mm;
        let n = r.len();
        // The feature each beam lies in, with its kind.
        let mut owner: Vec<Option<(char, &Feature)>> = vec![None; n];
        for f in &ex.features {
            let kind = if matches!(f, Feature::Line(_)) {
                'L'
            } else {
                'C'
            };
            for o in owner.iter_mut().take(f.last() + 1).skip(f.first()) {
                *o = Some((kind, f));
            }
        }
        valid_all += r
            .iter()
            .filter(|&&x| x.is_finite() && x > 0.0 && x <= rec.geometry.r_max)
            .count();
        for run in smooth_runs(&rec.geometry, r) {
            let (i, j) = (*run.start(), *run.end());
            let mut a = i;
            while a <= j {
                if owner[a].is_some() {
                    a += 1;
                    continue;
                }
                let mut b = a;
                while b < j && owner[b + 1].is_none() {
                    b += 1;
                }
                let len = b + 1 - a;
                bare_all += len;
                let side = |x: usize, end: bool| {
                    if end {
                        '|'
                    } else {
                        owner[x].map_or('-', |o| o.0)
                    }
                };
                let (left, right) = (side(a.wrapping_sub(1), a == i), side(b + 1, b == j));
                let bucket = match len {
                    1 => "1",
                    2 => "2",
                    3 => "3",
                    4..=5 => "4–5",
                    6..=9 => "6–9",
                    _ => "≥10",
                };
                *by_kind
                    .entry(format!("{bucket:>3} beams, {left}{right}"))
                    .or_default() += len;
                let line = match (left, right) {
                    ('L', '|') => owner[a - 1],
                    ('|', 'L') => owner[b + 1],
                    _ => None,
                };
                if let Some((_, Feature::Line(l))) = line {
                    let off = (a..=b)
                        .map(|x| (r[x] * (rec.geometry.bearing(x) - l.alpha).cos() - l.rho).abs())
                        .fold(0.0f32, f32::max);
                    let o = OFFSETS_MM.iter().take_while(|&&b| off >= b).count();
                    if let Some(slot) = by_offset.get_mut(o) {
                        *slot += len;
                    }
                }
                if show > 0 && len >= 2 {
                    show -= 1;
                    let around: Vec<String> = (a.saturating_sub(3)..=(b + 3).min(n - 1))
                        .map(|x| {
                            if (a..=b).contains(&x) {
                                format!("[{:.0}]", r[x])
                            } else {
                                format!("{:.0}", r[x])
                            }
                        })
                        .collect();
                    println!(
                        "scan {k} beams {a}..={b} {left}{right}: {}",
                        around.join(" ")
                    );
                }
                a = b + 1;
            }
        }
    }
    if scans == 0 {
        bail!("{log}: no scan");
    }
    let pct = |v: usize| 100.0 * v as f64 / valid_all.max(1) as f64;
    println!(
        "{log}: {scans} scans, bare {:.2} % of valid beams",
        pct(bare_all)
    );
    println!("by stretch length and neighbours (L line, C circle, | run end), % of valid beams:");
    for (kind, v) in &by_kind {
        println!("  {kind}: {:.3}", pct(*v));
    }
    println!("stretches between a line and a run end, by their farthest beam from the line:");
    let labels = ["< 30", "30–60", "60–100", "100–200", "≥ 200"];
    for (o, v) in labels.iter().zip(by_offset) {
        println!("  {o} mm: {:.3}", pct(v));
    }
    Ok(())
}
