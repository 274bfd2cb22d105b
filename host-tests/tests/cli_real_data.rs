//! The real logs in `../shared/data` (skipped, with a message, when the folder is absent):
//! `pfe extract` runs over every one of them, and the CARMEN angle convention is checked by the
//! residual of long straight walls.

use std::path::PathBuf;
use std::process::Command;

use host_tests::formats::carmen::{AngleConvention, Reader};
use host_tests::formats::{self, Record};
use host_tests::method::{Method, Pfe};
use pfe_core::{fit_line, Point};

fn data_dir() -> Option<PathBuf> {
    let d = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data");
    if d.join("carmen").is_dir() {
        Some(d)
    } else {
        eprintln!(
            "SKIPPED: real data folder {} is absent (it sits beside the repository as shared/data)",
            d.display()
        );
        None
    }
}

fn carmen_logs(d: &std::path::Path) -> Vec<PathBuf> {
    let mut logs: Vec<PathBuf> = std::fs::read_dir(d.join("carmen"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.to_string_lossy().ends_with(".log.gz"))
        .collect();
    logs.sort();
    logs
}

#[test]
fn extract_runs_over_every_real_log() {
    let Some(d) = data_dir() else { return };
    let mut inputs: Vec<(PathBuf, &str)> =
        carmen_logs(&d).into_iter().map(|p| (p, "carmen")).collect();
    inputs.push((d.join("hokuyo-cylinders/scans.txt.gz"), "hokuyo"));
    assert_eq!(inputs.len(), 11);
    for (path, format) in inputs {
        let out = Command::new(env!("CARGO_BIN_EXE_pfe"))
            .args(["extract", "--format", format])
            .arg(&path)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{}: {stderr}", path.display());
        let text = String::from_utf8(out.stdout).unwrap();
        let mut scans = 0;
        for line in text.lines() {
            let v: serde_json::Value = serde_json::from_str(line).unwrap();
            assert_eq!(v["scan"].as_u64(), Some(scans));
            scans += 1;
        }
        // The README's scan counts.
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let expected = match name.split('-').next().unwrap() {
            "acapulco" => 861,
            "aces" => 440,
            "csail" => 406,
            "edmonton" => 340,
            "fhw" => 488,
            "freiburg" if name.contains("079") => 4791,
            "freiburg" if name.contains("101") => 292,
            "freiburg" => 2008,
            "infinite" => 1941,
            "intel" => 910,
            "scans.txt.gz" => 661,
            other => panic!("unexpected log {other}"),
        };
        assert_eq!(scans, expected, "{name}");
        eprintln!("{name}: {}", stderr.trim());
    }
}

/// Sum of squared line-fit residuals (mm²) and point count of the beams `a..=b` of `r`
/// placed at bearings −90° + i·`step`.
fn sse(r: &Record, (a, b): (usize, usize), step: f32) -> (f64, usize) {
    let pts: Vec<Point> = (a..=b)
        .filter_map(|i| {
            let v = *r.ranges_mm.get(i)?;
            let t = -std::f32::consts::FRAC_PI_2 + step * i as f32;
            v.is_finite().then(|| Point::new(v * t.cos(), v * t.sin()))
        })
        .collect();
    (f64::from(fit_line(&pts).unwrap().sse()), pts.len())
}

/// Both conventions read the same ranges; on long straight walls the right angular step
/// leaves the smaller residual. Walls: line features of ≥ 20 beams that the extractor finds
/// under both conventions, each wall the beams common to both (so neither is favoured). For
/// a grid of steps around 180°/n the total residual is computed; its minimum should lie
/// at the step of the `Auto` convention. The result is recorded in the docs of
/// `formats::carmen`.
#[test]
fn carmen_angle_convention() {
    const MIN_BEAMS: usize = 20;
    let Some(d) = data_dir() else { return };
    let logs = carmen_logs(&d);
    let mut agree = 0;
    for path in &logs {
        let read = |c| -> Vec<Record> {
            let input = formats::open(path, |r| r).unwrap();
            Reader::with_convention(input, c)
                .map(|r| r.unwrap())
                .collect()
        };
        let (a_scans, b_scans) = (
            read(AngleConvention::EndToEnd),
            read(AngleConvention::DropEnd),
        );
        let n = a_scans[0].ranges_mm.len();
        let mut pfe = Pfe::paper();
        let mut walls: Vec<(usize, (usize, usize))> = Vec::new();
        for (k, (a, b)) in a_scans.iter().zip(&b_scans).enumerate() {
            let spans = |r: &Record, pfe: &mut Pfe| -> Vec<(usize, usize)> {
                pfe.extract(&r.geometry, &r.ranges_mm)
                    .features
                    .iter()
                    .filter(|f| f.is_line() && f.last() - f.first() >= MIN_BEAMS)
                    .map(|f| (f.first(), f.last()))
                    .collect()
            };
            let sa = spans(a, &mut pfe);
            let sb = spans(b, &mut pfe);
            for &(a0, a1) in &sa {
                for &(b0, b1) in &sb {
                    let (f, l) = (a0.max(b0), a1.min(b1));
                    if l >= f + MIN_BEAMS {
                        walls.push((k, (f, l)));
                    }
                }
            }
        }
        let step_a = std::f32::consts::PI / (n - 1) as f32;
        let step_b = std::f32::consts::PI / n as f32;
        let total = |step: f32| -> f64 {
            let (mut e, mut m) = (0.0, 0);
            for &(k, span) in &walls {
                let (s, c) = sse(&a_scans[k], span, step);
                e += s;
                m += c;
            }
            (e / m.max(1) as f64).sqrt()
        };
        // Grid of steps from 0.99 to 1.012 × 180°/n.
        let grid: Vec<(f32, f64)> = (0..=44)
            .map(|j| {
                let step = step_b * (0.99 + 0.0005 * j as f32);
                (step, total(step))
            })
            .collect();
        let (best, _) = grid
            .iter()
            .copied()
            .min_by(|x, y| x.1.total_cmp(&y.1))
            .unwrap();
        let (ea, eb) = (total(step_a), total(step_b));
        let name = path.file_name().unwrap().to_string_lossy();
        eprintln!(
            "| {name} | {n} | {} | {ea:.3} | {eb:.3} | {:.4} | {} |",
            walls.len(),
            best / step_b,
            if ea < eb { "180°/(n−1)" } else { "180°/n" },
        );
        assert!(walls.len() >= 50, "{name}: only {} walls", walls.len());
        let auto_better = if n % 2 == 1 { ea <= eb } else { eb <= ea };
        if auto_better {
            agree += 1;
        }
    }
    assert_eq!(
        agree,
        logs.len(),
        "the Auto convention should fit walls best on every log"
    );
}
