//! The README's sample data (examples/data) reads and extracts as its README says: the emulated
//! LMS200's room, walls 2.5 m left and right and 4 m ahead (lms200-emulator's `RoomSource`
//! default), one line each, in both files.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: a panic fails the test

use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use pfe_core::{Config, Extractor, Feature, Scan};
use pfe_formats::{scans, Format, Record};

fn read(name: &str, format: Format) -> Vec<Record> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../examples/data")
        .join(name);
    let file = File::open(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    scans(format, Box::new(BufReader::new(file)))
        .collect::<Result<Vec<_>, _>>()
        .unwrap_or_else(|e| panic!("{name}: {e}"))
}

#[test]
fn the_samples_are_the_same_room_and_give_its_three_walls() {
    let lms = read("room.lms", Format::Lms200);
    let csv = read("room.csv", Format::Csv);
    assert_eq!(lms.len(), 11);
    assert_eq!(csv.len(), lms.len());
    let mut ex = Extractor::<401, 48>::new();
    let config = Config::default().with_sigma_r(10.0);
    for (a, b) in lms.iter().zip(&csv) {
        assert_eq!(a.ranges_mm, b.ranges_mm, "scan {}", a.id);
        assert_eq!(a.ranges_mm.len(), 361);
        let scan = Scan::from_mm(a.geometry, &a.ranges_mm);
        ex.extract(&scan, &config).unwrap();
        let lines: Vec<(f32, f32)> = ex
            .features()
            .iter()
            .map(|f| match f {
                Feature::Line(l) => (l.alpha, l.rho),
                other => panic!("scan {}: not a line: {other:?}", a.id),
            })
            .collect();
        // Right wall (normal at −90°), front wall (0°), left wall (+90°), in beam order.
        let truth = [(-90f32, 2500f32), (0.0, 4000.0), (90.0, 2500.0)];
        assert_eq!(lines.len(), 3, "scan {}: {lines:?}", a.id);
        for ((alpha, rho), (deg, mm)) in lines.iter().zip(truth) {
            assert!(
                (alpha.to_degrees() - deg).abs() < 0.1,
                "scan {}: {lines:?}",
                a.id
            );
            assert!((rho - mm).abs() < 5.0, "scan {}: {lines:?}", a.id);
        }
    }
}
