//! `pfe_core::interleave::detect` on the shared recordings (skipped, with a message, when
//! `../shared/data` is absent): no scan of a one-sweep scanner (the 1° CARMEN logs, the Hokuyo
//! URG of hokuyo-cylinders) is declared interleaved; the 0.5° CARMEN logs (a SICK LMS, two
//! sweeps) show their sweeps in a share of their scans (those where the robot moves enough) and
//! are never taken for 4 sweeps.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code

use std::path::{Path, PathBuf};

use pfe_core::interleave::detect;
use pfe_core::Scan;
use pfe_formats::Format;

fn data_dir(test: &str) -> Option<PathBuf> {
    pfe_testkit::skip::shared_data(test, &["carmen", "hokuyo-cylinders"])
}

/// Scans read from each recording (the test runs in debug builds).
const MAX_SCANS: usize = 600;

/// Scans of `file` (its first [`MAX_SCANS`]) by the sweeps its format says and by the sweeps detected: `[told][found]`
/// counts, indices 1, 2, 4 → 0, 1, 2.
fn tally(format: Format, file: &Path) -> [[usize; 3]; 3] {
    let slot = |s: u8| match s {
        1 => 0,
        2 => 1,
        _ => 2,
    };
    let input = pfe_formats::open_for(file, format, |r| r).unwrap();
    let mut t = [[0usize; 3]; 3];
    for record in pfe_formats::scans(format, input).take(MAX_SCANS) {
        let r = record.unwrap();
        let told = r
            .sweeps
            .unwrap_or_else(|| pfe_formats::sweeps_of(format, &r.geometry));
        let q = pfe_formats::range_quantum(&r.ranges_mm, r.geometry.r_max);
        let found = detect(&Scan::from_mm(r.geometry, &r.ranges_mm).with_quantum(q)).sweeps;
        t[slot(told)][slot(found)] += 1;
    }
    t
}

#[test]
fn one_sweep_recordings_are_never_declared_interleaved() {
    let Some(d) = data_dir("one_sweep_recordings_are_never_declared_interleaved") else {
        return;
    };
    let mut files: Vec<(Format, PathBuf)> = std::fs::read_dir(d.join("carmen"))
        .unwrap()
        .map(|e| (Format::Carmen, e.unwrap().path()))
        .filter(|(_, p)| p.to_string_lossy().ends_with(".log.gz"))
        .collect();
    files.sort_by(|a, b| a.1.cmp(&b.1));
    files.push((Format::Hokuyo, d.join("hokuyo-cylinders/scans.txt.gz")));
    let (mut one, mut two) = (0usize, 0usize);
    for (format, file) in &files {
        let t = tally(*format, file);
        let name = file.display();
        eprintln!("{name}: told 1: found {:?}; told 2: found {:?}", t[0], t[1]);
        assert_eq!(
            t[0][1] + t[0][2],
            0,
            "{name}: one sweep declared interleaved"
        );
        assert_eq!(t[1][2], 0, "{name}: two sweeps taken for four");
        if t[1][0] + t[1][1] > 0 {
            // Found where the robot moves enough between mirror turns: 6 % of freiburg-079's
            // first 600 scans (0.1 m a scan), 63 % of csail's.
            let share = t[1][1] as f64 / (t[1][0] + t[1][1]) as f64;
            assert!(
                share > 0.03,
                "{name}: two sweeps found in {share:.3} of the scans"
            );
        }
        one += t[0][0];
        two += t[1][1];
    }
    assert!(one > 3000, "{one} one-sweep scans");
    assert!(two > 300, "{two} two-sweep scans found");
}
