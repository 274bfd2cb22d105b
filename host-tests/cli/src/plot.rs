//! `pfe plot`: one scan with its mark points and features as SVG (like Fig. 7 of the paper), or
//! a range of scans as one HTML page to page through (`--html`) or a grid of small plots
//! (`--sheet`).

use std::io::Write;
use std::ops::RangeInclusive;
use std::path::{Path, PathBuf};

use super::input::{bad_input, nothing_found, open_scans, MethodArgs, Scan};
use super::Failure;
use crate::figure;

mod world;
use pfe_eval::methods::{Extraction, Method};
use world::run_world;
pub use world::WORLD_DRAWN;

/// Most scans on one page or sheet.
pub const MAX_PAGE_SCANS: u64 = 1000;

/// Arguments of `pfe plot`.
#[derive(clap::Args, Debug)]
#[command(group(clap::ArgGroup::new("pages").args(["html", "sheet"]).multiple(true)))]
pub struct Args {
    /// Input file.
    file: PathBuf,
    #[command(flatten)]
    method: MethodArgs,
    /// Scan ID to plot (the csv ID, else the 0-based ordinal).
    #[arg(long, short, required_unless_present_any = ["scans", "world"], conflicts_with_all = ["scans", "pages", "world"], requires = "output")]
    scan: Option<u64>,
    /// Output SVG file of --scan (`-` = stdout).
    #[arg(short, long, requires = "scan")]
    output: Option<PathBuf>,
    /// Scan IDs A..B (both included, at most 1000) for --html and/or --sheet, or for --world
    /// (default there: every scan).
    #[arg(long, value_name = "A..B", value_parser = scan_range)]
    scans: Option<RangeInclusive<u64>>,
    /// One self-contained HTML page with every scan of --scans, a slider and prev/next buttons
    /// (also ←/→ keys); no external resources.
    #[arg(long, value_name = "OUT.html", requires = "scans")]
    html: Option<PathBuf>,
    /// One SVG with the scans of --scans as a grid of small plots.
    #[arg(long, value_name = "OUT.svg", requires = "scans")]
    sheet: Option<PathBuf>,
    /// One SVG of the scans (of --scans, else all) in the world frame: their points and
    /// features placed by the log's poses (CARMEN), the log's trajectory; with --odometry, the
    /// feature odometry's trajectory (its 3σ position ellipses, its failures) and map beside
    /// them, started at the first scan's pose.
    #[arg(long, value_name = "OUT.svg", conflicts_with = "pages")]
    world: Option<PathBuf>,
    /// With --world: run `pfe odometry` (no prior) on the scans and draw its trajectory and
    /// map; a log without poses is then drawn in the odometry's frame.
    #[arg(long, requires = "world")]
    odometry: bool,
    /// With --world --odometry: the odometry also uses the scans' own points, as `pfe
    /// odometry --points` does (host only; the firmware registers features alone).
    #[arg(long, requires = "odometry")]
    points: bool,
    /// With --world: draw the points and features of every Nth scan (default: at most 200
    /// scans drawn); the trajectories keep every scan.
    #[arg(long, value_name = "N", requires = "world", value_parser = clap::value_parser!(u64).range(1..))]
    every: Option<u64>,
    /// Replace output files even when no pfe command wrote them (without it such a file is
    /// left alone: exit 2).
    #[arg(long)]
    force: bool,
}

/// `A..B`: scan IDs from A to B, both included, at most [`MAX_PAGE_SCANS`] of them.
pub fn scan_range(s: &str) -> Result<RangeInclusive<u64>, String> {
    let (a, b) = s
        .split_once("..")
        .ok_or_else(|| format!("expected A..B (e.g. 0..99), got {s:?}"))?;
    let id = |t: &str| {
        t.trim()
            .parse::<u64>()
            .map_err(|_| format!("not a scan ID: {t:?} in {s:?}"))
    };
    let (a, b) = (id(a)?, id(b.strip_prefix('=').unwrap_or(b))?);
    if a > b {
        return Err(format!("{a}..{b} is empty (A must be at most B)"));
    }
    if b - a >= MAX_PAGE_SCANS {
        return Err(format!(
            "{} scans in {a}..{b}; at most {MAX_PAGE_SCANS} per page",
            b - a + 1
        ));
    }
    Ok(a..=b)
}

/// Runs `pfe plot`.
pub fn run(a: Args) -> Result<(), Failure> {
    let (file, format) = (a.file.as_path(), a.method.format);
    if a.scans.is_some() && a.html.is_none() && a.sheet.is_none() && a.world.is_none() {
        return Err(Failure::input(
            "--scans A..B needs an output: --html, --sheet or --world",
        ));
    }
    let outputs = [&a.output, &a.html, &a.sheet, &a.world];
    let files = outputs
        .iter()
        .filter_map(|o| o.as_deref())
        .filter(|p| p.as_os_str() != "-");
    pfe_formats::outfile::check(files, a.force).map_err(|e| Failure::input(e.to_string()))?;
    if let Some(world) = &a.world {
        return run_world(&a, world);
    }
    let wanted = match (&a.scans, a.scan) {
        (Some(r), _) => r.clone(),
        (None, Some(k)) => k..=k,
        (None, None) => return Err(Failure::input("--scan K or --scans A..B is required")),
    };
    let mut method = a.method.method();
    let input = open_scans(file, format, a.method.topic.as_deref())?;
    let bar = input.bar.clone();
    let want = wanted.end() - wanted.start() + 1;
    let mut found: Vec<Scan> = Vec::new();
    let mut count = 0u64;
    for s in input.scans {
        let s = s.map_err(|e| bad_input(file, format, count, &e))?;
        count += 1;
        if wanted.contains(&s.record.id) {
            found.push(s);
            if found.len() as u64 == want {
                break;
            }
        }
    }
    bar.finish_and_clear();
    if count == 0 {
        let bytes = input.bytes.load(std::sync::atomic::Ordering::Relaxed);
        return Err(nothing_found(file, format, "scan", bytes));
    }
    if found.is_empty() {
        let what = if want == 1 {
            format!("with ID {}", wanted.start())
        } else {
            format!("with an ID in {}..{}", wanted.start(), wanted.end())
        };
        return Err(Failure::input(format!(
            "{}: no scan {what} ({count} scans read)",
            file.display()
        )));
    }
    let name = file
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    // The range noise of one point (the along-line σ of a line's end points), mm.
    let sigma_point_mm = f64::from(
        a.method
            .sigma_r
            .unwrap_or(format.sigma_r())
            .hypot(a.method.sigma_sys.unwrap_or(format.sigma_sys())),
    );
    let mut auto = a.method.auto_sweeps();
    let extracted: Vec<(Extraction, Vec<usize>)> = found
        .iter()
        .map(|s| {
            let context = a.method.context(&s.record, &mut auto);
            let ex = method.extract_in(&s.record.geometry, &s.record.ranges_mm, &context);
            (ex, method.veils())
        })
        .collect();
    // Pages of several scans: one view and one exaggeration for all, so that paging through
    // them does not rescale.
    let (view, exaggeration) = if found.len() > 1 {
        let view = found
            .iter()
            .zip(&extracted)
            .map(|(s, (ex, _))| figure::extent(&s.record, ex))
            .reduce(figure::View::union);
        let factor = view.map(|v| {
            figure::exaggeration_in(
                &v,
                extracted.iter().flat_map(|(ex, _)| &ex.features),
                sigma_point_mm,
            )
        });
        (view, factor)
    } else {
        (None, None)
    };
    let plots: Vec<Plot> = found
        .iter()
        .zip(extracted)
        .map(|(s, (ex, veils))| {
            let title = title(&name, s, method.name());
            let opts = figure::Options {
                veils,
                sigma_point_mm,
                view,
                exaggeration,
            };
            Plot {
                id: s.record.id,
                svg: figure::svg_with(&s.record, &ex, &title, &opts),
                title,
                ex,
            }
        })
        .collect();
    if let (Some(output), [plot]) = (&a.output, plots.as_slice()) {
        write_output(output, &plot.svg, a.force)?;
        eprintln!(
            "pfe: wrote {} ({} marks, {} features)",
            if output.as_os_str() == "-" {
                "the SVG to stdout".to_string()
            } else {
                output.display().to_string()
            },
            plot.ex.marks.len(),
            plot.ex.features.len()
        );
        return Ok(());
    }
    if (plots.len() as u64) < want {
        eprintln!(
            "pfe: warning: {} of the {want} scans in {}..{} found ({count} scans read)",
            plots.len(),
            wanted.start(),
            wanted.end()
        );
    }
    let heading = format!("{name} — scans {}..{}", wanted.start(), wanted.end());
    if let Some(html) = &a.html {
        write_output(html, &html_page(&heading, &plots), a.force)?;
        eprintln!("pfe: wrote {} ({} scans)", html.display(), plots.len());
    }
    if let Some(sheet) = &a.sheet {
        write_output(sheet, &sheet_svg(&heading, &plots), a.force)?;
        eprintln!("pfe: wrote {} ({} scans)", sheet.display(), plots.len());
    }
    Ok(())
}

/// One plotted scan.
struct Plot {
    id: u64,
    title: String,
    svg: String,
    ex: Extraction,
}

/// The title of a scan's plot; a bag's scan names its frame and stamp.
fn title(name: &str, s: &Scan, method: &str) -> String {
    let id = s.record.id;
    match (&s.frame_id, s.stamp_ns) {
        (Some(frame), Some(t)) => format!(
            "{name} — scan {id} ({frame}, {}.{:09} s) — {method}",
            t / 1_000_000_000,
            t % 1_000_000_000
        ),
        _ => format!("{name} — scan {id} — {method}"),
    }
}

fn write_output(output: &Path, text: &str, force: bool) -> Result<(), Failure> {
    if output.as_os_str() == "-" {
        let mut out = std::io::stdout().lock();
        match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
            Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
                Err(Failure::other(format!("cannot write output: {e}")))
            }
            _ => Ok(()),
        }
    } else {
        pfe_formats::outfile::write(output, text, force).map_err(|e| {
            if e.is_refusal() {
                Failure::input(e.to_string())
            } else {
                Failure::other(e.to_string())
            }
        })
    }
}

/// `svg` with its element IDs made unique to plot `k` (several plots in one document).
fn unique_ids(svg: &str, k: usize) -> String {
    svg.replace(r#"id="plot""#, &format!(r#"id="plot-{k}""#))
        .replace("url(#plot)", &format!("url(#plot-{k})"))
}

/// The value of attribute `name` in the opening tag of `svg`.
fn attribute(svg: &str, name: &str) -> Option<f64> {
    let tag = &svg[..svg.find('>')?];
    let key = format!(" {name}=\"");
    let start = tag.find(&key)? + key.len();
    let len = tag[start..].find('"')?;
    tag[start..start + len].parse().ok()
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// One HTML page: every plot (one shown at a time), a slider over them, prev/next buttons and
/// ←/→ keys, in plain inline CSS and JavaScript.
fn html_page(heading: &str, plots: &[Plot]) -> String {
    let n = plots.len();
    let mut page = format!(
        r#"<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>{title}</title>
<style>
body {{ font-family: sans-serif; margin: 1em; }}
.nav {{ display: flex; gap: 0.6em; align-items: center; margin-bottom: 0.8em; }}
#slider {{ flex: 1; max-width: 40em; }}
.scan svg {{ max-width: 100%; height: auto; }}
</style>
</head>
<body>
<h1>{title}</h1>
<div class="nav">
<button id="prev" type="button">&#9664; prev</button>
<input id="slider" type="range" min="0" max="{max}" step="1" value="0">
<button id="next" type="button">next &#9654;</button>
<span id="label"></span>
</div>
"#,
        title = escape(heading),
        max = n.saturating_sub(1),
    );
    for (k, p) in plots.iter().enumerate() {
        page.push_str(&format!(
            "<div class=\"scan\" data-scan=\"{}\" data-title=\"{}\"{}>\n{}</div>\n",
            p.id,
            escape(&p.title),
            if k == 0 { "" } else { " hidden" },
            unique_ids(&p.svg, k)
        ));
    }
    page.push_str(
        r#"<script>
"use strict";
const scans = document.querySelectorAll(".scan");
const slider = document.getElementById("slider");
const label = document.getElementById("label");
function show(i) {
  i = Math.max(0, Math.min(scans.length - 1, i));
  scans.forEach((s, k) => { s.hidden = k !== i; });
  slider.value = i;
  label.textContent = "scan " + scans[i].dataset.scan + " (" + (i + 1) + " of " + scans.length + ")";
}
slider.addEventListener("input", () => show(Number(slider.value)));
document.getElementById("prev").addEventListener("click", () => show(Number(slider.value) - 1));
document.getElementById("next").addEventListener("click", () => show(Number(slider.value) + 1));
document.addEventListener("keydown", (e) => {
  if (e.key === "ArrowLeft") show(Number(slider.value) - 1);
  if (e.key === "ArrowRight") show(Number(slider.value) + 1);
});
show(0);
</script>
</body>
</html>
"#,
    );
    page
}

/// Width of one plot on a sheet, px (heights follow each plot's aspect).
const CELL_W: f64 = 420.0;
/// Height of one cell of a sheet, px.
const CELL_H: f64 = 320.0;

/// One SVG: the plots in a grid of up to 4 columns, each scaled into its cell.
fn sheet_svg(heading: &str, plots: &[Plot]) -> String {
    let cols = plots.len().clamp(1, 4);
    let rows = plots.len().div_ceil(cols);
    let (top, gap) = (40.0, 10.0);
    let width = cols as f64 * (CELL_W + gap) + gap;
    let height = top + rows as f64 * (CELL_H + gap) + gap;
    let mut s = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0}" height="{height:.0}" viewBox="0 0 {width:.0} {height:.0}" font-family="DejaVu Sans, Helvetica, Arial, sans-serif">
<rect width="100%" height="100%" fill="white"/>
<text x="{gap}" y="26" font-size="18" font-weight="bold">{}</text>
"#,
        escape(heading)
    );
    for (k, p) in plots.iter().enumerate() {
        let (w, h) = (
            attribute(&p.svg, "width").unwrap_or(CELL_W),
            attribute(&p.svg, "height").unwrap_or(CELL_H),
        );
        let (x, y) = (
            gap + (k % cols) as f64 * (CELL_W + gap),
            top + (k / cols) as f64 * (CELL_H + gap),
        );
        s.push_str(&format!(
            "<svg x=\"{x:.0}\" y=\"{y:.0}\" width=\"{CELL_W:.0}\" height=\"{CELL_H:.0}\" viewBox=\"0 0 {w:.0} {h:.0}\">\n{}</svg>\n",
            unique_ids(&p.svg, k)
        ));
    }
    s.push_str("</svg>\n");
    s
}
