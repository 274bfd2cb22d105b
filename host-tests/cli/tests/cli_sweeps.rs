//! `pfe extract --sweeps`: a 0.5° scan whose odd beams were taken a mirror turn later from a
//! scanner 8 mm further and turned 6 mrad (a moving robot, LMS200 interleaving), of a wall
//! 5 m ahead (ranges ray-cast here, whole mm). Told its two sweeps, or left to `auto` (a CSV
//! cannot say: the sweeps are detected from the scan), the extractor finds the one wall; told
//! one sweep, it cannot. On simulated scenes written as CSV, `auto` extracts interleaved ones as
//! `--sweeps 2` does and plain ones as `--sweeps 1`.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: a panic fails the test

use serde_json::Value;

#[path = "../../tests/common/mod.rs"]
mod common;
use common::{json_lines, pfe, TempDir};

/// The CSV line of the scan: beam i at −90° + i/2 from the pose of its sweep.
fn interleaved_wall() -> String {
    let mut line = String::from("0,-90,0.5");
    for i in 0..361 {
        let (dx, dth) = if i % 2 == 1 { (8.0, 0.006) } else { (0.0, 0.0) };
        let b = (-90.0f64 + 0.5 * i as f64).to_radians() + dth;
        // Wall x = 5000 in the frame of sweep 0, seen from (dx, 0) heading dth.
        let r = if b.cos() > 0.3 {
            ((5000.0 - dx) / b.cos()).round() as i64
        } else {
            0
        };
        line.push_str(&format!(",{r}"));
    }
    line.push('\n');
    line
}

fn lines_near_the_wall(scan: &Value) -> Vec<(f64, f64)> {
    scan["features"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|f| f["kind"] == "line")
        .map(|f| (f["rho"].as_f64().unwrap(), f["alpha"].as_f64().unwrap()))
        .filter(|(rho, _)| (rho - 5000.0).abs() < 100.0)
        .collect()
}

#[test]
fn told_its_sweeps_the_extractor_finds_the_wall() {
    let dir = TempDir::new("cli-sweeps");
    let path = dir.0.join("interleaved.csv");
    std::fs::write(&path, interleaved_wall()).unwrap();
    let p = path.to_str().unwrap();
    let two = pfe(&["extract", "--format", "csv", "--sweeps", "2", p]);
    assert!(
        two.status.success(),
        "{}",
        String::from_utf8_lossy(&two.stderr)
    );
    let scan = &json_lines(&two)[0];
    let walls = lines_near_the_wall(scan);
    assert_eq!(walls.len(), 1, "{scan}");
    let (rho, alpha) = walls[0];
    assert!(
        (rho - 5000.0).abs() < 2.0 && alpha.abs() < 1e-3,
        "{rho} {alpha}"
    );
    // Auto (the default): the CSV cannot say, the scan shows it.
    let auto = pfe(&["extract", "--format", "csv", p]);
    assert_eq!(lines_near_the_wall(&json_lines(&auto)[0]), walls);
    // One sweep: the zigzag is not one wall.
    let one = pfe(&["extract", "--format", "csv", "--sweeps", "1", p]);
    let scan = &json_lines(&one)[0];
    let walls = lines_near_the_wall(scan);
    assert!(
        walls.len() != 1 || (walls[0].0 - 5000.0).abs() >= 2.0,
        "{scan}"
    );
    // A count the scanner cannot have is refused.
    let bad = pfe(&["extract", "--format", "csv", "--sweeps", "5", p]);
    assert_eq!(bad.status.code(), Some(2));
}

/// `n` simulated mixed scenes (σ 5 mm, seed `seed`), moving 8 mm / 6 mrad a mirror turn or
/// standing still, as CSV lines.
fn simulated_csv(n: usize, seed: u64, moving: bool) -> String {
    use pfe_eval::scene::{Scenario, SceneKind};
    let mut text = String::new();
    for k in 0..n {
        let mut sc = Scenario::new(SceneKind::Mixed, pfe_eval::scan_seed(seed, k)).with_sigma(5.0);
        if moving {
            sc = sc.with_motion(pfe_eval::MOVING_V, pfe_eval::MOVING_OMEGA);
        }
        let s = sc.simulate();
        text.push_str(&format!("{k},-90,0.5"));
        for r in &s.ranges_mm {
            text.push_str(&format!(",{}", if r.is_finite() { *r } else { 0.0 }));
        }
        text.push('\n');
    }
    text
}

/// Scans whose features are the same in both outputs.
fn same_features(a: &[Value], b: &[Value]) -> usize {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .filter(|(x, y)| x["features"] == y["features"])
        .count()
}

#[test]
fn auto_extracts_simulated_csv_as_the_sweeps_it_was_made_of() {
    const N: usize = 30;
    let dir = TempDir::new("cli-sweeps-auto");
    for (moving, told) in [(true, "2"), (false, "1")] {
        let path = dir.0.join(format!("scenes-{moving}.csv"));
        std::fs::write(&path, simulated_csv(N, 77, moving)).unwrap();
        let p = path.to_str().unwrap();
        let run = |extra: &[&str]| {
            let mut args = vec!["extract", "--format", "csv"];
            args.extend_from_slice(extra);
            args.push(p);
            let out = pfe(&args);
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            json_lines(&out)
        };
        let (auto, told_out) = (run(&[]), run(&["--sweeps", told]));
        let other = run(&["--sweeps", if told == "2" { "1" } else { "2" }]);
        let same = same_features(&auto, &told_out);
        eprintln!(
            "moving {moving}: auto as --sweeps {told} on {same} of {N} scans; --sweeps 1 and 2 \
             agree on {}",
            same_features(&told_out, &other)
        );
        if moving {
            // Until the first scan that shows its sweeps, auto takes one.
            assert!(same >= N - 1, "auto as --sweeps 2 on {same} of {N}");
            assert!(same_features(&auto, &other) < N / 2, "one sweep differs");
        } else {
            assert_eq!(same, N, "plain scenes: auto as --sweeps 1");
        }
    }
}
