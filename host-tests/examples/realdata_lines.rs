//! Why lines do not re-appear: the real-data benchmark's line comparison (`pfe realdata`,
//! docs/REALDATA.md "lines%") on one CARMEN log, split by the line's stated σ_α and by what
//! scan k+1 has where an unmatched line of scan k went.
//!
//! `cargo run -p host-tests --release --example realdata_lines -- LOG [--sigma-r MM]`
//!
//! For each method: the points of scan k's lines of ≥ 10 points whose σ_α is at most 10 mrad
//! (well determined) and above, with the share of each that re-appears; and for the others,
//! whether k+1 has a line within the gate that does not overlap, an overlapping line outside
//! the gate (|Δα| ≥ 0.1 rad or |Δρ| ≥ 0.3 m), a circle within 0.3 m of the moved segment, or
//! none of these. The matching is the benchmark's ([`pfe_eval::realdata::compare`]).
//! σ_α is each method's own: the baselines' covariances are not consistent (their NIS is
//! 10–100), so the split compares each method with itself rather than with the others.

use anyhow::Result;
use pfe_eval::realdata::compare::{GATE_ALPHA, GATE_RHO_MM, MIN_LINE_POINTS};
use pfe_eval::realdata::{methods, FrameChange, LineObs, Seen};
use pfe_formats::Format;

mod common;
use common::{for_each_pair, LogArgs};

/// Bound between well and poorly determined lines, rad.
const SIGMA_ALPHA: f64 = 0.010;

/// Where an unmatched line of scan k went in scan k+1.
const FATES: [&str; 4] = [
    "gated, no overlap",
    "overlap, outside gate",
    "circle there",
    "nothing",
];

#[derive(Default)]
struct Tally {
    /// Points and re-appearing points: [well determined, poorly determined].
    points: [usize; 2],
    matched: [usize; 2],
    /// Points of unmatched lines by [`FATES`].
    fates: [usize; 4],
}

fn main() -> Result<()> {
    let Some(args) = LogArgs::parse("realdata_lines", &["--sigma-r"])? else {
        return Ok(());
    };
    let sigma_r: f32 = args.get("--sigma-r", Format::Carmen.sigma_r())?;
    let log = &args.log;
    let mut ms = methods(sigma_r);
    let mut tallies: Vec<Tally> = ms.iter().map(|_| Tally::default()).collect();
    for_each_pair(log, &mut ms, |m, a, b| {
        if let Some(tally) = tallies.get_mut(m) {
            add(tally, a, b);
        }
    })?;
    println!("{log}: σ_r {sigma_r} mm; lines of ≥ {MIN_LINE_POINTS} points, point-weighted");
    println!(
        "{:12} {:>9} {:>7} {:>9} {:>9} {:>7} | unmatched: {}",
        "method",
        "σα≤10mrad",
        "re-found",
        "σα>10mrad",
        "re-found",
        "all",
        FATES.join(" / ")
    );
    let pct = |a: usize, b: usize| 100.0 * a as f64 / b.max(1) as f64;
    for (m, t) in ms.iter().zip(&tallies) {
        let all = t.points[0] + t.points[1];
        let unmatched = all - t.matched[0] - t.matched[1];
        let fates: Vec<String> = t
            .fates
            .iter()
            .map(|&f| format!("{:.1}", pct(f, unmatched)))
            .collect();
        println!(
            "{:12} {:>9} {:>6.1}% {:>9} {:>8.1}% {:>6.1}% | {} %",
            m.name(),
            t.points[0],
            pct(t.matched[0], t.points[0]),
            t.points[1],
            pct(t.matched[1], t.points[1]),
            pct(t.matched[0] + t.matched[1], all),
            fates.join(" / ")
        );
    }
    Ok(())
}

/// Scan k's (`a`) lines moved into scan k+1's (`b`) frame, matched and tallied.
fn add(t: &mut Tally, a: &Seen, b: &Seen) {
    let change = FrameChange::between(a.pose, b.pose);
    for l in a.lines.iter().filter(|l| l.points >= MIN_LINE_POINTS) {
        // NaN (no variance) counts as poorly determined.
        let well = l.cov[0][0].sqrt() <= SIGMA_ALPHA;
        let class = usize::from(!well);
        t.points[class] += l.points;
        let moved = change.line(l);
        let tests: Vec<(bool, bool)> = b
            .lines
            .iter()
            .map(|o| {
                let (d, _, _) = moved.difference(o);
                let in_gate = d[0].abs() < GATE_ALPHA && d[1].abs() < GATE_RHO_MM;
                (in_gate, overlaps(&moved, o))
            })
            .collect();
        if tests.iter().any(|&(g, o)| g && o) {
            t.matched[class] += l.points;
            continue;
        }
        let gated = tests.iter().any(|&(g, _)| g);
        let overlapping = tests.iter().any(|&(_, o)| o);
        let (s, e) = (change.point(l.start), change.point(l.end));
        let circle = b
            .circles
            .iter()
            .any(|c| (segment_distance(c.center, s, e) - c.radius).abs() < 300.0);
        let fate = match (gated, overlapping, circle) {
            (true, _, _) => 0,
            (false, true, _) => 1,
            (false, false, true) => 2,
            (false, false, false) => 3,
        };
        t.fates[fate] += l.points;
    }
}

/// Whether the extents of `m` and `o` overlap along `o` (the benchmark's test).
fn overlaps(m: &LineObs, o: &LineObs) -> bool {
    let (m0, m1) = m.extent_along(o);
    let (c0, c1) = o.extent_along(o);
    m0 <= c1 && c0 <= m1
}

/// Distance from `p` to the segment `a`–`b`, mm.
fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
}
