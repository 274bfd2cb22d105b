//! `pfe plot`: one scan with its mark points and features as SVG (like Fig. 7 of the paper), or
//! a range of scans as one HTML page to page through (`--html`) or a grid of small plots
//! (`--sheet`).

use std::io::Write;
use std::ops::RangeInclusive;
use std::path::{Path, PathBuf};

use super::input::{bad_input, nothing_found, open_scans, MethodArgs, Scan};
use super::Failure;
use crate::figure;
use pfe_eval::methods::{Extraction, Method};

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

/// Most scans whose points `pfe plot --world` draws without --every.
pub const WORLD_DRAWN: usize = 200;

/// `pfe plot --world`: the scans in the world frame, with the odometry beside the log's poses.
fn run_world(a: &Args, output: &Path) -> Result<(), Failure> {
    use crate::figure::world::{self, MapFeature, OdometryTrack, Placed, Pose, World};
    use pfe_core::Feature;
    let (file, format) = (a.file.as_path(), a.method.format);
    let mut method = a.method.method();
    let input = open_scans(file, format, a.method.topic.as_deref())?;
    let bar = input.bar.clone();
    let mut scans: Vec<(pfe_formats::Record, Vec<Feature>)> = Vec::new();
    let mut count = 0u64;
    let mut auto = a.method.auto_sweeps();
    for s in input.scans {
        if crate::interrupt::requested() {
            return Err(Failure {
                code: 130,
                message: format!("interrupted after {count} scans"),
            });
        }
        let s = s.map_err(|e| bad_input(file, format, count, &e))?;
        count += 1;
        if a.scans.as_ref().is_some_and(|r| !r.contains(&s.record.id)) {
            if a.scans.as_ref().is_some_and(|r| s.record.id > *r.end()) {
                break;
            }
            continue;
        }
        let context = a.method.context(&s.record, &mut auto);
        let ex = method.extract_in(&s.record.geometry, &s.record.ranges_mm, &context);
        scans.push((s.record, ex.features));
        if count % 256 == 0 {
            bar.set_message(format!("{count} scans"));
        }
    }
    bar.finish_and_clear();
    if count == 0 {
        let bytes = input.bytes.load(std::sync::atomic::Ordering::Relaxed);
        return Err(nothing_found(file, format, "scan", bytes));
    }
    if scans.is_empty() {
        let r = a.scans.clone().unwrap_or(0..=0);
        return Err(Failure::input(format!(
            "{}: no scan with an ID in {}..{} ({count} scans read)",
            file.display(),
            r.start(),
            r.end()
        )));
    }
    let mm = |p: [f64; 3]| -> Pose { [p[0] * 1000.0, p[1] * 1000.0, p[2]] };
    let log: Vec<Pose> = scans
        .iter()
        .filter_map(|(r, _)| r.pose.map(mm))
        .filter(|p| p.iter().all(|v| v.is_finite()))
        .collect();
    if log.is_empty() && !a.odometry {
        return Err(Failure::input(format!(
            "{}: no scan has a pose (a CARMEN log has them); --world needs them, or --odometry to draw the scans in the odometry's frame",
            file.display()
        )));
    }
    let every = a
        .every
        .map(|n| usize::try_from(n).unwrap_or(usize::MAX))
        .unwrap_or_else(|| scans.len().div_ceil(WORLD_DRAWN).max(1));
    let odometry_poses: Option<(Vec<Pose>, OdometryTrack)> = a.odometry.then(|| {
        let mut odo = Box::new(pfe_pose::Odometry::<{ crate::odometry::MAP }>::new(
            pfe_pose::Config::default(),
        ));
        let mut track = OdometryTrack {
            poses: Vec::with_capacity(scans.len()),
            covs: Vec::with_capacity(scans.len()),
            degenerate: Vec::new(),
            none: Vec::new(),
            map: Vec::new(),
            segments: Vec::new(),
        };
        let mut raw: Vec<(Pose, [[f64; 2]; 2])> = Vec::with_capacity(scans.len());
        for (k, (_, features)) in scans.iter().enumerate() {
            let obs: Vec<pfe_pose::Observation> = features
                .iter()
                .filter_map(pfe_pose::Observation::from_feature)
                .collect();
            let step = odo.update(&obs, None);
            match step.status {
                pfe_pose::Status::Ok => {}
                pfe_pose::Status::Degenerate { .. } => track.degenerate.push(k),
                pfe_pose::Status::None(_) => track.none.push(k),
            }
            let p = step.pose;
            let c = |i: usize, j: usize| f64::from(step.cov[i][j]);
            raw.push((
                [f64::from(p.x), f64::from(p.y), f64::from(p.theta)],
                [[c(0, 0), c(0, 1)], [c(1, 0), c(1, 1)]],
            ));
        }
        // The odometry's frame in the log's: where the first scan with a log pose is in both
        // (the first scan's log pose when it has one), else the origin.
        let anchor: Pose = scans
            .iter()
            .zip(&raw)
            .find_map(|((r, _), (o, _))| {
                let l = mm(r.pose?);
                let (s, c) = o[2].sin_cos();
                let inv = [-(c * o[0] + s * o[1]), s * o[0] - c * o[1], -o[2]];
                Some(world::compose(&l, &inv))
            })
            .unwrap_or([0.0; 3]);
        let (s0, c0) = anchor[2].sin_cos();
        for (p, cov) in &raw {
            let pose = world::compose(&anchor, p);
            // The position's covariance turned into the world's axes: R C Rᵀ.
            let (xx, xy, yy) = (cov[0][0], 0.5 * (cov[0][1] + cov[1][0]), cov[1][1]);
            track.covs.push([
                [
                    c0 * c0 * xx - 2.0 * s0 * c0 * xy + s0 * s0 * yy,
                    s0 * c0 * (xx - yy) + (c0 * c0 - s0 * s0) * xy,
                ],
                [
                    s0 * c0 * (xx - yy) + (c0 * c0 - s0 * s0) * xy,
                    s0 * s0 * xx + 2.0 * s0 * c0 * xy + c0 * c0 * yy,
                ],
            ]);
            track.poses.push(pose);
        }
        for m in odo.map() {
            let at = |v: [f32; 2]| world::place(&anchor, (f64::from(v[0]), f64::from(v[1])));
            match m {
                pfe_pose::Observation::Line(l) if l.has_extent() => {
                    track.map.push(MapFeature::Segment(at(l.start), at(l.end)));
                }
                pfe_pose::Observation::Point(p) => {
                    track.map.push(MapFeature::Point(at([p.x, p.y])));
                }
                _ => {}
            }
        }
        (track.poses.clone(), track)
    });
    let (placed_by, poses): (String, Vec<Option<Pose>>) = if log.is_empty() {
        let odo = odometry_poses
            .as_ref()
            .map(|(p, _)| p.iter().copied().map(Some).collect())
            .unwrap_or_default();
        ("the odometry".into(), odo)
    } else {
        (
            "the log's poses".into(),
            scans.iter().map(|(r, _)| r.pose.map(mm)).collect(),
        )
    };
    let mut drawn: Vec<Placed> = Vec::new();
    let mut track = odometry_poses.map(|(_, t)| t);
    for (k, ((record, features), pose)) in scans.iter().zip(&poses).enumerate() {
        if k % every != 0 {
            continue;
        }
        if let Some(pose) = pose {
            drawn.push(Placed {
                record,
                features,
                pose: *pose,
            });
        }
        // The lines by the odometry's poses, beside those by the log's (not twice).
        if let Some(t) = track.as_mut().filter(|_| !log.is_empty()) {
            if let Some(p) = t.poses.get(k).copied() {
                for f in features {
                    if let Feature::Line(l) = f {
                        let a = world::place(&p, (f64::from(l.start.x), f64::from(l.start.y)));
                        let e = world::place(&p, (f64::from(l.end.x), f64::from(l.end.y)));
                        t.segments.push((a, e));
                    }
                }
            }
        }
    }
    let name = file
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let (first, last) = (
        scans.first().map_or(0, |s| s.0.id),
        scans.last().map_or(0, |s| s.0.id),
    );
    let frame = if log.is_empty() { "odometry" } else { "world" };
    let figure = World {
        title: format!(
            "{name} — scans {first}..{last} in the {frame} frame — {}",
            method.name()
        ),
        frame: frame.into(),
        placed_by,
        scans: drawn,
        read: scans.len(),
        every,
        log,
        odometry: track,
    };
    write_output(output, &world::svg(&figure), a.force)?;
    eprintln!(
        "pfe: wrote {} ({} scans, {} drawn{})",
        output.display(),
        figure.read,
        figure.scans.len(),
        figure
            .odometry
            .as_ref()
            .map(|o| format!(
                "; odometry: {} degenerate, {} none",
                o.degenerate.len(),
                o.none.len()
            ))
            .unwrap_or_default()
    );
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
