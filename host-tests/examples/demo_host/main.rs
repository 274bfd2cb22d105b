//! Host side of `cargo xtask demo`, `bench-mcu` and `size`: runs the pfe firmware under QEMU
//! (mps2-an386) and reads the feature frames it sends on UART1.
//!
//! ```text
//! demo_host bench-scans --scans 100 --out scans.bin      # simulated B0 telegrams for pfe-bench
//! demo_host bench --elf pfe-bench [--elf-micromath pfe-bench-mm] [--md docs/PERFORMANCE.md]
//! demo_host demo --elf pfe-qemu [--scans 10] [--config default|paper] [--svg demo.svg]
//! ```

use host_tests::qemu;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::{bail, Context, Result};
use firmware::output::{Header, Report, Stage};
use host_tests::scene::{Scenario, SceneKind};

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (cmd, rest) = args
        .split_first()
        .context("usage: demo_host <bench-scans|bench|demo> ...")?;
    let opts = Opts::parse(rest)?;
    match cmd.as_str() {
        "bench-scans" => bench_scans(&opts),
        "bench" => bench(&opts),
        "demo" => demo(&opts),
        other => bail!("unknown subcommand `{other}`"),
    }
}

/// `--key value` options.
struct Opts(BTreeMap<String, String>);

impl Opts {
    fn parse(args: &[String]) -> Result<Self> {
        let mut m = BTreeMap::new();
        let mut it = args.iter();
        while let Some(k) = it.next() {
            let key = k
                .strip_prefix("--")
                .with_context(|| format!("unexpected `{k}`"))?;
            let v = it.next().with_context(|| format!("`{k}` needs a value"))?;
            m.insert(key.to_string(), v.clone());
        }
        Ok(Self(m))
    }
    fn get(&self, k: &str) -> Option<&str> {
        self.0.get(k).map(String::as_str)
    }
    fn path(&self, k: &str) -> Result<PathBuf> {
        self.get(k)
            .map(PathBuf::from)
            .with_context(|| format!("--{k} is required"))
    }
    fn num(&self, k: &str, default: u64) -> Result<u64> {
        self.get(k)
            .map(|v| {
                v.parse()
                    .with_context(|| format!("--{k} {v}: not a number"))
            })
            .unwrap_or(Ok(default))
    }
}

/// Simulated scans (mixed scenes, σ_r 5 mm, 0.5°), seeds `seed..seed+n`.
fn sim_scans(n: u64, seed: u64) -> Vec<host_tests::scene::SimScan> {
    (seed..seed + n)
        .map(|s| Scenario::new(SceneKind::Mixed, s).simulate())
        .collect()
}

fn bench_scans(o: &Opts) -> Result<()> {
    let n = o.num("scans", 100)?;
    let out = o.path("out")?;
    let mut bytes = Vec::new();
    for s in sim_scans(n, o.num("seed", 1000)?) {
        bytes.extend(qemu::b0_telegram(&s.raw, true)?);
    }
    if let Some(dir) = out.parent() {
        std::fs::create_dir_all(dir)?;
    }
    std::fs::write(&out, &bytes).with_context(|| format!("writing {}", out.display()))?;
    eprintln!(
        "{n} B0 telegrams, {} bytes -> {}",
        bytes.len(),
        out.display()
    );
    Ok(())
}

/// Per-stage instruction counts of one bench run.
struct BenchRun {
    /// stage → (instructions, points) per scan.
    stages: BTreeMap<&'static str, Vec<(f64, f64)>>,
    stack: Option<(u32, u32)>,
    scans: u32,
}

const STAGES: [(&str, &str); 4] = [
    ("decode", "decode one B0 telegram (CRC, values)"),
    ("paper", "pfe-core `Config::paper()`"),
    ("default", "pfe-core `Config::default()`"),
    (
        "pipeline",
        "whole pipeline: telegram bytes → features → encoded frame",
    ),
];

fn run_bench(elf: &Path) -> Result<BenchRun> {
    let (l, port) = qemu::listener()?;
    let cmd = qemu::qemu_command(elf, "null", &format!("tcp:127.0.0.1:{port}"), &[], true);
    let run = qemu::run_collect(cmd, l, Duration::from_secs(600))?;
    if run.code != Some(0) {
        bail!(
            "{} exited with {:?} (101 panic, 102 hard fault, 2 no scans built in)\n{}",
            elf.display(),
            run.code,
            run.stderr
        );
    }
    let (frames, errors) = qemu::decode_frames(&run.output);
    if !errors.is_empty() {
        bail!(
            "{} bad frames from the bench firmware: {errors:?}",
            errors.len()
        );
    }
    let mut r = BenchRun {
        stages: BTreeMap::new(),
        stack: None,
        scans: 0,
    };
    for f in frames {
        match f.header {
            Header::Report(Report::Timing {
                stage,
                ticks,
                points,
                ..
            }) => {
                let name = match stage {
                    Stage::Decode => "decode",
                    Stage::ExtractPaper => "paper",
                    Stage::ExtractDefault => "default",
                    Stage::Pipeline => "pipeline",
                };
                // SysTick 25 MHz, 1024 ns per instruction under -icount shift=10.
                let instr = f64::from(ticks) * 10.0 / 256.0;
                r.stages
                    .entry(name)
                    .or_default()
                    .push((instr, f64::from(points)));
            }
            Header::Report(Report::Stack { used, size }) => r.stack = Some((used, size)),
            Header::Report(Report::Done { scans }) => r.scans = scans,
            _ => {}
        }
    }
    if r.scans == 0 {
        bail!("the bench firmware measured no scan");
    }
    Ok(r)
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        return f64::NAN;
    }
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// (median, max) per scan and (median, max) per point.
fn summary(samples: &[(f64, f64)]) -> (f64, f64, f64, f64) {
    let mut per_scan: Vec<f64> = samples.iter().map(|s| s.0).collect();
    let mut per_point: Vec<f64> = samples.iter().map(|s| s.0 / s.1.max(1.0)).collect();
    let max_s = per_scan.iter().copied().fold(0.0, f64::max);
    let max_p = per_point.iter().copied().fold(0.0, f64::max);
    (median(&mut per_scan), max_s, median(&mut per_point), max_p)
}

/// Budget: whole pipeline ≤ 200 instructions per point (median).
const BUDGET_PER_POINT: f64 = 200.0;

fn bench(o: &Opts) -> Result<()> {
    let libm = run_bench(&o.path("elf")?)?;
    let mm = match o.get("elf-micromath") {
        Some(p) => Some(run_bench(Path::new(p))?),
        None => None,
    };
    let mut md = String::new();
    md.push_str(&format!(
        "Instruction counts on QEMU `mps2-an386` (Cortex-M4F model) with `-icount shift=10`, \
         measured with SysTick (instructions = ticks × 10 / 256), over {} simulated scans \
         (mixed scenes, 361 beams, σ_r = 5 mm). **These are instruction counts, not Cortex-M4 \
         cycles** (no pipeline, wait-state or FPU latency model).\n\n",
        libm.scans
    ));
    md.push_str("| stage (libm) | median instr/scan | max instr/scan | median instr/point | max instr/point |\n|---|---:|---:|---:|---:|\n");
    let mut pipe_median = f64::NAN;
    for (key, label) in STAGES {
        if let Some(s) = libm.stages.get(key) {
            let (ms, xs, mp, xp) = summary(s);
            if key == "pipeline" {
                pipe_median = mp;
            }
            md.push_str(&format!(
                "| {label} | {ms:.0} | {xs:.0} | {mp:.1} | {xp:.1} |\n"
            ));
        }
    }
    if let Some(mm) = &mm {
        md.push_str("\n`libm` vs `micromath` (pfe-core feature), medians:\n\n| stage | libm instr/scan | micromath instr/scan | micromath / libm | libm instr/point | micromath instr/point |\n|---|---:|---:|---:|---:|---:|\n");
        for (key, label) in STAGES.iter().skip(1) {
            if let (Some(a), Some(b)) = (libm.stages.get(key), mm.stages.get(key)) {
                let (sa, sb) = (summary(a), summary(b));
                md.push_str(&format!(
                    "| {label} | {:.0} | {:.0} | {:.2} | {:.1} | {:.1} |\n",
                    sa.0,
                    sb.0,
                    sb.0 / sa.0,
                    sa.2,
                    sb.2
                ));
            }
        }
    }
    if let Some((used, size)) = libm.stack {
        md.push_str(&format!(
            "\nStack high-water mark of the bench firmware: {used} bytes (of {size}).\n"
        ));
    }
    md.push_str(&format!(
        "\nBudget: whole pipeline ≤ {BUDGET_PER_POINT:.0} instructions per point (median): \
         **{}** ({pipe_median:.1}).\n",
        if pipe_median <= BUDGET_PER_POINT {
            "met"
        } else {
            "BROKEN"
        }
    ));
    println!("{md}");
    if let Some(path) = o.get("md") {
        host_tests::docs::write_section(
            Path::new(path),
            "bench-mcu",
            "`cargo xtask bench-mcu`",
            &format!("Reproduce: `cargo xtask bench-mcu`\n\n{md}"),
        )?;
    }
    if pipe_median.is_nan() || pipe_median > BUDGET_PER_POINT {
        bail!("pipeline median {pipe_median:.1} instructions/point > budget {BUDGET_PER_POINT}");
    }
    Ok(())
}

fn demo(o: &Opts) -> Result<()> {
    use firmware::app::ConfigChoice;
    use host_tests::methods::Extraction;
    let elf = o.path("elf")?;
    let scans = u32::try_from(o.num("scans", 10)?).context("--scans too large")?;
    let config = o.get("config").unwrap_or("default");
    let choice = match config {
        "default" => ConfigChoice::Default,
        "paper" => ConfigChoice::Paper,
        other => bail!("--config {other}: paper or default"),
    };
    let seed = o.num("seed", 1)?;
    let timeout = Duration::from_secs(o.num("timeout", 300)?);
    eprintln!("running {} under QEMU mps2-an386 against the emulated LMS200 ({scans} simulated scans, config {config})", elf.display());
    let s = qemu::session(&elf, scans, config, seed, timeout)?;
    if let Some(path) = o.get("defmt-log") {
        std::fs::write(path, &s.run.stdout)?;
    }
    let mut total = host_tests::eval::score::Score::default();
    let (mut equal, mut compared, mut worst_ulps) = (0usize, 0usize, 0u32);
    let mut stack = None;
    let mut done = None;
    println!("scan  valid  segs  features  lines  circles  telegrams  crc-dropped  skipped  reinits  host-equal");
    for f in &s.frames {
        match f.header {
            Header::Scan(h) => {
                let k = h.seq as usize;
                let lines = f.features.iter().filter(|w| w.is_line()).count();
                let sent = s.emulator.scans.get(k);
                let host = match sent {
                    Some(sc) if !sc.damaged => Some(qemu::host_features(&sc.words, choice)?),
                    _ => None,
                };
                let same = match &host {
                    Some(hf) => {
                        compared += 1;
                        let mut ok = hf.len() == f.features.len();
                        for (a, b) in hf.iter().zip(f.features.iter()) {
                            if let Some(u) = qemu::ulps_apart(a, b) {
                                worst_ulps = worst_ulps.max(u);
                                ok = false;
                            }
                        }
                        equal += usize::from(ok);
                        if ok {
                            "yes"
                        } else {
                            "NO"
                        }
                    }
                    None => "n/a",
                };
                println!(
                    "{:4}  {:5}  {:4}  {:8}  {:5}  {:7}  {:9}  {:11}  {:7}  {:7}  {same}",
                    h.seq,
                    h.valid,
                    h.segments,
                    h.n_features,
                    lines,
                    f.features.len() - lines,
                    h.counters.telegrams_ok,
                    h.counters.crc_dropped,
                    h.counters.bytes_skipped,
                    h.counters.reinits
                );
                if let Some(sim) = s.sims.get(k % s.sims.len().max(1)) {
                    let ex = Extraction {
                        marks: Vec::new(),
                        features: f.features.iter().map(|w| w.to_feature()).collect(),
                    };
                    total.add(&host_tests::eval::score::score_sim(&ex, sim));
                    if k == 0 {
                        if let Some(path) = o.get("svg") {
                            let rec = host_tests::formats::Record {
                                id: 0,
                                geometry: sim.geometry,
                                ranges_mm: sim.ranges_mm.clone(),
                            };
                            let title = format!(
                                "pfe-qemu scan 0 ({config}): {} features from the firmware",
                                f.features.len()
                            );
                            std::fs::write(path, host_tests::plot::svg(&rec, &ex, &title))?;
                            eprintln!("SVG of scan 0 -> {path}");
                        }
                    }
                }
            }
            Header::Report(Report::Stack { used, size }) => stack = Some((used, size)),
            Header::Report(Report::Done { scans }) => done = Some(scans),
            Header::Report(_) => {}
        }
    }
    let n_scans = s.frames.iter().filter(|f| f.scan().is_some()).count();
    println!(
        "firmware exit code {:?}; {n_scans} scan frames, {} rejected frames; emulator sent {} B0 telegrams",
        s.run.code,
        s.bad_frames.len(),
        s.emulator.scans.len()
    );
    if let Some((used, size)) = stack {
        println!("stack high-water mark: {used} of {size} bytes");
    }
    println!(
        "firmware vs host pfe-core on the same B0 values: {equal}/{compared} scans bit-identical{}",
        if worst_ulps > 0 {
            format!(" (worst difference {worst_ulps} ulp)")
        } else {
            String::new()
        }
    );
    println!(
        "vs ground truth ({} scans): {} truth features, {} matched, {} missed, {} spurious, {} lines seen as circles, {} circles seen as lines",
        total.scans, total.truth_features, total.matched, total.missed, total.spurious,
        total.lines_as_circles, total.circles_as_lines
    );
    if let Some(path) = o.get("summary") {
        let (used, size) = stack.unwrap_or((0, 0));
        std::fs::write(
            path,
            format!("exit={:?}\nscans={n_scans}\nequal={equal}\ncompared={compared}\nworst_ulps={worst_ulps}\nstack_used={used}\nstack_size={size}\n", s.run.code),
        )?;
    }
    if s.run.code != Some(0) || done != Some(scans) || n_scans != scans as usize {
        bail!(
            "the firmware did not finish cleanly (exit {:?}: 3 scanner link, 4 output, 101 panic, 102 fault; done {done:?})\n{}",
            s.run.code,
            s.run.stderr
        );
    }
    identical(equal, compared, worst_ulps)
}

/// The demo's claim, "N/N scans bit-identical" (firmware under QEMU against host pfe-core on
/// the same B0 values), enforced: at least one scan compared and every compared scan equal.
fn identical(equal: usize, compared: usize, worst_ulps: u32) -> Result<()> {
    if compared == 0 {
        bail!("no scan was compared with host pfe-core (every telegram damaged?)");
    }
    if equal != compared {
        bail!(
            "firmware and host pfe-core differ: {equal}/{compared} scans bit-identical (worst difference {worst_ulps} ulp)"
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_demo_fails_unless_every_compared_scan_is_identical() {
        assert!(super::identical(10, 10, 0).is_ok());
        assert!(super::identical(9, 10, 3).is_err());
        assert!(super::identical(0, 0, 0).is_err());
    }
}
