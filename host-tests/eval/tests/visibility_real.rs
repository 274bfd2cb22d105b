//! Issue 39 on the shared recordings (skipped, with a message, when `../shared/data` is absent):
//! pfe `default`, as `pfe extract` runs it, reports no line seen at more than 85° from the
//! scanner at its midpoint and none shorter than 10 mm, and every feature's covariance is
//! finite; the share of small objects some feature holds is printed per recording
//! (`pfe_eval::realdata::visible`); and on the CARMEN logs the centre NIS of the static small
//! objects re-found in the next scan (`pfe_eval::realdata::statics`) is printed, through the
//! logs' corrected poses, with their own scatter added (at most 2, median, on every log where
//! at least 20 match), and after each pair's pose refit from its lines.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code

use std::path::PathBuf;

use pfe_eval::methods::{Method, Pfe, ScanContext};
use pfe_eval::realdata::statics::Statics;
use pfe_eval::realdata::visible::{Seen, Visibility};
use pfe_eval::realdata::{self, log_scans};
use pfe_eval::score::quantile;
use pfe_formats::Format;

fn data_dir(test: &str) -> Option<PathBuf> {
    pfe_testkit::skip::shared_data(test, &["carmen", "hokuyo-cylinders"])
}

fn pfe(format: Format) -> Pfe {
    Pfe::new(
        "pfe-default",
        pfe_core::Config::default()
            .with_sigma_r(format.sigma_r())
            .with_sigma_sys(format.sigma_sys()),
    )
}

/// Counts one scan, checking every feature is finite; returns its features.
fn count(
    v: &mut Visibility,
    m: &mut Pfe,
    r: &pfe_formats::Record,
    context: &ScanContext,
) -> Vec<pfe_core::Feature> {
    let ex = m.extract_in(&r.geometry, &r.ranges_mm, context);
    for f in &ex.features {
        assert!(f.is_well_formed(), "{f:?}");
    }
    let seen: Vec<Seen> = ex.features.iter().map(Seen::from).collect();
    v.add(&r.geometry, &r.ranges_mm, &seen);
    ex.features
}

#[test]
fn no_line_the_scanner_cannot_see_on_the_shared_recordings() {
    let Some(d) = data_dir("no_line_the_scanner_cannot_see_on_the_shared_recordings") else {
        return;
    };
    let mut logs: Vec<PathBuf> = std::fs::read_dir(d.join("carmen"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.to_string_lossy().ends_with(".log.gz"))
        .collect();
    logs.sort();
    assert_eq!(logs.len(), 10, "the ten CARMEN logs");
    let mut all = Vec::new();
    let mut statics = Vec::new();
    for log in &logs {
        let mut m = pfe(Format::Carmen);
        let mut v = Visibility::default();
        let mut st = Statics::default();
        for s in log_scans(log).unwrap() {
            let s = s.unwrap();
            let features = count(&mut v, &mut m, &s.record, &s.context);
            match s.pose {
                Some(p) => st.scan(&realdata::Seen::new(p, &features)),
                None => st.gap(),
            }
        }
        let name = log.file_name().unwrap().to_string_lossy().to_string();
        statics.push((name.clone(), st.nis(), st.nis_reference(), st.nis_refit()));
        all.push((name, v));
    }
    let hokuyo = d.join("hokuyo-cylinders/scans.txt.gz");
    let input = pfe_formats::open_for(&hokuyo, Format::Hokuyo, |r| r).unwrap();
    let mut m = pfe(Format::Hokuyo);
    let mut v = Visibility::default();
    for r in pfe_formats::scans(Format::Hokuyo, input) {
        let r = r.unwrap();
        let context = ScanContext {
            odometry: None,
            sweeps: 1,
            quantum: pfe_formats::range_quantum(&r.ranges_mm, r.geometry.r_max),
        };
        count(&mut v, &mut m, &r, &context);
    }
    all.push(("hokuyo-cylinders".into(), v));
    for (name, v) in &all {
        eprintln!(
            "{name}: {} scans, {} lines, {} > 85°, {} < 10 mm; small objects {} covered {:.1} %",
            v.scans,
            v.lines,
            v.steep,
            v.short,
            v.objects,
            v.covered_pct()
        );
    }
    for (name, nis, reference, refit) in &statics {
        eprintln!(
            "{name}: {} static small objects re-found, centre NIS median {:.2} through the poses, {:.2} with their scatter, {:.2} after the refit",
            nis.len(),
            quantile(nis, 0.5),
            quantile(reference, 0.5),
            quantile(refit, 0.5)
        );
    }
    for (name, nis, reference, _) in &statics {
        // Through the poses alone csail's is 2.3: its scans are a metre apart, and the
        // reference poses' own error between them counts as the objects'. (After the refit
        // from a pair's lines, printed above, csail's median rests on 84 pairs whose values
        // near it lie 0.2-0.4 apart: 1.5 or 2.0 as one or two of them cross it.)
        if reference.len() >= 20 {
            let m = quantile(reference, 0.5);
            assert!(
                m <= 2.0,
                "{name}: static object NIS with the reference's scatter {m:.2} > 2"
            );
        }
        assert!(nis.iter().all(|v| v.is_finite()), "{name}");
    }
    for (name, v) in &all {
        assert!(v.scans > 0 && v.lines > 0, "{name}: {v:?}");
        assert_eq!((v.steep, v.short), (0, 0), "{name}: {v:?}");
        // Issue 39's target: at least 95 % of the small objects in some feature.
        assert!(
            v.covered_pct() >= 95.0,
            "{name}: small objects covered {:.1} % < 95 %: {v:?}",
            v.covered_pct()
        );
    }
}
