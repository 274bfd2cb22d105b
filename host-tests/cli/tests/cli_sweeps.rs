//! `pfe extract --sweeps`: a 0.5° scan whose odd beams were taken a mirror turn later from a
//! scanner 8 mm further and turned 6 mrad (a moving robot, LMS200 interleaving), of a wall
//! 5 m ahead (ranges ray-cast here, whole mm). Told its two sweeps, the extractor finds the
//! one wall; told one sweep, it cannot.
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
    // One sweep (the default): the zigzag is not one wall.
    let one = pfe(&["extract", "--format", "csv", p]);
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
