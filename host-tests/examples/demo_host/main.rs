//! Host side of `cargo xtask demo`, `bench-mcu` and `size`: runs the pfe firmware under QEMU
//! (mps2-an386) and reads the feature frames it sends on UART1.
//!
//! ```text
//! demo_host bench-scans --scans 100 --out scans.bin      # B0 telegrams for pfe-bench: 3 sets of N
//! demo_host bench --elf pfe-bench --scans 100 [--elf-micromath pfe-bench-mm] [--md docs/PERFORMANCE.md]
//! demo_host worst-scans --out worst.bin --kinds worst.txt [--iterations 4000] [--seed 20]
//! demo_host worst --elf pfe-bench --kinds worst.txt [--md docs/PERFORMANCE.md]
//! demo_host demo --elf pfe-qemu [--scans 10] [--config default|paper|default-nopose|paper-nopose] [--svg demo.svg]
//! demo_host pose-scans --out pose.bin --kinds pose.txt [--scans 256] [--carmen LOG]
//! demo_host pose-bench --elf pfe-bench-pose --kinds pose.txt --static-ram B [--md docs/PERFORMANCE.md]
//! ```

use host_tests::qemu;

mod pose;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::{bail, Context, Result};
use pfe_eval::scene::{Scenario, SceneKind};
use pfe_frame::{Header, Report, Stage};

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (cmd, rest) = args.split_first().context(
        "usage: demo_host <bench-scans|bench|worst-scans|worst|demo|pose-scans|pose-bench> ...",
    )?;
    let opts = Opts::parse(rest)?;
    match cmd.as_str() {
        "bench-scans" => bench_scans(&opts),
        "bench" => bench(&opts),
        "worst-scans" => worst_scans(&opts),
        "worst" => worst(&opts),
        "demo" => demo(&opts),
        "pose-scans" => pose::pose_scans(&opts),
        "pose-bench" => pose::pose_bench(&opts),
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
    /// With `--md PATH`: writes `md` as section `name` of that document, reproduced by
    /// `command`.
    fn write_section(&self, name: &str, command: &str, md: &str) -> Result<()> {
        if let Some(path) = self.get("md") {
            pfe_formats::docs::write_section(
                Path::new(path),
                name,
                &format!("`{command}`"),
                &format!("Reproduce: `{command}`\n\n{md}"),
                false,
            )?;
        }
        Ok(())
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

/// The scan sets of `bench-scans` and `bench`, in order, `--scans` of each: (key, description).
const SETS: [(&str, &str); 3] = [
    (
        "still",
        "simulated scans at 0.5° (mixed scenes, 361 beams, σ_r = 5 mm), the scanner still: 2 sweeps declared, none out of place",
    ),
    (
        "moving",
        "the same scenes at 0.5° with the scanner moving at 600 mm/s and 0.45 rad/s: the odd sweep 8 mm / 6 mrad off the even one, aligned from the scan",
    ),
    (
        "quarter",
        "the same scenes, moving likewise, at 0.25° over 100° (401 beams, 4 interleaved sweeps)",
    ),
];

/// Scan `k` of set `set` (a key of [`SETS`]) as LMS200 codes in mm.
fn bench_scan(set: &str, seed: u64) -> Vec<u16> {
    use pfe_eval::scene::Resolution;
    let mut sc = Scenario::new(SceneKind::Mixed, seed);
    match set {
        "still" => sc.simulate().raw,
        "moving" => sc.with_motion(600.0, 0.45).simulate().raw,
        _ => {
            sc.resolution = Resolution::Quarter;
            // 180° at 0.25° from −90°: beams 160..=560 are the LMS200's 100° (from −50°), and
            // 160 is a multiple of 4, so every beam keeps its sweep.
            let raw = sc.with_motion(600.0, 0.45).simulate().raw;
            raw.get(160..561).map(<[u16]>::to_vec).unwrap_or_default()
        }
    }
}

fn bench_scans(o: &Opts) -> Result<()> {
    let n = o.num("scans", 100)?;
    let out = o.path("out")?;
    let seed = o.num("seed", 1000)?;
    let mut bytes = Vec::new();
    for (set, _) in SETS {
        for s in seed..seed + n {
            bytes.extend(qemu::b0_telegram(&bench_scan(set, s), true)?);
        }
    }
    if let Some(dir) = out.parent() {
        std::fs::create_dir_all(dir)?;
    }
    std::fs::write(&out, &bytes).with_context(|| format!("writing {}", out.display()))?;
    eprintln!(
        "{} sets of {n} B0 telegrams, {} bytes -> {}",
        SETS.len(),
        bytes.len(),
        out.display()
    );
    Ok(())
}

/// Per-stage instruction counts of one bench run.
struct BenchRun {
    /// stage → (scan, instructions, points) per scan.
    stages: BTreeMap<&'static str, Vec<(u32, f64, f64)>>,
    stack: Option<(u32, u32)>,
    scans: u32,
}

impl BenchRun {
    /// The samples of `stage` from scans `range`, as (instructions, points).
    fn of(&self, stage: &str, range: std::ops::Range<u32>) -> Vec<(f64, f64)> {
        self.stages
            .get(stage)
            .map(|v| {
                v.iter()
                    .filter(|s| range.contains(&s.0))
                    .map(|s| (s.1, s.2))
                    .collect()
            })
            .unwrap_or_default()
    }
}

/// The stages pfe-bench reports, in table order: (key, label, part of the default extraction's
/// steps).
const STAGES: [(&str, &str, bool); 14] = [
    ("decode", "decode one B0 telegram (CRC, values)", false),
    (
        "scan",
        "pfe-core scan from the codes (`RawScan::to_pfe`: sweeps, grid)",
        false,
    ),
    ("load", "· readings to points", true),
    ("scatter", "· the scan's own σ", true),
    ("mark", "· mark points (the walk)", true),
    (
        "sweeps",
        "· sweep alignment (estimate, move, mark again)",
        true,
    ),
    ("check", "· check step", true),
    ("segments", "· segments, typing, fits", true),
    ("reach", "· line ends reach", true),
    ("sift", "· sift: no unseeable lines, small objects", true),
    ("encode", "encode the output frame", false),
    (
        "default",
        "pfe-core `ConfigChoice::Default` (everything on), whole",
        false,
    ),
    ("paper", "pfe-core `ConfigChoice::Paper`", false),
    (
        "pipeline",
        "**whole pipeline**: telegram bytes → features → encoded frame",
        false,
    ),
];

fn run_bench(elf: &Path) -> Result<BenchRun> {
    let (l, port) = qemu::listener()?;
    let cmd = qemu::qemu_command(elf, "null", &format!("tcp:127.0.0.1:{port}"), &[], true);
    let run = qemu::run_collect(cmd, l, Duration::from_secs(1200))?;
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
                seq,
                stage,
                ticks,
                points,
            }) => {
                let name = match stage {
                    Stage::Decode => "decode",
                    Stage::ExtractPaper => "paper",
                    Stage::ExtractDefault => "default",
                    Stage::Pipeline => "pipeline",
                    Stage::Load => "load",
                    Stage::Scatter => "scatter",
                    Stage::Scan => "scan",
                    Stage::Mark => "mark",
                    Stage::Sweeps => "sweeps",
                    Stage::Check => "check",
                    Stage::Segments => "segments",
                    Stage::Reach => "reach",
                    Stage::Sift => "sift",
                    Stage::Encode => "encode",
                    Stage::Pose => "pose",
                    Stage::PipelinePose => "pipeline-pose",
                };
                // SysTick 25 MHz, 1024 ns per instruction under -icount shift=10.
                let instr = f64::from(ticks) * 10.0 / 256.0;
                r.stages
                    .entry(name)
                    .or_default()
                    .push((seq, instr, f64::from(points)));
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

/// Issue 42's target: the whole pipeline ≤ 200 instructions a point (median, in every set).
const BUDGET_PER_POINT: f64 = 200.0;
/// What CI holds while that target is not met: the medians measured with everything on
/// (docs/PERFORMANCE.md: at most 1007.4 a point, the 0.25° set) with 10 % of room, so that the
/// cost cannot grow unnoticed while the speed work goes on. Lower it as the code gets faster.
const CEILING_PER_POINT: f64 = 1110.0;

fn bench(o: &Opts) -> Result<()> {
    let libm = run_bench(&o.path("elf")?)?;
    let mm = match o.get("elf-micromath") {
        Some(p) => Some(run_bench(Path::new(p))?),
        None => None,
    };
    let per_set = u32::try_from(o.num("scans", 100)?)?;
    anyhow::ensure!(
        libm.scans == per_set * SETS.len() as u32,
        "the firmware measured {} scans, {} sets of {per_set} were built in",
        libm.scans,
        SETS.len()
    );
    let mut md = format!(
        "Instruction counts on QEMU `mps2-an386` (Cortex-M4F model) with `-icount shift=10`, \
         measured with SysTick (instructions = ticks × 10 / 256). **These are instruction \
         counts, not Cortex-M4 cycles** (no pipeline, wait-state or FPU latency model). The \
         firmware's extraction with everything on, as on the host (`pfe extract --format \
         lms200`: the checks for real scans, small objects, no unseeable lines, the interleaved \
         sweeps aligned); the rows marked · are its steps (pfe-core's stage observer, in the \
         bench firmware only: `Extractor::extract_observed`), whose sum is the whole extraction \
         but for the observer's own few instructions a step. {per_set} scans in each set.\n\n"
    );
    let mut broken = Vec::new();
    let mut over_ceiling = Vec::new();
    for (k, (set, what)) in SETS.iter().enumerate() {
        let range = k as u32 * per_set..(k as u32 + 1) * per_set;
        md.push_str(&format!("**{set}**: {what}.\n\n"));
        md.push_str("| stage (libm) | median instr/scan | max instr/scan | median instr/point | max instr/point |\n|---|---:|---:|---:|---:|\n");
        for (key, label, _) in STAGES {
            let samples = libm.of(key, range.clone());
            if samples.is_empty() {
                continue;
            }
            let (ms, xs, mp, xp) = summary(&samples);
            if key == "pipeline" && (mp.is_nan() || mp > BUDGET_PER_POINT) {
                broken.push(format!("{set}: pipeline median {mp:.1} instructions/point"));
            }
            if key == "pipeline" && (mp.is_nan() || mp > CEILING_PER_POINT) {
                over_ceiling.push(format!("{set}: pipeline median {mp:.1} instructions/point"));
            }
            md.push_str(&format!(
                "| {label} | {ms:.0} | {xs:.0} | {mp:.1} | {xp:.1} |\n"
            ));
        }
        md.push('\n');
    }
    if let Some(mm) = &mm {
        md.push_str("`libm` vs `micromath` (pfe-core feature), medians over every set:\n\n| stage | libm instr/scan | micromath instr/scan | micromath / libm | libm instr/point | micromath instr/point |\n|---|---:|---:|---:|---:|---:|\n");
        for key in ["paper", "default", "pipeline"] {
            let label = STAGES.iter().find(|s| s.0 == key).map_or(key, |s| s.1);
            let (a, b) = (libm.of(key, 0..u32::MAX), mm.of(key, 0..u32::MAX));
            if a.is_empty() || b.is_empty() {
                continue;
            }
            let (sa, sb) = (summary(&a), summary(&b));
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
    if let Some((used, size)) = libm.stack {
        md.push_str(&format!(
            "\nStack high-water mark of the bench firmware: {used} bytes (of {size}).\n"
        ));
    }
    md.push_str(&format!(
        "\nBudget (issue 42): whole pipeline ≤ {BUDGET_PER_POINT:.0} instructions per point \
         (median, in every set): **{}**{}. Until it is met, CI holds the cost measured with \
         everything on as a ceiling, ≤ {CEILING_PER_POINT:.0} instructions per point (median, \
         in every set): **{}**.\n",
        if broken.is_empty() { "met" } else { "NOT MET" },
        if broken.is_empty() {
            String::new()
        } else {
            format!(" ({})", broken.join("; "))
        },
        if over_ceiling.is_empty() {
            "held"
        } else {
            "EXCEEDED"
        },
    ));
    println!("{md}");
    o.write_section("bench-mcu", "cargo xtask bench-mcu", &md)?;
    if !broken.is_empty() {
        eprintln!(
            "NOT MET: issue 42's budget of {BUDGET_PER_POINT} instructions a point: {}",
            broken.join("; ")
        );
    }
    if !over_ceiling.is_empty() {
        bail!(
            "pipeline median over the ceiling {CEILING_PER_POINT}: {}",
            over_ceiling.join("; ")
        );
    }
    Ok(())
}

/// The adversarial scans (structured, then the search's best) as B0 telegrams in `--out`,
/// one kind a line in `--kinds`.
fn worst_scans(o: &Opts) -> Result<()> {
    use pfe_eval::scene::adversarial;
    let iterations = usize::try_from(o.num("iterations", 4000)?)?;
    let mut scans = adversarial::structured();
    scans.extend(adversarial::search(o.num("seed", 20)?, iterations, 4));
    let (mut bytes, mut kinds) = (Vec::new(), String::new());
    for s in &scans {
        bytes.extend(qemu::b0_telegram(&s.codes, s.mm)?);
        let st = s.stats();
        kinds.push_str(&format!("{}\t{}\n", s.kind, adversarial::work(&st)));
    }
    std::fs::write(o.path("out")?, &bytes)?;
    std::fs::write(o.path("kinds")?, kinds)?;
    eprintln!(
        "{} adversarial scans ({iterations} search iterations), {} bytes",
        scans.len(),
        bytes.len()
    );
    Ok(())
}

/// How [`bound`] follows from pfe-core's default mode (the generated section's second half).
const BOUND_DERIVATION: &str = "
**The bound.** pfe-core's default configuration: window W = 10 points, grown up to W_max = 24;
arc window A = 24; merge test at 8 points of a new segment; boundary refinement over 6 points
each side; Np = 3; 5 geometric refinement steps per circle; at most M = 48 features kept. The
work is counted in *point visits* (one point read into a running sum or test) and every loop
is bounded by these constants, so one scan of N points costs at most:

| where | visits per point | why |
|---|---:|---|
| prediction window growth | 24 | ≤ W_max distance tests |
| fresh window line | 24 | a fit over ≤ W_max points (at most one per point) |
| arc continuation | 49 | an arc fit over ≤ A points (two passes) and one prediction |
| boundary location | 29 | a line over ≤ W points, ≤ 4 predictions, ≤ 3 axis fits of ≤ 5 points |
| merge test at 8 points | 64 | an arc fit over ≤ A + 8 points, two passes (≤ one per boundary) |
| boundary refinement | 21 | two axis fits of ≤ 6 points, ≤ 5 candidates (≤ one per boundary) |
| check step | 3 | one prediction from Np points per run of marks |
| merge of neighbouring segments | 128 | an arc fit over ≤ 64 points, two passes, ≤ one per segment (≤ one per point) |
| typing and fitting | 10 | line fit, algebraic circle, normal equations, 5 refinements: ≤ 10 passes over the segment; segments partition the points |
| **total** | **352** | |

Each visit is costed at 30 instructions (two f32 loads, a few FPU operations, a compare and the
loop), every point at 200 more (the median pipeline's whole cost per point: decoding, loading,
flags, the fast path), every kept feature at 3 000 (its covariance and its frame): bound =
N · (352 · 30 + 200) + 48 · 3 000 instructions. The bound charges every point with every test at
once; no scan can trigger them all at the same point (a boundary point is not also refined and
merge-tested), so it is loose by design: it proves the cost is linear in N with a fixed
constant, and the measured maximum, not the bound, is held to the budget of 1 000 000
instructions per scan (under half the 26.7 ms scan period at the board's 96 MHz).

The bound counts one walk and none of the work the default mode added since: the checks for real
scans (the scan's own σ, joined short segments, corner splits, reach, the sift) and, for an
interleaved scan, the sweeps' offset estimate and the second walk after moving them. With
everything on it is a yardstick, not a proof; the measured maximum is what the budget holds.
";

/// Worst case per scan: whole pipeline ≤ this many instructions.
const WORST_BUDGET: f64 = 1_000_000.0;

/// The algorithmic bound on a scan of `n` values, in point visits and instructions (see
/// docs/PERFORMANCE.md, "Worst case per scan").
fn bound(n: usize) -> (usize, f64) {
    /// Point visits per point: walk 211, check step 3, merge of neighbours and fits 138.
    const VISITS_PER_POINT: usize = 24 + 24 + 49 + 29 + 64 + 21 + 3 + 128 + 10;
    /// Instructions per visit (two f32 loads, a few FPU operations, a compare, the loop).
    const PER_VISIT: f64 = 30.0;
    /// Per point outside the visits (decode, load, flags) and per feature (fit finish, frame).
    const PER_POINT: f64 = 200.0;
    const PER_FEATURE: f64 = 3000.0;
    let visits = n * VISITS_PER_POINT;
    let instr = visits as f64 * PER_VISIT
        + n as f64 * PER_POINT
        + firmware::app::LMS_FEATURES as f64 * PER_FEATURE;
    (visits, instr)
}

fn worst(o: &Opts) -> Result<()> {
    let kinds_text = std::fs::read_to_string(o.path("kinds")?)?;
    let kinds: Vec<(&str, &str)> = kinds_text
        .lines()
        .filter_map(|l| l.split_once('\t'))
        .collect();
    let run = run_bench(&o.path("elf")?)?;
    anyhow::ensure!(
        run.scans as usize == kinds.len(),
        "the firmware measured {} scans, {} were built in",
        run.scans,
        kinds.len()
    );
    // kind → (scans, values, max pipeline, max paper, max default, max host work)
    let mut rows: Vec<(&str, usize, usize, f64, f64, f64, usize)> = Vec::new();
    // kind → the scan of its max pipeline
    let mut costliest: Vec<(&str, usize, f64)> = Vec::new();
    let stage = |name: &str, i: usize| {
        run.stages
            .get(name)
            .and_then(|v| v.iter().find(|s| s.0 as usize == i))
            .map_or((0.0, 0.0), |s| (s.1, s.2))
    };
    for (i, (kind, work)) in kinds.iter().enumerate() {
        let (pipe, pts) = stage("pipeline", i);
        let (paper, default) = (stage("paper", i).0, stage("default", i).0);
        let work: usize = work.parse().unwrap_or(0);
        match costliest.iter_mut().find(|c| c.0 == *kind) {
            Some(c) if c.2 >= pipe => {}
            Some(c) => *c = (kind, i, pipe),
            None => costliest.push((kind, i, pipe)),
        }
        match rows.iter_mut().find(|r| r.0 == *kind) {
            Some(r) => {
                r.1 += 1;
                r.2 = r.2.max(pts as usize);
                r.3 = r.3.max(pipe);
                r.4 = r.4.max(paper);
                r.5 = r.5.max(default);
                r.6 = r.6.max(work);
            }
            None => rows.push((kind, 1, pts as usize, pipe, paper, default, work)),
        }
    }
    let mut md = String::from(
        "Worst case per scan: adversarial scans (`pfe_eval::scene::adversarial`: structured \
         kinds, and the best scans of a hill-climb on pfe-core's work counters) on QEMU \
         `mps2-an386`, `-icount shift=10` (instruction counts, not cycles). The bound is the \
         algorithmic one derived below for the scan's value count. pfe-bench extracts every \
         scan as the firmware does, with everything on: the variant from the value count \
         (the 361-value kinds at 0.5° in 2 sweeps, the 401-value ones at 0.25° in 4), the \
         unit from the telegram, the checks for real scans.\n\n\
         | scan kind | scans | values | host work (max) | paper max instr | default max instr | pipeline max instr/scan | bound instr/scan (visits) |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    let mut max = 0.0f64;
    for (kind, n, values, pipe, paper, default, work) in &rows {
        let (visits, b) = bound(*values);
        max = max.max(*pipe);
        md.push_str(&format!(
            "| {kind} | {n} | {values} | {work} | {paper:.0} | {default:.0} | {pipe:.0} | {b:.0} ({visits}) |\n"
        ));
    }
    md.push_str(
        "\nThe costliest scan of each kind, step by step (instructions; pfe-core's stage observer):\n\n\
         | scan kind | pipeline | decode | scan | load | own σ | mark | sweeps | check | segments | reach | sift | encode |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for (kind, i, pipe) in &costliest {
        md.push_str(&format!("| {kind} | {pipe:.0} |"));
        for key in [
            "decode", "scan", "load", "scatter", "mark", "sweeps", "check", "segments", "reach",
            "sift", "encode",
        ] {
            md.push_str(&format!(" {:.0} |", stage(key, *i).0));
        }
        md.push('\n');
    }
    md.push_str(&format!(
        "\nBudget: whole pipeline ≤ {WORST_BUDGET:.0} instructions per scan (worst case): \
         **{}** ({max:.0}).\n",
        if max <= WORST_BUDGET { "met" } else { "BROKEN" }
    ));
    md.push_str(BOUND_DERIVATION);
    println!("{md}");
    o.write_section("bench-mcu-worst", "cargo xtask bench-mcu --worst", &md)?;
    if max > WORST_BUDGET {
        bail!("worst-case pipeline {max:.0} instructions/scan > budget {WORST_BUDGET}");
    }
    Ok(())
}

fn demo(o: &Opts) -> Result<()> {
    use firmware::app::ConfigChoice;
    use pfe_eval::methods::Extraction;
    let elf = o.path("elf")?;
    let scans = u32::try_from(o.num("scans", 10)?).context("--scans too large")?;
    let config = o.get("config").unwrap_or("default");
    let choice = match config {
        "default" | "default-nopose" => ConfigChoice::Default,
        "paper" | "paper-nopose" => ConfigChoice::Paper,
        other => bail!("--config {other}: paper, default, paper-nopose or default-nopose"),
    };
    let seed = o.num("seed", 1)?;
    let timeout = Duration::from_secs(o.num("timeout", 300)?);
    eprintln!("running {} under QEMU mps2-an386 against the emulated LMS200 ({scans} simulated scans, config {config})", elf.display());
    let s = qemu::session(&elf, scans, config, seed, timeout)?;
    if let Some(path) = o.get("defmt-log") {
        std::fs::write(path, &s.run.stdout)?;
    }
    let mut total = pfe_eval::score::Score::default();
    let (mut equal, mut compared, mut worst_ulps) = (0usize, 0usize, 0u32);
    let mut stack = None;
    let mut done = None;
    let mut next = 0usize;
    println!("scan  valid  segs  features  lines  circles  telegrams  crc-dropped  skipped  reinits  host-equal");
    for f in &s.frames {
        match f.header {
            Header::Scan(h) => {
                let lines = f.features.iter().filter(|w| w.is_line()).count();
                // The telegram of this scan: the first intact one from `next` on whose host
                // features are the scan's (telegrams lost or cut by a re-initialisation are no
                // scans to the firmware, so sequence numbers and telegrams can part); when none
                // is, the scan is compared with telegram `next`.
                let same_as = |words: &[u16]| -> Result<(bool, u32)> {
                    let hf = qemu::host_features(words, choice)?;
                    let mut worst = 0;
                    let mut ok = hf.len() == f.features.len();
                    for (a, b) in hf.iter().zip(f.features.iter()) {
                        if let Some(u) = qemu::ulps_apart(a, b) {
                            worst = worst.max(u);
                            ok = false;
                        }
                    }
                    Ok((ok, worst))
                };
                let mut found = None;
                let mut first = None;
                for (j, sc) in s.emulator.scans.iter().enumerate().skip(next) {
                    if sc.damaged {
                        continue;
                    }
                    let r = same_as(&sc.words)?;
                    first.get_or_insert(r);
                    if r.0 {
                        found = Some(j);
                        break;
                    }
                }
                let k = found.unwrap_or(next);
                let same = match (found, first) {
                    (Some(j), _) => {
                        compared += 1;
                        equal += 1;
                        next = j + 1;
                        "yes"
                    }
                    (None, Some((_, u))) => {
                        compared += 1;
                        worst_ulps = worst_ulps.max(u);
                        "NO"
                    }
                    (None, None) => "n/a",
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
                        features: f.features.to_vec(),
                    };
                    total.add(&pfe_eval::score::score_sim(&ex, sim));
                    if h.seq == 0 {
                        if let Some(path) = o.get("svg") {
                            let rec = pfe_formats::Record {
                                id: 0,
                                geometry: sim.geometry,
                                ranges_mm: sim.ranges_mm.clone(),
                                time: None,
                                pose: None,
                                sweeps: None,
                            };
                            let title = format!(
                                "pfe-qemu scan 0 ({config}): {} features from the firmware",
                                f.features.len()
                            );
                            std::fs::write(path, pfe_cli::figure::svg(&rec, &ex, &title))?;
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
