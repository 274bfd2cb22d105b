//! How often `pfe_core::interleave::detect` declares a scan interleaved (issue 39, item 3):
//! on plain simulated scenes at several σ (its false positives), on interleaved ones with
//! offsets of 2–20 mm between sweeps (its detection rate), on recordings, and the eval's
//! scores of the interleaved 8 mm / 6 mrad case with the sweeps told and with `auto`.
//!
//! `cargo run -p host-tests --release --example sweeps_detect -- sim [--scans N] [--seeds A,B,..]`
//! `cargo run -p host-tests --release --example sweeps_detect -- score [--scans N] [--seeds A,B,..] [--sigma MM]`
//! `cargo run -p host-tests --release --example sweeps_detect -- log FORMAT FILE` (`PER_SCAN=1`: each scan)
//! `cargo run -p host-tests --release --example sweeps_detect -- csv OUT [--scans N] [--seeds S] [--sigma MM]`
//! (the interleaved scenes of seed S as CSV, for `pfe extract --format csv`)

use anyhow::{bail, Context, Result};
use pfe_core::interleave::detect;
use pfe_core::Scan;
use pfe_eval::methods::{Extraction, Method, Pfe, ScanContext};
use pfe_eval::scene::{Resolution, Scenario, SceneKind};
use pfe_eval::{run_methods, scan_seed, MOVING_OMEGA, MOVING_V};
use pfe_formats::Format;

/// One mirror turn of the LMS2xx, s.
const TURN_S: f32 = 1.0 / 75.0;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (mut scans, mut seeds, mut sigma) = (100usize, vec![11u64, 12, 13], 5.0f32);
    let mut rest = Vec::new();
    let mut it = args.iter().skip(1);
    while let Some(a) = it.next() {
        let mut val = || it.next().with_context(|| format!("{a} needs a value"));
        match a.as_str() {
            "--scans" => scans = val()?.parse()?,
            "--sigma" => sigma = val()?.parse()?,
            "--seeds" => {
                seeds = val()?
                    .split(',')
                    .map(|s| s.trim().parse())
                    .collect::<Result<_, _>>()?
            }
            other => rest.push(other.to_string()),
        }
    }
    match args.first().map(String::as_str) {
        Some("sim") => sim(scans, &seeds),
        Some("score") => score(scans, &seeds, sigma),
        Some("csv") => match rest.as_slice() {
            [out] => csv(out, scans, &seeds, sigma),
            _ => bail!("csv OUT"),
        },
        Some("log") => match rest.as_slice() {
            [format, file] => log(format, file),
            _ => bail!("log FORMAT FILE"),
        },
        _ => bail!("sweeps_detect sim|score|log ..."),
    }
}

/// The sweeps detected on each scenario's scan.
fn detected(sc: &Scenario) -> (u8, f32, f32) {
    let s = sc.simulate();
    let d = detect(&Scan::from_mm(s.geometry, &s.ranges_mm).with_quantum(s.mm_per_unit));
    (d.sweeps, d.evidence2, d.evidence4)
}

fn scenarios(scans: usize, seeds: &[u64], sigma: f32) -> Vec<Scenario> {
    seeds
        .iter()
        .flat_map(|&seed| {
            (0..scans)
                .map(move |i| Scenario::new(SceneKind::Mixed, scan_seed(seed, i)).with_sigma(sigma))
        })
        .collect()
}

/// Counts of 1, 2, 4 detected and the largest evidence.
fn tally(all: &[Scenario]) -> String {
    let mut n = [0usize; 3];
    let (mut e2, mut e4) = (Vec::new(), Vec::new());
    for sc in all {
        let (s, a, b) = detected(sc);
        n[match s {
            1 => 0,
            2 => 1,
            _ => 2,
        }] += 1;
        e2.push(a);
        e4.push(b);
    }
    let q = |v: &mut Vec<f32>, p: f32| {
        v.sort_by(f32::total_cmp);
        v[((v.len() - 1) as f32 * p) as usize]
    };
    format!(
        "n {:4}  1:{:4} 2:{:4} 4:{:4}  ev2 median {:7.2} max {:7.2}  ev4 median {:7.2} max {:7.2}",
        all.len(),
        n[0],
        n[1],
        n[2],
        q(&mut e2, 0.5),
        q(&mut e2, 1.0),
        q(&mut e4, 0.5),
        q(&mut e4, 1.0)
    )
}

fn sim(scans: usize, seeds: &[u64]) -> Result<()> {
    println!("plain scenes (standing still), 0.5° / 0.25° / 1°:");
    for res in [Resolution::Half, Resolution::Quarter, Resolution::One] {
        for sigma in [1.0, 2.0, 5.0, 10.0] {
            let mut all = scenarios(scans, seeds, sigma);
            all.iter_mut().for_each(|s| s.resolution = res);
            println!("  {res:?} σ {sigma:4} mm: {}", tally(&all));
        }
    }
    println!("one sweep moving (control: 8 mm / 6 mrad a turn, no interleaving), σ 5 mm:");
    let mut all = scenarios(scans, seeds, 5.0);
    all.iter_mut().for_each(|s| {
        *s = s.with_motion(MOVING_V, MOVING_OMEGA);
        s.one_sweep = true;
    });
    println!("  {}", tally(&all));
    for res in [Resolution::Half, Resolution::Quarter] {
        println!("interleaved {res:?}, d mm forward a mirror turn (and 0.75 mrad/mm turn):");
        for sigma in [1.0, 2.0, 5.0, 10.0] {
            for d in [2.0f32, 4.0, 8.0, 12.0, 20.0] {
                for turn in [false, true] {
                    let mut all = scenarios(scans, seeds, sigma);
                    let (v, w) = (d / TURN_S, if turn { 0.75e-3 * d / TURN_S } else { 0.0 });
                    all.iter_mut().for_each(|s| {
                        *s = s.with_motion(v, w);
                        s.resolution = res;
                    });
                    let t = if turn { "+turn" } else { "     " };
                    println!("  σ {sigma:4} d {d:4} {t}: {}", tally(&all));
                }
            }
        }
    }
    Ok(())
}

/// pfe-default with `--sweeps auto` as `pfe extract --format csv` takes it: detected from each
/// scan and held over the input's later scans (`pfe_formats::AutoSweeps`), or, with `held`
/// false, each scan on its own.
struct Auto(Pfe, String, pfe_formats::AutoSweeps, bool);

impl Method for Auto {
    fn name(&self) -> &str {
        &self.1
    }
    fn extract(&mut self, g: &pfe_core::ScanGeometry, r: &[f32]) -> Extraction {
        self.extract_in(g, r, &ScanContext::default())
    }
    fn extract_in(
        &mut self,
        g: &pfe_core::ScanGeometry,
        r: &[f32],
        context: &ScanContext,
    ) -> Extraction {
        let record = pfe_formats::Record {
            id: 0,
            geometry: *g,
            ranges_mm: r.to_vec(),
            time: None,
            pose: None,
            sweeps: None,
        };
        if !self.3 {
            self.2 = pfe_formats::AutoSweeps::new(Format::Csv);
        }
        let c = ScanContext {
            sweeps: usize::from(self.2.sweeps(&record)),
            ..*context
        };
        self.0.extract_in(g, r, &c)
    }
}

/// pfe-default told one sweep whatever the scan (`--sweeps auto` before detection, on CSV).
struct One(Pfe, String);

impl Method for One {
    fn name(&self) -> &str {
        &self.1
    }
    fn extract(&mut self, g: &pfe_core::ScanGeometry, r: &[f32]) -> Extraction {
        self.0.extract(g, r)
    }
    fn extract_in(&mut self, g: &pfe_core::ScanGeometry, r: &[f32], c: &ScanContext) -> Extraction {
        let c = ScanContext { sweeps: 1, ..*c };
        self.0.extract_in(g, r, &c)
    }
}

fn score(scans: usize, seeds: &[u64], sigma: f32) -> Result<()> {
    let cases: [pfe_eval::Condition; 4] = [
        ("plain", |_| {}),
        ("interleaved 0.5°, 8 mm / 6 mrad, no odometry", |s| {
            *s = s.with_motion(MOVING_V, MOVING_OMEGA)
        }),
        ("interleaved 0.25°, 8 mm / 6 mrad, no odometry", |s| {
            *s = s.with_motion(MOVING_V, MOVING_OMEGA);
            s.resolution = Resolution::Quarter;
        }),
        ("plain 0.5°, declared 2 sweeps", |_| {}),
    ];
    for seed in seeds {
        for (name, change) in cases {
            let mut all = scenarios(scans, &[*seed], sigma);
            all.iter_mut().for_each(change);
            let mut sims: Vec<_> = all.iter().map(Scenario::simulate).collect();
            if name.contains("declared 2") {
                sims.iter_mut().for_each(|s| s.sweeps = 2);
            }
            let mut told = Pfe::new(
                "pfe-default",
                pfe_core::Config::default().with_sigma_r(sigma),
            );
            let pfe = || {
                Pfe::new(
                    "pfe-default",
                    pfe_core::Config::default().with_sigma_r(sigma),
                )
            };
            let mut auto = Auto(
                pfe(),
                "auto".into(),
                pfe_formats::AutoSweeps::new(Format::Csv),
                true,
            );
            let mut each = Auto(
                pfe(),
                "auto-each".into(),
                pfe_formats::AutoSweeps::new(Format::Csv),
                false,
            );
            let mut one = One(pfe(), "one".into());
            let mut m: [&mut dyn Method; 4] = [&mut told, &mut auto, &mut each, &mut one];
            let res = run_methods(&mut m, &sims);
            println!(
                "seed {seed} σ {sigma} {name}: truth {}",
                sims.iter().map(|s| s.truth.len()).sum::<usize>()
            );
            for r in &res {
                let s = &r.score;
                println!(
                    "  {:<12} FalseMark {:.4} FalseIden {:.4} missed {:.3} spurious {:.3}",
                    if r.name == "pfe-default" {
                        "told"
                    } else {
                        &r.name
                    },
                    s.false_mark_ratio(),
                    s.false_iden_ratio(),
                    s.missed_ratio(),
                    s.spurious_ratio()
                );
            }
        }
    }
    Ok(())
}

fn log(format: &str, file: &str) -> Result<()> {
    let format = match format {
        "carmen" => Format::Carmen,
        "hokuyo" => Format::Hokuyo,
        "csv" => Format::Csv,
        f => bail!("format {f}: carmen, hokuyo or csv"),
    };
    let input = pfe_formats::open_for(std::path::Path::new(file), format, |r| r)
        .with_context(|| format!("opening {file}"))?;
    let mut n = [0usize; 3];
    let mut e2 = Vec::new();
    let mut told = [0usize; 5];
    let mut spent = std::time::Duration::ZERO;
    for record in pfe_formats::scans(format, input) {
        let record = record.map_err(|e| anyhow::anyhow!("{file}: {e}"))?;
        let q = pfe_formats::range_quantum(&record.ranges_mm, record.geometry.r_max);
        let t0 = std::time::Instant::now();
        let d = detect(&Scan::from_mm(record.geometry, &record.ranges_mm).with_quantum(q));
        spent += t0.elapsed();
        n[match d.sweeps {
            1 => 0,
            2 => 1,
            _ => 2,
        }] += 1;
        e2.push(d.evidence2);
        if std::env::var_os("PER_SCAN").is_some() {
            println!(
                "scan {} sweeps {} ev2 {:.2} ev4 {:.2}",
                record.id, d.sweeps, d.evidence2, d.evidence4
            );
        }
        let t = record
            .sweeps
            .unwrap_or_else(|| pfe_formats::sweeps_of(format, &record.geometry));
        told[usize::from(t).min(4)] += 1;
    }
    e2.sort_by(f32::total_cmp);
    let q = |p: f32| {
        e2.get(((e2.len().max(1) - 1) as f32 * p) as usize)
            .copied()
            .unwrap_or(0.0)
    };
    println!(
        "{file}: {} scans, format says 1:{} 2:{} 4:{}; detected 1:{} 2:{} 4:{}; ev2 p50 {:.2} p90 {:.2} p99 {:.2} max {:.2}; detect {:.1} µs a scan",
        e2.len(),
        told[1],
        told[2],
        told[4],
        n[0],
        n[1],
        n[2],
        q(0.5),
        q(0.9),
        q(0.99),
        q(1.0),
        spent.as_secs_f64() * 1e6 / e2.len().max(1) as f64
    );
    Ok(())
}

/// Writes the interleaved 8 mm / 6 mrad scenes of the first seed as `pfe extract --format csv`
/// reads them.
fn csv(out: &str, scans: usize, seeds: &[u64], sigma: f32) -> Result<()> {
    use std::fmt::Write as _;
    let mut text = String::new();
    for (k, sc) in scenarios(scans, &seeds[..1], sigma).into_iter().enumerate() {
        let s = sc.with_motion(MOVING_V, MOVING_OMEGA).simulate();
        let _ = write!(text, "{k},-90,0.5");
        for r in &s.ranges_mm {
            let _ = write!(text, ",{}", if r.is_finite() { *r } else { 0.0 });
        }
        text.push('\n');
    }
    std::fs::write(out, text)?;
    Ok(())
}
