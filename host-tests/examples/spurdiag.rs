//! Diagnostic: lists each spurious and each mistyped pfe-default feature on simulated scans
//! with the truth of its beams (primitive runs: `L3x4` = 4 beams on line primitive 3,
//! `C5x2` circle primitive 5, `-x1` no return / mixed pixel).
//!
//! The same scans and scoring as `pfe eval` (`scenarios(kind, scans, sigma, seed)`); the last
//! line is the totals. `--dump SCAN,FIRST,LAST` prints beams FIRST..=LAST of scan SCAN instead
//! (range, true range, point, primitive, marks, features) and writes it to /tmp/spurdiag.csv
//! (`pfe plot --format csv`).
//!
//! `cargo run -p host-tests --release --example spurdiag -- --kind corridor --scans 100 [--seed 1] [--sigma 5] [--dump S,A,B]`

use anyhow::{bail, Context, Result};
use pfe_core::Feature;
use pfe_eval::methods::{Method, Pfe};
use pfe_eval::scenarios;
use pfe_eval::scene::{SceneKind, Shape};
use pfe_eval::score::{match_features, score_sim, Score};

fn runs(sim: &pfe_eval::scene::SimScan, a: usize, b: usize) -> String {
    let mut out = Vec::new();
    let mut i = a;
    while i <= b {
        let p = sim.beam_primitive.get(i).copied().flatten();
        let mut j = i;
        while j < b && sim.beam_primitive.get(j + 1).copied().flatten() == p {
            j += 1;
        }
        let tag = match p {
            None => "-".to_string(),
            Some(k) => match sim.shapes.get(k) {
                Some(Shape::Circle { radius, .. }) => format!("C{k}(r{:.0})", radius),
                _ => format!("L{k}"),
            },
        };
        out.push(format!("{tag}x{}", j + 1 - i));
        i = j + 1;
    }
    out.join(" ")
}

fn kind(f: &Feature) -> &'static str {
    match f {
        Feature::Line(_) => "line",
        Feature::Circle(_) => "circle",
        Feature::Object(_) => "object",
        _ => "other",
    }
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (mut kind_s, mut scans, mut sigma, mut seed) =
        (SceneKind::Corridor, 100usize, 5.0f32, 1u64);
    let mut dump: Option<(usize, usize, usize)> = None;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().with_context(|| format!("{a} needs a value"));
        match a.as_str() {
            "--kind" => kind_s = val()?.parse().map_err(anyhow::Error::msg)?,
            "--scans" => scans = val()?.parse()?,
            "--sigma" => sigma = val()?.parse()?,
            "--seed" => seed = val()?.parse()?,
            "--dump" => {
                let v: Vec<usize> = val()?
                    .split(',')
                    .map(|x| x.parse())
                    .collect::<Result<_, _>>()?;
                dump = Some((v[0], v[1], v[2]));
            }
            other => bail!("unknown argument `{other}`"),
        }
    }
    let mut pfe = Pfe::new(
        "pfe-default",
        pfe_core::Config::default().with_sigma_r(sigma),
    );
    let mut total = Score::default();
    for (si, sc) in scenarios(kind_s, scans, sigma, seed).iter().enumerate() {
        let sim = sc.simulate();
        let ex = pfe.extract_in(&sim.geometry, &sim.ranges_mm, &sim.context());
        let s = score_sim(&ex, &sim);
        total.add(&s);
        let m = match_features(&sim.truth, &ex.features);
        if let Some((ds, a, b)) = dump {
            if ds != si {
                continue;
            }
            let g = &sim.geometry;
            let csv: Vec<String> = sim
                .ranges_mm
                .iter()
                .map(|r| {
                    if r.is_finite() {
                        format!("{r:.0}")
                    } else {
                        "0".into()
                    }
                })
                .collect();
            std::fs::write(
                "/tmp/spurdiag.csv",
                format!(
                    "0,{},{},{}\n",
                    g.start_angle.to_degrees(),
                    g.angle_step.to_degrees(),
                    csv.join(",")
                ),
            )?;
            for i in a..=b.min(sim.ranges_mm.len() - 1) {
                let mk = if ex.marks.contains(&i) { "M" } else { " " };
                let feats: Vec<String> = ex
                    .features
                    .iter()
                    .filter(|f| f.first() <= i && i <= f.last())
                    .map(|f| format!("{}{}..{}", kind(f), f.first(), f.last()))
                    .collect();
                let ang = g.start_angle + g.angle_step * i as f32;
                let r = sim.ranges_mm[i];
                println!(
                    "{i:4} {mk} r {:7.0} true {:9.1} x {:7.0} y {:7.0} {:?} {}",
                    r,
                    sim.true_ranges_mm[i],
                    r * ang.cos(),
                    r * ang.sin(),
                    sim.beam_primitive[i],
                    feats.join(" ")
                );
            }
            for (k, sh) in sim.shapes.iter().enumerate() {
                if sim.beam_primitive[a..=b.min(sim.ranges_mm.len() - 1)].contains(&Some(k)) {
                    println!("shape {k}: {sh:?}");
                }
            }
            return Ok(());
        }
        for (pi, f) in ex.features.iter().enumerate() {
            let (a, b) = (f.first(), f.last());
            let ctx = format!(
                "[{}] {} [{}]",
                runs(
                    &sim,
                    a.saturating_sub(3),
                    a.saturating_sub(1).max(a.saturating_sub(3))
                ),
                runs(&sim, a, b),
                runs(&sim, b + 1, (b + 3).min(sim.beam_primitive.len() - 1))
            );
            let rng = |i: usize| sim.ranges_mm.get(i).copied().unwrap_or(f32::NAN);
            match m.iter().find(|x| x.1 == pi) {
                None => {
                    // unscorable objects are skipped like the scorer does
                    let unscorable = f.is_object()
                        && sim.truth.iter().all(|t| {
                            let (lo, hi) = (t.first.max(a), t.last.min(b));
                            hi < lo || hi + 1 - lo < pfe_eval::scene::MIN_RUN
                        });
                    if !unscorable {
                        println!(
                            "SPUR scan {si} {} {a}..{b} ({} beams) r {:.0}..{:.0} truth {ctx}",
                            kind(f),
                            b + 1 - a,
                            rng(a),
                            rng(b)
                        );
                    }
                }
                Some(&(ti, _)) => {
                    let t = &sim.truth[ti];
                    let bad = !matches!(
                        (t.kind.is_line(), f),
                        (true, Feature::Line(_)) | (false, Feature::Circle(_) | Feature::Object(_))
                    );
                    if bad {
                        println!(
                            "IDEN scan {si} {} {a}..{b} ({} beams) r {:.0}..{:.0} truth-feature {}..{} {} truth {ctx}",
                            kind(f),
                            b + 1 - a,
                            rng(a),
                            rng(b),
                            t.first,
                            t.last,
                            if t.kind.is_line() { "line" } else { "circle" }
                        );
                    }
                }
            }
        }
        for (ti, t) in sim.truth.iter().enumerate() {
            if !m.iter().any(|x| x.0 == ti) {
                println!(
                    "MISS scan {si} {}..{} {} truth {}",
                    t.first,
                    t.last,
                    if t.kind.is_line() { "line" } else { "circle" },
                    runs(
                        &sim,
                        t.first.saturating_sub(2),
                        (t.last + 2).min(sim.beam_primitive.len() - 1)
                    )
                );
            }
        }
    }
    println!(
        "TOTAL truth {} matched {} FalseMark {:.4} FalseIden {:.4} ({}+{}) missed {} spurious {}",
        total.truth_features,
        total.matched,
        total.false_mark_ratio(),
        total.false_iden_ratio(),
        total.circles_as_lines,
        total.lines_as_circles,
        total.missed,
        total.spurious
    );
    Ok(())
}
