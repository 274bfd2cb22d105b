//! `pfe plot --scans A..B --html|--sheet`: a range of scans as one self-contained HTML page (a
//! slider and prev/next buttons over the plots) or one SVG sheet.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: a panic fails the test

use std::path::PathBuf;
use std::process::{Command, Output};

#[path = "../../tests/common/mod.rs"]
mod common;
use common::{arg, fixture, scratch, stderr};

fn plot(args: &[&str]) -> Output {
    let room = fixture("room.log");
    Command::new(env!("CARGO_BIN_EXE_pfe"))
        .args(["plot", "--format", "carmen", arg(&room)])
        .args(args)
        .output()
        .unwrap()
}

/// Every `url(#X)` in `text` names an element `id="X"` defined once.
fn references_resolve_once(text: &str) {
    for part in text.split("url(#").skip(1) {
        let id = &part[..part.find(')').unwrap()];
        let defs = text.matches(&format!("id=\"{id}\"")).count();
        assert_eq!(defs, 1, "id {id} defined {defs} times");
    }
}

#[test]
fn html_page_holds_every_scan_and_a_slider_over_them() {
    let d = scratch("html");
    let (html, sheet) = (d.join("room.html"), d.join("room.svg"));
    let out = plot(&[
        "--scans",
        "0..1",
        "--html",
        arg(&html),
        "--sheet",
        arg(&sheet),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let page = std::fs::read_to_string(&html).unwrap();
    // pfe's mark first (comments may precede the doctype), then the page.
    let rest = page
        .strip_prefix(pfe_formats::outfile::MARK)
        .unwrap_or_default();
    assert!(rest.trim_start().starts_with("<!DOCTYPE html>"));
    // B - A + 1 plots, one per scan, the first shown.
    assert_eq!(page.matches("<svg xmlns=").count(), 2);
    assert!(page.contains(r#"<div class="scan" data-scan="0""#));
    assert!(page.contains(r#"<div class="scan" data-scan="1""#) && page.contains(" hidden>"));
    assert!(
        page.contains(r#"<input id="slider" type="range" min="0" max="1" step="1" value="0">"#),
        "no slider over 2 scans"
    );
    assert!(page.contains(r#"id="prev""#) && page.contains(r#"id="next""#));
    assert!(page.contains("<script>") && page.contains("function show(i)"));
    // Self-contained: nothing loaded from elsewhere (the SVG namespace is a name, not a load).
    for external in ["src=", "href=", "<link", "@import", "url(http"] {
        assert!(
            !page.contains(external),
            "the page loads something: {external}"
        );
    }
    assert_eq!(
        page.matches("http").count(),
        page.matches("http://www.w3.org/2000/svg").count()
    );
    references_resolve_once(&page);

    let svg = std::fs::read_to_string(&sheet).unwrap();
    let body = svg
        .strip_prefix(pfe_formats::outfile::MARK)
        .unwrap_or_default();
    assert!(body.trim_start().starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    // The sheet, a cell per scan, each holding its plot.
    assert_eq!(svg.matches("<svg").count(), 1 + 2 * 2);
    assert_eq!(svg.matches("</svg>").count(), 1 + 2 * 2);
    references_resolve_once(&svg);
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn a_range_past_the_log_keeps_what_it_has_and_says_so() {
    let d = scratch("past");
    let html = d.join("room.html");
    let out = plot(&["--scans", "1..5", "--html", arg(&html)]);
    assert!(out.status.success(), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(err.contains("1 of the 5 scans"), "{err}");
    let page = std::fs::read_to_string(&html).unwrap();
    assert_eq!(page.matches("<svg xmlns=").count(), 1);
    assert!(page.contains(r#"min="0" max="0""#));

    // No scan in the range, a reversed or oversized range, --scans without a page: exit 2.
    let none = plot(&["--scans", "7..9", "--html", arg(&html)]);
    assert_eq!(none.status.code(), Some(2), "{}", stderr(&none));
    assert!(stderr(&none).contains("no scan with an ID in 7..9"));
    for bad in [
        &["--scans", "3..1", "--html", "x.html"][..],
        &["--scans", "0..1000", "--html", "x.html"],
        &["--scans", "0..1"],
        &["--scan", "0", "--html", "x.html"],
    ] {
        let out = plot(bad);
        assert_eq!(out.status.code(), Some(2), "{bad:?}: {}", stderr(&out));
    }
    assert!(!PathBuf::from("x.html").exists());
    std::fs::remove_dir_all(&d).unwrap();
}

/// The `<svg …>` tag and the grid of each plot in `text`, in order.
fn frames(text: &str) -> Vec<(String, String)> {
    text.split("<svg xmlns=")
        .skip(1)
        .map(|p| {
            let tag = p[..p.find('>').unwrap()].to_string();
            let grid = p
                .split("<path ")
                .find(|t| t.contains(r##"stroke="#e4e4e4""##))
                .map(|t| t[..t.find("/>").unwrap()].to_string())
                .unwrap();
            (tag, grid)
        })
        .collect()
}

/// Scans of different extents (a wall 1.5 m ahead, then 6 m): alone, each gets its own
/// scale; on one HTML page or sheet they share one size, one scale and one grid, so that
/// paging does not jump.
#[test]
fn pages_keep_one_scale_across_scans() {
    let d = scratch("scale");
    let csv = d.join("walls.csv");
    let scan = |id: u32, dist: f64| {
        let r: Vec<String> = (0..181)
            .map(|i| {
                let b = f64::from(i - 90).to_radians();
                format!("{:.0}", (dist / b.cos().max(0.25)).min(8000.0))
            })
            .collect();
        format!("{id},-90,1,{}\n", r.join(","))
    };
    std::fs::write(&csv, scan(0, 1500.0) + &scan(1, 6000.0)).unwrap();
    let run = |args: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_pfe"))
            .args(["plot", "--format", "csv", arg(&csv)])
            .args(args)
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", stderr(&out));
    };
    let alone: Vec<(String, String)> = (0..2)
        .map(|k| {
            let out = d.join(format!("scan{k}.svg"));
            run(&["--scan", &k.to_string(), "-o", arg(&out)]);
            frames(&std::fs::read_to_string(out).unwrap()).remove(0)
        })
        .collect();
    assert_ne!(
        alone[0].1, alone[1].1,
        "the two scans have the same grid alone"
    );
    let (html, sheet) = (d.join("walls.html"), d.join("walls-sheet.svg"));
    run(&[
        "--scans",
        "0..1",
        "--html",
        arg(&html),
        "--sheet",
        arg(&sheet),
    ]);
    let page = frames(&std::fs::read_to_string(&html).unwrap());
    assert_eq!(page.len(), 2);
    assert_eq!(page[0], page[1], "the page's plots differ in size or scale");
    // The common view holds the larger scan: its grid, not the small one's.
    assert_eq!(page[0].1, alone[1].1);
    let sheet = std::fs::read_to_string(&sheet).unwrap();
    let cells: Vec<(String, String)> = sheet
        .split("<svg x=")
        .skip(1)
        .map(|c| {
            let grid = c
                .split("<path ")
                .find(|t| t.contains(r##"stroke="#e4e4e4""##))
                .unwrap();
            (String::new(), grid[..grid.find("/>").unwrap()].to_string())
        })
        .collect();
    assert_eq!(cells.len(), 2);
    assert_eq!(cells[0], cells[1]);
    std::fs::remove_dir_all(&d).unwrap();
}
