//! The real-data benchmark as a text table, and `docs/REALDATA.md` with its plots.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use pfe_formats::outfile;

use super::compare::{CONSISTENT_DRAWS, GATE_ALPHA, GATE_CENTER_MM, GATE_RHO_MM, MIN_LINE_POINTS};
use super::coverage::{MAX_SIGMA_ALPHA, MAX_SIGMA_MID_MM, MIN_SMOOTH_RUN, SMOOTH_STEP_MM};
use super::frame::{REFERENCE_SIGMA_MM, REFERENCE_SIGMA_RAD};
use super::refit::{MIN_LINES, MIN_SPREAD};
use super::shared::Shared;
use super::statics::{STATIC_MM, STATIC_MOVE_MM, STATIC_SPAN, STATIC_TURN_RAD};
use super::svg::grouped_bars;
use super::{LogReport, Summary};

/// Median of a χ²₂ variable (2 ln 2): the line and circle NIS median of consistent covariances.
pub const CHI2_2_MEDIAN: f64 = 1.386_294_361;

const HEADER: [&str; 24] = [
    "method",
    "feat%",
    "bare%",
    "at ends%",
    "lines%",
    "n lines",
    "|Δρ| mm",
    "|Δα| mrad",
    "NIS",
    "NIS refit",
    "if consistent",
    "circles",
    "circ%",
    "n circ",
    "circ NIS",
    "circ NIS refit",
    "obj/scan",
    "obj%",
    "obj NIS",
    "obj NIS refit",
    "n static obj",
    "static obj NIS",
    "static obj NIS +ref",
    "static obj NIS refit",
];

fn num(v: f64, digits: usize) -> String {
    if v.is_finite() {
        format!("{v:.digits$}")
    } else {
        "–".to_string()
    }
}

fn row(s: &Summary) -> [String; 24] {
    [
        s.method.clone(),
        num(s.in_features_pct, 1),
        num(s.bare_pct, 2),
        num(s.bare_at_ends_pct, 2),
        num(s.lines_reappear_pct, 1),
        s.lines_matched.to_string(),
        num(s.d_rho_mm, 1),
        num(s.d_alpha_mrad, 1),
        num(s.nis, 2),
        num(s.nis_refit, 2),
        num(s.nis_refit_consistent, 2),
        s.circles.to_string(),
        num(s.circles_reappear_pct, 1),
        s.circles_matched.to_string(),
        num(s.circle_nis, 2),
        num(s.circle_nis_refit, 2),
        num(s.objects_per_scan, 2),
        num(s.objects_reappear_pct, 1),
        num(s.object_nis, 2),
        num(s.object_nis_refit, 2),
        s.static_objects_matched.to_string(),
        num(s.static_object_nis, 2),
        num(s.static_object_nis_reference, 2),
        num(s.static_object_nis_refit, 2),
    ]
}

const SHARED_HEADER: [&str; 6] = [
    "against",
    "shared beams",
    "default re-found%",
    "other re-found%",
    "only default (re-found%)",
    "only other (re-found%)",
];

/// `a` of `b` in %, NaN when `b` is 0.
fn pct(a: usize, b: usize) -> f64 {
    if b == 0 {
        f64::NAN
    } else {
        100.0 * a as f64 / b as f64
    }
}

fn shared_row(s: &Shared) -> [String; 6] {
    [
        s.method.clone(),
        s.both.to_string(),
        num(pct(s.both_reference_refound, s.both), 1),
        num(pct(s.both_other_refound, s.both), 1),
        format!(
            "{} ({})",
            s.only_reference,
            num(pct(s.only_reference_refound, s.only_reference), 1)
        ),
        format!(
            "{} ({})",
            s.only_other,
            num(pct(s.only_other_refound, s.only_other), 1)
        ),
    ]
}

fn title(r: &LogReport) -> String {
    let pairs = r.methods.first().map_or(0, |s| s.pairs);
    let scans = r.methods.first().map_or(0, |s| s.scans);
    format!(
        "{}: {scans} scans of {} beams, {pairs} pairs",
        r.log, r.beams
    )
}

/// One log's text table.
pub fn table(r: &LogReport) -> String {
    let rows: Vec<[String; 24]> = r.methods.iter().map(row).collect();
    let mut out = format!("{}\n", title(r));
    aligned(&mut out, &HEADER, &rows);
    let _ = writeln!(
        out,
        "pfe-default's lines of ≥ {MIN_LINE_POINTS} points against each method's, by beam:"
    );
    let shared: Vec<[String; 6]> = r.shared.iter().map(shared_row).collect();
    aligned(&mut out, &SHARED_HEADER, &shared);
    out
}

/// `header` and `rows` as right-aligned text columns, appended to `out`.
fn aligned<const N: usize>(out: &mut String, header: &[&str; N], rows: &[[String; N]]) {
    let mut widths: Vec<usize> = header.iter().map(|h| h.chars().count()).collect();
    for cells in rows {
        for (w, c) in widths.iter_mut().zip(cells) {
            *w = (*w).max(c.chars().count());
        }
    }
    let line = |cells: &mut dyn Iterator<Item = &str>| {
        let mut s = String::new();
        for (k, (c, w)) in cells.zip(&widths).enumerate() {
            let pad = w.saturating_sub(c.chars().count());
            if k == 0 {
                let _ = write!(s, "{c}{}", " ".repeat(pad));
            } else {
                let _ = write!(s, "  {}{c}", " ".repeat(pad));
            }
        }
        s.trim_end().to_string()
    };
    let _ = writeln!(out, "{}", line(&mut header.iter().copied()));
    for cells in rows {
        let _ = writeln!(out, "{}", line(&mut cells.iter().map(String::as_str)));
    }
}

/// The Markdown of `docs/REALDATA.md` (plots referenced by file name, written by
/// [`write_markdown`]); `command` is the command that generated it.
pub fn markdown(reports: &[LogReport], command: &str) -> String {
    let reference_deg = REFERENCE_SIGMA_RAD.to_degrees();
    let mut md = format!(
        "# Real-data benchmark (no ground truth)\n\n\
Generated by `{command}`; do not edit by hand. Every method runs on every scan of the shared \
CARMEN logs (`../shared/data/carmen`, σ_r = 10 mm told to every method, as `pfe bench` does, \
and to pfe `default` the LMS200's beam-to-beam systematic range error σ_sys = 5 mm, ±15 mm in \
its data sheet, as `pfe extract` does for real scanners' formats, the grid each scan's \
ranges lie on (`formats::range_quantum`: 10 mm in most scans, 50 mm in 86 of acapulco's, 33 of \
edmonton's and 118 of fhw's), whose rounding pfe `default` counts as systematic where the \
noise does not dither it, and the interleaved sweeps each scan is made of, `--sweeps` (default `auto`: 2 at 0.5°, one at 1°), which it aligns where \
their offset shows); each pair of consecutive scans k, k+1 is compared through the logs' corrected poses, taken as \
the laser's and as exact. In these logs consecutive scans are about 1 m and 0.1–0.4 rad apart \
(freiburg-079: 0.1 m), one scan per step of the robot.\n\n\
## Columns\n\n\
- **feat%**: valid beams (a return, ≤ r_max) inside the beam span of a feature a consumer can \
use, % of valid beams. Every circle and small object counts; a line counts when the scanner \
can have seen it (≤ 85° incidence at its midpoint, ≥ 10 mm long) and its σ_α ≤ {:.1} rad and \
the σ of its distance at its midpoint ≤ {:.0} mm (beyond them, ±3σ spans more than the benchmark's own gates of 0.1 rad and \
0.3 m: a localiser could not tell that wall from the next); the other lines hold no beam, here \
and in bare%.\n\
- **bare%**: beams of smooth runs that lie in no feature, % of valid beams. A smooth run is a \
maximal run of ≥ {MIN_SMOOTH_RUN} consecutive valid beams whose neighbours differ in range by \
less than {:.1} m: a surface seen continuously that the method left as bare mark points (or \
left out).\n\
- **at ends%**: the part of bare% in bare stretches that reach an end of their smooth run: the \
beams between a feature's end and a jump (≥ {:.1} m) or a no-return, such as the mixed pixels an \
edge gives and short pieces too small for a feature; the rest lies between two features.\n\
- **lines%**: scan k's lines of ≥ {MIN_LINE_POINTS} points are moved into scan k+1's frame \
(α' = α + θ_k − θ_{{k+1}}, ρ' = ρ + (t_k − t_{{k+1}})·(cos α_w, sin α_w), α_w = α + θ_k; \
(α', ρ') → (α' + π, −ρ') when ρ' < 0) and matched to the nearest line of k+1 by \
(Δα/{GATE_ALPHA})² + (Δρ/{GATE_RHO_MM} mm)² among those with |Δα| < {GATE_ALPHA} rad, \
|Δρ| < {:.1} m and extents overlapping along the line; the point-weighted fraction that \
re-appears, %. **n lines**: matched lines.\n\
- **|Δρ|**, **|Δα|**: medians over the matched lines.\n\
- **NIS**: median of dᵀ (J Σ_k Jᵀ + Σ_{{k+1}})⁻¹ d, d = (Δα, Δρ), Σ the lines' full (α, ρ) \
covariance and J the Jacobian of the frame change (the pose exact). Consistent covariances \
and exact poses give a χ²₂, median {CHI2_2_MEDIAN:.2}.\n\
- **NIS refit**: the same after removing, per pair of scans, the weighted least-squares \
3-DOF correction of the relative pose from all its matched lines (when ≥ {MIN_LINES} match and \
their normals are not nearly parallel: smallest eigenvalue of the mean n nᵀ ≥ {MIN_SPREAD}). \
The refit absorbs the poses' own errors but also 3 of the 2m degrees of freedom of m lines: \
consistent covariances then give a mean NIS of (2m − 3)/m per line (1 for m = 3, 1.7 for \
m = 10), so the median lies below {CHI2_2_MEDIAN:.2}.\n\
- **if consistent**: the median NIS refit that consistent covariances would give on the same \
lines and refits: each refitted pair's differences drawn {CONSISTENT_DRAWS} times from \
N(0, S) with its lines' own S, refitted and scored as the measured ones. Below it, the \
covariances are larger than the differences; above it, smaller. Scans taken from nearly one \
place (freiburg-079: 0.1 m apart) see a wall's roughness and the scanner's systematic error \
alike: their errors are correlated, which S, the sum of both scans' covariances, ignores, so \
there the NIS lies below the reference even where each scan's covariance is right. `cargo run -p host-tests --release --example realdata_nis -- LOG` \
splits both by class of line.\n\
- **circles**: circles of scan k; **circ%**: those whose moved centre lies within \
{:.1} m of a circle centre of k+1 (the nearest is taken), %; **n circ**: matched; \
**circ NIS**: median centre NIS with both 2×2 centre covariances (k's turned with the frame), \
χ²₂ median {CHI2_2_MEDIAN:.2} when consistent; **circ NIS refit**: the same after moving k's \
centres by the pair's pose refit from its lines (pairs with a refit; the refit is fitted to \
the lines only, so it costs the circles no degree of freedom; its own uncertainty, the inverse \
of its normal matrix, is added to the centres' covariance). `cargo run -p host-tests --release \
--example realdata_circles -- LOG` splits it by class of circle.\n\
- **obj/scan**: small objects (pfe's third kind of feature: a run of ≥ 3 returns between \
range jumps, at most 0.3 m across) per scan; **obj%**: those of scan k whose moved centre \
lies within {:.1} m of a small object's centre in k+1; **obj NIS** and **obj NIS refit**: as \
for circles, with the objects' centre covariances (a method without small objects: –); \
**n static obj** and **static obj NIS**: the matches that are unambiguous (one candidate each \
way within the gate) and whose object is static (re-found within {STATIC_MM:.0} mm of the same \
place in the world in a scan at most {STATIC_SPAN} away, taken {STATIC_MOVE_MM:.0} mm or \
{STATIC_TURN_RAD} rad from both scans of the pair), and their median NIS: the covariance's \
measure where people walking with the robot or a railing's posts closer than the gate make \
the nearest match say nothing about it; **static obj NIS +ref**: the same with the corrected \
poses' own scatter between the two scans ({REFERENCE_SIGMA_MM:.0} mm per axis and {reference_deg:.1}°, as in \
docs/POSE.md) added to the pair's covariance, since through those poses their error counts \
as the objects'; **static obj NIS refit**: the same after the pair's pose refit from its \
lines, as for circles.\n\n\
Under each log's table, pfe `default`'s lines against each other method's, beam by beam. \
lines% weighs each method's lines by their own points, so a method that also makes lines \
where another makes none is not scored on the same beams as it; this table is. A beam of scan \
k is held by a line of ≥ {MIN_LINE_POINTS} points when it lies between the line's first and \
last beam, and counts once per pair of scans (re-found if any line holding it is). \
**shared beams**: beams both methods hold in such lines; **default re-found%** and **other \
re-found%**: of those, the share whose line (pfe `default`'s, the other method's) re-appears \
in k+1, matched as for lines%; **only default** and **only other**: beams only that method \
holds in such lines, with the share re-found.\n\n\
Figures are over the whole log; `–` = nothing to measure.\n\n",
        f64::from(MAX_SIGMA_ALPHA),
        f64::from(MAX_SIGMA_MID_MM),
        f64::from(SMOOTH_STEP_MM) / 1000.0,
        f64::from(SMOOTH_STEP_MM) / 1000.0,
        GATE_RHO_MM / 1000.0,
        GATE_CENTER_MM / 1000.0,
        GATE_CENTER_MM / 1000.0,
    );
    md.push_str("## Tables\n\n");
    for r in reports {
        let _ = writeln!(md, "### {}\n", title(r));
        let _ = writeln!(md, "| {} |", HEADER.join(" | "));
        let _ = writeln!(md, "|{}", "---|".repeat(HEADER.len()));
        for s in &r.methods {
            let _ = writeln!(md, "| {} |", row(s).join(" | "));
        }
        md.push('\n');
        if !r.shared.is_empty() {
            let _ = writeln!(md, "| {} |", SHARED_HEADER.join(" | "));
            let _ = writeln!(md, "|{}", "---|".repeat(SHARED_HEADER.len()));
            for s in &r.shared {
                let _ = writeln!(md, "| {} |", shared_row(s).join(" | "));
            }
            md.push('\n');
        }
    }
    md.push_str("## Plots\n\n");
    for (file, what) in PLOTS {
        let _ = writeln!(md, "![{what}]({file})\n");
    }
    md
}

const PLOTS: [(&str, &str); 6] = [
    ("realdata-lines.svg", "lines of ≥ 10 points that re-appear"),
    (
        "realdata-shared.svg",
        "lines re-found on the beams pfe-default and split-and-merge both hold in lines",
    ),
    ("realdata-bare.svg", "bare beams of smooth runs"),
    ("realdata-nis.svg", "line NIS median after the pose refit"),
    ("realdata-circles.svg", "circle centre NIS median"),
    (
        "realdata-circles-refit.svg",
        "circle centre NIS median after the lines' pose refit",
    ),
];

/// A bar chart: title, y label, the value per method, a reference line, log y.
type Chart = (
    &'static str,
    &'static str,
    fn(&Summary) -> f64,
    Option<(f64, &'static str)>,
    bool,
);

/// The four plots: lines re-appearing, bare beams, line NIS after the refit, circle NIS.
pub fn plots(reports: &[LogReport]) -> Vec<String> {
    let groups: Vec<String> = reports.iter().map(|r| r.log.clone()).collect();
    let names: Vec<String> = reports
        .first()
        .map(|r| r.methods.iter().map(|s| s.method.clone()).collect())
        .unwrap_or_default();
    let series = |f: &dyn Fn(&Summary) -> f64| -> Vec<(String, Vec<f64>)> {
        names
            .iter()
            .enumerate()
            .map(|(k, n)| {
                let ys = reports
                    .iter()
                    .map(|r| r.methods.get(k).map_or(f64::NAN, f))
                    .collect();
                (n.clone(), ys)
            })
            .collect()
    };
    let nis = Some((CHI2_2_MEDIAN, "χ²₂ median"));
    let charts: [Chart; 5] = [
        (
            "Lines of ≥ 10 points that re-appear in the next scan (point-weighted)",
            "%",
            |s| s.lines_reappear_pct,
            None,
            false,
        ),
        (
            "Beams of smooth runs in no feature",
            "% of valid beams",
            |s| s.bare_pct,
            Some((1.0, "1 %")),
            false,
        ),
        (
            "Line NIS median after the per-pair pose refit",
            "NIS (log)",
            |s| s.nis_refit,
            nis,
            true,
        ),
        (
            "Circle centre NIS median",
            "NIS (log)",
            |s| s.circle_nis,
            nis,
            true,
        ),
        (
            "Circle centre NIS median after the lines' pose refit",
            "NIS (log)",
            |s| s.circle_nis_refit,
            nis,
            true,
        ),
    ];
    let mut out: Vec<String> = charts
        .iter()
        .map(|&(title, ylabel, metric, reference, log_y)| {
            grouped_bars(title, ylabel, &groups, &series(&metric), reference, log_y)
        })
        .collect();
    out.insert(1, shared_chart(reports, &groups));
    out
}

/// pfe-default's and split-and-merge's lines re-found on the beams both hold in lines, and
/// pfe-default's on the beams only it holds, per log.
fn shared_chart(reports: &[LogReport], groups: &[String]) -> String {
    let series = |name: &str, f: fn(&Shared) -> f64| {
        let ys = reports
            .iter()
            .map(|r| {
                let against = r.shared.iter().find(|s| s.method == "split-merge");
                against.map_or(f64::NAN, f)
            })
            .collect();
        (name.to_string(), ys)
    };
    grouped_bars(
        "Line beams re-found: pfe-default vs split-and-merge, beam by beam",
        "% of the beams",
        groups,
        &[
            series("default, shared", |s| pct(s.both_reference_refound, s.both)),
            series("split-merge, shared", |s| pct(s.both_other_refound, s.both)),
            series("default only", |s| {
                pct(s.only_reference_refound, s.only_reference)
            }),
        ],
        None,
        false,
    )
}

/// The files [`write_markdown`] writes for `path`: it, then its plots next to it (none when
/// `path` is a device or a pipe, [`outfile::beside`]).
pub fn output_files(path: &Path) -> Vec<PathBuf> {
    std::iter::once(path.to_path_buf())
        .chain(
            PLOTS
                .iter()
                .filter_map(|(file, _)| outfile::beside(path, file)),
        )
        .collect()
}

/// Writes [`markdown`] to `path` and the plots next to it; none of them replaces a file no
/// `pfe` command wrote unless `force` ([`outfile`]).
pub fn write_markdown(
    path: &Path,
    reports: &[LogReport],
    command: &str,
    force: bool,
) -> anyhow::Result<()> {
    let files = output_files(path);
    outfile::check(files.iter().map(PathBuf::as_path), force)?;
    outfile::write(path, &markdown(reports, command), force)?;
    for (p, svg) in files.iter().skip(1).zip(plots(reports)) {
        outfile::write(p, &svg, force)?;
    }
    Ok(())
}
