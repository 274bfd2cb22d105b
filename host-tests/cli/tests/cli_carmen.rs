//! `pfe realdata` on CARMEN logs it cannot compare, and on the newer logger's lines
//! (`ROBOTLASER1`, `RAWLASER1`), with the fixtures.

use std::path::Path;

#[path = "../../tests/common/mod.rs"]
mod common;
use common::{arg, fixture, pfe, scratch, stderr};

/// `pfe realdata` answers a log it cannot compare with exit 2 and no table: no two
/// consecutive scans with a pose (one scan; scans of `RAWLASER1` lines only), a malformed
/// line, a missing file; among other logs, it names it and compares the others. The room's
/// scans as `ROBOTLASER1` lines give the `FLASER` lines' table.
#[test]
fn realdata_refuses_logs_with_nothing_to_compare() {
    let dir = scratch("realdata-refuses");
    let room = std::fs::read_to_string(fixture("room.log")).unwrap();
    let scans: Vec<&str> = room.lines().filter(|l| l.starts_with("FLASER")).collect();
    assert!(scans.len() >= 2, "{}", scans.len());
    // The FLASER fields as ROBOTLASER1 / RAWLASER1 lines (from −90°, 180° / (n − 1) apart
    // for n odd, 180° / n for n even, 50 m).
    let laser = |line: &str, kind: &str| -> String {
        let t: Vec<&str> = line.split_ascii_whitespace().collect();
        let n: usize = t[1].parse().unwrap();
        let (ranges, rest) = t[2..].split_at(n);
        let head = format!(
            "{kind} 0 -1.5707963268 3.1415926536 {:.12} 50 0.01 0 {n} {} 0",
            std::f64::consts::PI / if n % 2 == 1 { n - 1 } else { n } as f64,
            ranges.join(" ")
        );
        match kind {
            "ROBOTLASER1" => format!(
                "{head} {} {} 0 0 0 0 0 {}\n",
                rest[0..3].join(" "),
                rest[3..6].join(" "),
                rest[6..9].join(" ")
            ),
            _ => format!("{head} {}\n", rest[6..9].join(" ")),
        }
    };
    let write = |name: &str, text: String| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let robot = write(
        "robot.log",
        scans.iter().map(|l| laser(l, "ROBOTLASER1")).collect(),
    );
    let table = |p: &Path| {
        let out = pfe(&["realdata", arg(p)]);
        assert!(out.status.success(), "{}", stderr(&out));
        let text = String::from_utf8(out.stdout).unwrap();
        text.lines().skip(1).collect::<Vec<_>>().join("\n")
    };
    let flaser = table(&fixture("room.log"));
    assert!(flaser.contains("pfe-default"), "{flaser}");
    assert_eq!(table(&robot), flaser);
    let one = write("one.log", format!("{}\n", scans[0]));
    let raw = write(
        "raw.log",
        scans.iter().map(|l| laser(l, "RAWLASER1")).collect(),
    );
    for (path, says) in [
        (one, "1 scan(s)"),
        (raw, "2 scan(s)"),
        (
            fixture("truncated.log"),
            "line 3: FLASER declares 181 ranges",
        ),
        (dir.join("absent.log"), "absent.log"),
    ] {
        let out = pfe(&["realdata", arg(&path)]);
        assert_eq!(out.status.code(), Some(2), "{path:?}: {}", stderr(&out));
        assert!(stderr(&out).contains(says), "{path:?}: {}", stderr(&out));
        assert!(out.stdout.is_empty(), "{path:?}");
    }
    // Among other logs: named and left out, the others still compared (exit 2).
    let out = pfe(&[
        "realdata",
        arg(&fixture("truncated.log")),
        arg(&fixture("room.log")),
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("1 of 2 logs left out"),
        "{}",
        stderr(&out)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.starts_with("room:") && text.contains(&flaser),
        "{text}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--md /dev/null` writes the report to the device and no plots: they would land in /dev.
#[test]
fn realdata_writes_no_plots_beside_a_device() {
    let strays = || -> Vec<String> {
        std::fs::read_dir("/dev")
            .map(|d| {
                d.flatten()
                    .map(|e| e.file_name().to_string_lossy().into_owned())
                    .filter(|n| n.starts_with("realdata-"))
                    .collect()
            })
            .unwrap_or_default()
    };
    assert!(strays().is_empty(), "{:?}", strays());
    let out = pfe(&["realdata", arg(&fixture("room.log")), "--md", "/dev/null"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(strays().is_empty(), "{:?}", strays());
}
