//! The C API from C: `tests/c/pfe_test.c`, compiled with the host's C compiler (`$CC`, else
//! `cc`) against the static library cargo built for this test run, checks every error path
//! and extracts the eval's scans (`pfe eval`: the main comparison, the scene kinds, the noise
//! sweep and the robustness conditions, simulated by host-tests) with the paper's and the
//! default configuration, from mm and from raw codes. Its output must equal pfe-core's, float
//! for float, bit for bit; and pfe-core's must be the eval's own (its `Pfe` method). The
//! same for the first scans of each real CARMEN log in `../shared/data`. Skipped loudly
//! (host-tests' skip list) without a C compiler or the data.

// Test helpers: a failure to run a tool or read a file fails the test.
#![allow(clippy::expect_used, clippy::panic, clippy::indexing_slicing)]

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use pfe_core::{Config, ExtractError, Extractor, Feature, Scan};
use pfe_eval as eval;
use pfe_eval::methods::{Method, Pfe};
use pfe_eval::scene::{Scenario, SceneKind, SimScan};
use pfe_formats::{self as formats, carmen, Format};
use pfe_testkit::skip::{skip, Need};

const N: usize = pfe_capi::PFE_MAX_READINGS;
const M: usize = pfe_capi::PFE_MAX_FEATURES;

/// The crate's directory.
fn here() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// `libpfe_capi.a` of this build. Cargo builds it beside the test binary (in `deps/`, named
/// with the hash of this build's features) without copying it up: the newest one that is not
/// newer than the test binary is the one compiled with the rlib this test links.
fn static_lib() -> PathBuf {
    let exe = std::env::current_exe().expect("test binary path");
    let built = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    let exe_time = built(&exe).expect("test binary time");
    let deps = exe.parent().expect("target/<profile>/deps");
    std::fs::read_dir(deps)
        .expect("read deps/")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("libpfe_capi-") && n.ends_with(".a"))
        })
        .filter_map(|p| built(&p).filter(|t| *t <= exe_time).map(|t| (t, p)))
        .max()
        .map(|(_, p)| p)
        .expect("libpfe_capi-*.a in deps/ (cargo builds the staticlib with the test)")
}

/// The C compiler: `$CC` or `cc`, when it runs.
fn c_compiler() -> Option<String> {
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".to_string());
    Command::new(&cc)
        .arg("--version")
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|_| cc)
}

/// Compiles `tests/c/pfe_test.c` into the test's temporary directory (a program per test:
/// they run in parallel); `None` (skipped loudly) without a C compiler.
fn build_c_test(test: &str) -> Option<PathBuf> {
    let Some(cc) = c_compiler() else {
        skip(test, "no C compiler (cc or $CC)", Need::InCi);
        return None;
    };
    let lib = static_lib();
    let name = test.rsplit(' ').next().unwrap_or("pfe_test");
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("pfe_test-{name}"));
    let status = Command::new(&cc)
        .args(["-std=c11", "-Wall", "-Wextra", "-Werror", "-O1", "-o"])
        .arg(&out)
        .arg(here().join("tests/c/pfe_test.c"))
        .arg("-I")
        .arg(here().join("include"))
        .arg(&lib)
        // What Rust's std needs from the C runtime on Linux (rustc --print native-static-libs).
        .args([
            "-lgcc_s",
            "-lutil",
            "-lrt",
            "-lpthread",
            "-lm",
            "-ldl",
            "-lc",
        ])
        .status()
        .expect("run the C compiler");
    assert!(status.success(), "compiling tests/c/pfe_test.c failed");
    Some(out)
}

#[test]
fn every_error_is_a_return_code_from_c() {
    let Some(exe) = build_c_test("pfe-capi c_api every_error_is_a_return_code_from_c") else {
        return;
    };
    let out = Command::new(&exe)
        .arg("errors")
        .output()
        .expect("run pfe_test");
    let stdout = String::from_utf8_lossy(&out.stdout);
    eprint!("{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "pfe_test errors: {stdout}");
    assert!(stdout.contains(", 0 failed"), "{stdout}");
}

/// The eval's scans (`pfe eval`'s defaults: seed 1, 100 scans, σ_r 5 mm, sweep 1, 2, 5,
/// 10 mm), each with its σ_r: the main level, each scene kind (50 scans), the sweep's other
/// levels and every robustness condition.
fn eval_scans() -> Vec<(f32, SimScan)> {
    let o = eval::EvalOptions::default();
    let mut levels: Vec<(f32, Vec<Scenario>)> =
        vec![(o.sigma, eval::scenarios(o.kind, o.scans, o.sigma, o.seed))];
    for k in SceneKind::CONCRETE {
        let n = (o.scans / 2).max(1);
        levels.push((o.sigma, eval::scenarios(k, n, o.sigma, o.seed)));
    }
    for &s in o.sweep.iter().filter(|&&s| s != o.sigma) {
        levels.push((s, eval::scenarios(o.kind, o.scans, s, o.seed)));
    }
    for (_, change) in eval::conditions() {
        let mut sc = eval::scenarios(o.kind, o.scans, o.sigma, o.seed);
        sc.iter_mut().for_each(change);
        levels.push((o.sigma, sc));
    }
    levels
        .into_iter()
        .flat_map(|(s, sc)| sc.iter().map(|c| (s, c.simulate())).collect::<Vec<_>>())
        .collect()
}

/// One scan for `pfe_test extract`, with what pfe is told about it.
struct TestScan {
    geometry: pfe_core::ScanGeometry,
    ranges_mm: Vec<f32>,
    /// The same as raw codes of `unit` mm.
    raw: Vec<u16>,
    unit: f32,
    /// The readings' grid, mm (0: unknown).
    quantum: f32,
    sweeps: u8,
    odometry: Option<pfe_core::Motion>,
    /// The configurations' σ_r and σ_sys, mm.
    sigma_r: f32,
    sigma_sys: f32,
}

impl TestScan {
    /// A simulated scan as the eval gives it to pfe (`SimScan::context`), σ_r `sigma_r`.
    fn simulated(sigma_r: f32, sim: &SimScan) -> Self {
        Self {
            geometry: sim.geometry,
            ranges_mm: sim.ranges_mm.clone(),
            raw: sim.raw.clone(),
            unit: sim.mm_per_unit,
            quantum: sim.mm_per_unit,
            sweeps: u8::try_from(sim.sweeps).expect("sweeps fit u8"),
            odometry: sim.odometry,
            sigma_r,
            sigma_sys: 0.0,
        }
    }

    /// The configurations the scan is extracted with: the paper's and the default.
    fn configs(&self) -> [(&'static str, Config); 2] {
        [Config::paper(), Config::default()].map(|c| {
            let name = if c.scrutiny { "default" } else { "paper" };
            (
                name,
                c.with_sigma_r(self.sigma_r).with_sigma_sys(self.sigma_sys),
            )
        })
    }

    /// `scan` with what pfe is told: odometry, sweeps.
    fn told<'a>(&self, mut scan: Scan<'a>) -> Scan<'a> {
        if let Some(m) = self.odometry {
            scan = scan.with_motion(m);
        }
        scan.with_sweeps(self.sweeps)
    }

    /// The scan from mm (with its quantum).
    fn mm(&self) -> Scan<'_> {
        self.told(Scan::from_mm(self.geometry, &self.ranges_mm))
            .with_quantum(self.quantum)
    }

    /// The scan from raw codes.
    fn lms(&self) -> Scan<'_> {
        self.told(Scan::from_lms(self.geometry, &self.raw, self.unit))
    }
}

/// The scans in `pfe_test extract`'s input format.
fn write_scans(scans: &[TestScan]) -> String {
    let mut s = String::new();
    for (id, t) in scans.iter().enumerate() {
        let g = t.geometry;
        let (has_motion, m) = match t.odometry {
            Some(m) => (1, m),
            None => (0, pfe_core::Motion::uniform(0.0, 0.0, 0.0)),
        };
        let b = f32::to_bits;
        writeln!(
            s,
            "S {id} {:x} {:x} {} {:x} {:x} {:x} {:x} {:x} {has_motion} {:x} {:x} {:x} {:x} {} {}",
            b(t.sigma_r),
            b(t.sigma_sys),
            t.sweeps,
            b(t.quantum),
            b(t.unit),
            b(g.start_angle),
            b(g.angle_step),
            b(g.r_max),
            b(m.v),
            b(m.omega),
            b(m.timing.beam_dt),
            b(m.timing.sweep_dt),
            m.timing.sweeps,
            t.ranges_mm.len(),
        )
        .ok();
        write!(s, "R {}", t.ranges_mm.len()).ok();
        for r in &t.ranges_mm {
            write!(s, " {:x}", r.to_bits()).ok();
        }
        write!(s, "\nC {}", t.raw.len()).ok();
        for c in &t.raw {
            write!(s, " {c}").ok();
        }
        s.push('\n');
    }
    s
}

/// pfe_test's status code of an extraction.
fn code(r: Result<pfe_core::Stats, ExtractError>) -> i32 {
    match r {
        Ok(_) => 0,
        Err(ExtractError::TooManyReadings { .. }) => -6,
        Err(ExtractError::InvalidGeometry) => -7,
        Err(ExtractError::InvalidConfig) => -8,
        Err(ExtractError::FeatureCapacity { .. }) => -9,
        Err(_) => -11,
    }
}

/// What pfe_test prints for one extraction, from pfe-core.
fn print_result(
    out: &mut String,
    ex: &Extractor<N, M>,
    r: Result<pfe_core::Stats, ExtractError>,
    cfg: &str,
    path: &str,
    id: usize,
) {
    let st = ex.stats();
    let f = ex.features();
    writeln!(out, "X {id} {cfg} {path} {} {}", code(r), f.len()).ok();
    writeln!(
        out,
        "T {} {} {} {} {} {} {} {} {} {}",
        st.readings,
        st.valid,
        st.segments,
        st.short_segments,
        st.degenerate,
        st.features,
        st.dropped,
        st.predictions,
        st.sweeps_aligned,
        st.scan_sigma_um
    )
    .ok();
    for feature in f {
        let (tag, first, last, points, values): (_, _, _, _, Vec<f32>) = match feature {
            Feature::Line(l) => ("L", l.first, l.last, l.points, l.values().to_vec()),
            Feature::Circle(c) => ("C", c.first, c.last, c.points, c.values().to_vec()),
            Feature::Object(o) => ("O", o.first, o.last, o.points, {
                let [x, y, a, b, c, d, w] = o.values();
                vec![x, y, a, b, c, d, w]
            }),
            _ => continue,
        };
        write!(out, "{tag} {first} {last} {points}").ok();
        for v in values {
            write!(out, " {:08x}", v.to_bits()).ok();
        }
        out.push('\n');
    }
    out.push('M');
    for m in ex.marks() {
        write!(out, " {m}").ok();
    }
    out.push('\n');
}

/// Runs `pfe_test extract` on `scans` and compares its output with `expected`, line by line.
fn c_output_equals(test: &str, name: &str, scans: &[TestScan], expected: &str) -> bool {
    let Some(exe) = build_c_test(test) else {
        return false;
    };
    let input = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("{name}.txt"));
    std::fs::write(&input, write_scans(scans)).expect("write the scans");
    let out = Command::new(&exe)
        .arg("extract")
        .arg(&input)
        .output()
        .expect("run pfe_test");
    eprint!("{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "pfe_test extract failed");
    let got = String::from_utf8(out.stdout).expect("UTF-8 output");
    if let Some((i, (a, b))) = got
        .lines()
        .zip(expected.lines())
        .enumerate()
        .find(|(_, (a, b))| a != b)
    {
        panic!("line {}: C printed\n  {a}\nRust:\n  {b}", i + 1);
    }
    assert_eq!(got.lines().count(), expected.lines().count());
    true
}

/// What `pfe_test extract` must print for `scans`, from pfe-core: the paper's and the default
/// configuration, from mm and from raw codes. Calls `check` after each extraction from mm.
fn expected_output(
    scans: &[TestScan],
    mut check: impl FnMut(
        usize,
        &TestScan,
        &str,
        &Config,
        &Extractor<N, M>,
        &Result<pfe_core::Stats, ExtractError>,
    ),
) -> String {
    let mut ex = Box::new(Extractor::<N, M>::new());
    let mut expected = String::new();
    for (id, t) in scans.iter().enumerate() {
        for (cfg, config) in t.configs() {
            let r = ex.extract(&t.mm(), &config);
            check(id, t, cfg, &config, &ex, &r);
            print_result(&mut expected, &ex, r, cfg, "mm", id);
            let r = ex.extract(&t.lms(), &config);
            print_result(&mut expected, &ex, r, cfg, "lms", id);
        }
    }
    expected
}

#[test]
fn c_extracts_the_eval_scans_bit_for_bit_as_rust() {
    let test = "pfe-capi c_api c_extracts_the_eval_scans_bit_for_bit_as_rust";
    let sims = eval_scans();
    let scans: Vec<TestScan> = sims
        .iter()
        .map(|(sigma, sim)| TestScan::simulated(*sigma, sim))
        .collect();
    // pfe-core's output, the way the C test asks for it; and the eval's own (its `Pfe`
    // method, with its larger capacities) must be the same.
    let mut features = 0;
    let mut circles = 0;
    let mut overflows = 0;
    let expected = expected_output(&scans, |id, _, cfg, config, ex, r| {
        let (_, sim) = &sims[id];
        let mut method = Pfe::new(cfg, *config);
        let eval = method.extract_in(&sim.geometry, &sim.ranges_mm, &sim.context());
        assert!(method.last_result().is_ok(), "scan {id} {cfg}");
        match r {
            Ok(_) => assert_eq!(eval.features, ex.features(), "scan {id} {cfg}"),
            // More than M features (the paper's method on mixed pixels): the first M are the
            // eval's first M, and the rest are counted.
            Err(ExtractError::FeatureCapacity { dropped }) => {
                assert_eq!(
                    eval.features.get(..M),
                    Some(ex.features()),
                    "scan {id} {cfg}"
                );
                assert_eq!(eval.features.len(), M + dropped, "scan {id} {cfg}");
                overflows += 1;
            }
            Err(e) => panic!("scan {id} {cfg}: {e:?}"),
        }
        assert_eq!(
            eval.marks,
            ex.marks().collect::<Vec<_>>(),
            "scan {id} {cfg}"
        );
        features += ex.features().len();
        circles += ex.features().iter().filter(|f| !f.is_line()).count();
    });
    // The scans exercise the library: many features, circles among them, every kind of scan.
    assert!(scans.len() >= 1000, "{} scans", scans.len());
    assert!(
        features > 20 * scans.len() && circles > scans.len(),
        "{features} {circles}"
    );
    assert!(scans.iter().any(|s| s.odometry.is_some()));
    assert!(scans
        .iter()
        .any(|s| s.sweeps == 4 && s.ranges_mm.len() == 721));
    assert!(scans.iter().any(|s| s.unit == 10.0));
    assert!(overflows > 0, "no scan fills the feature buffer");
    if c_output_equals(test, "eval_scans", &scans, &expected) {
        eprintln!(
            "C API bit-identical to pfe-core on {} eval scans × 2 configurations × 2 inputs \
             ({features} features of which {circles} circles from mm; {overflows} extractions \
             over PFE_MAX_FEATURES; {} output lines)",
            scans.len(),
            expected.lines().count()
        );
    }
}

/// Scans read from the real CARMEN logs in `../shared/data` (the first `per_log` of each), as
/// `pfe extract --format carmen` gives them to pfe: its σ_r and σ_sys for the format, the
/// sweeps and the readings' grid; raw codes are the ranges rounded to mm. `None` (skipped
/// loudly) without the data.
fn real_scans(test: &str, per_log: usize) -> Option<Vec<TestScan>> {
    let dir = here().join("../../../shared/data/carmen");
    if !dir.is_dir() {
        skip(
            test,
            &format!("real data folder {} is absent", dir.display()),
            Need::InCi,
        );
        return None;
    }
    let mut logs: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("read the data folder")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| carmen::is_log_name(&p.to_string_lossy()))
        .collect();
    logs.sort();
    let mut scans = Vec::new();
    for log in &logs {
        let input = formats::open_for(log, Format::Carmen, |r| r).expect("open the log");
        for record in carmen::Reader::new(input).take(per_log) {
            let r = record.expect("a scan");
            let g = r.geometry;
            let raw = r
                .ranges_mm
                .iter()
                .map(|&v| match (0.5..8182.5).contains(&v) {
                    true => v.round() as u16,
                    false => 0,
                })
                .collect();
            scans.push(TestScan {
                geometry: g,
                quantum: formats::range_quantum(&r.ranges_mm, g.r_max),
                sweeps: r
                    .sweeps
                    .unwrap_or_else(|| formats::sweeps_of(Format::Carmen, &g)),
                ranges_mm: r.ranges_mm,
                raw,
                unit: 1.0,
                odometry: None,
                sigma_r: Format::Carmen.sigma_r(),
                sigma_sys: Format::Carmen.sigma_sys(),
            });
        }
    }
    assert!(
        logs.len() >= 10 && scans.len() >= 10 * per_log,
        "{} logs",
        logs.len()
    );
    Some(scans)
}

#[test]
fn c_extracts_real_scans_bit_for_bit_as_rust() {
    let test = "pfe-capi c_api c_extracts_real_scans_bit_for_bit_as_rust";
    let Some(scans) = real_scans(test, 40) else {
        return;
    };
    let mut features = 0;
    let expected = expected_output(&scans, |id, _, cfg, _, ex, r| {
        assert!(
            matches!(r, Ok(_) | Err(ExtractError::FeatureCapacity { .. })),
            "scan {id} {cfg}: {r:?}"
        );
        features += ex.features().len();
    });
    assert!(features > 10 * scans.len(), "{features} features");
    if c_output_equals(test, "real_scans", &scans, &expected) {
        eprintln!(
            "C API bit-identical to pfe-core on {} real CARMEN scans × 2 configurations × 2 \
             inputs ({features} features from mm)",
            scans.len()
        );
    }
}

#[test]
fn the_c_example_finds_the_wall_and_the_pillar() {
    let test = "pfe-capi c_api the_c_example_finds_the_wall_and_the_pillar";
    let Some(cc) = c_compiler() else {
        skip(test, "no C compiler (cc or $CC)", Need::InCi);
        return;
    };
    let exe = Path::new(env!("CARGO_TARGET_TMPDIR")).join("static_extractor");
    let status = Command::new(&cc)
        .args(["-std=c11", "-Wall", "-Wextra", "-Werror", "-o"])
        .arg(&exe)
        .arg(here().join("examples/static_extractor.c"))
        .arg("-I")
        .arg(here().join("include"))
        .arg(static_lib())
        .args(["-lm", "-lpthread", "-ldl"])
        .status()
        .expect("run the C compiler");
    assert!(
        status.success(),
        "compiling examples/static_extractor.c failed"
    );
    let out = Command::new(&exe).output().expect("run the example");
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    // The scene the example draws: the wall x = 2000 mm (α 0, ρ 2000) on both sides of a
    // pillar of radius 150 mm at (1200, 600).
    let numbers = |l: &str| -> Vec<f64> {
        l.split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-'))
            .filter_map(|w| w.parse().ok())
            .collect()
    };
    let lines: Vec<Vec<f64>> = text
        .lines()
        .filter(|l| l.starts_with("line"))
        .map(numbers)
        .collect();
    let circles: Vec<Vec<f64>> = text
        .lines()
        .filter(|l| l.starts_with("circle"))
        .map(numbers)
        .collect();
    assert_eq!((lines.len(), circles.len()), (2, 1), "{text}");
    for l in &lines {
        // beams first, last; alpha; rho; sd
        assert!(l[2].abs() < 1e-3 && (l[3] - 2000.0).abs() < 1.0, "{text}");
    }
    let c = &circles[0];
    assert!(
        (c[2] - 1200.0).abs() < 5.0 && (c[3] - 600.0).abs() < 5.0,
        "{text}"
    );
    assert!((c[4] - 150.0).abs() < 5.0, "{text}");
}
