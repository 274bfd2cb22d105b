//! A log in the world frame: its scans' points and features placed by their poses, the log's
//! own trajectory and, beside it, a feature odometry's trajectory and map (`pfe plot --world`).

use std::fmt::Write;

use pfe_core::Feature;
use pfe_formats::Record;

use super::axes::Bounds;
use super::{arc_points, ellipse, escape, Canvas, CIRCLE, LEFT, LINE, OBJECT, POINT, TOP};

/// Colour of the log's own trajectory.
const LOG: &str = "#222222";
/// Colour of the odometry's trajectory and map.
const ODOMETRY: &str = "#d62728";

/// Colour of the odometry's map.
const MAP: &str = "#8b0000";

/// A pose in the world: x mm, y mm, θ rad.
pub type Pose = [f64; 3];

/// `p` (mm, in the frame of `pose`) in the world.
pub fn place(pose: &Pose, (x, y): (f64, f64)) -> (f64, f64) {
    let (s, c) = pose[2].sin_cos();
    (pose[0] + c * x - s * y, pose[1] + s * x + c * y)
}

/// `a ⊕ b`: pose `b`, given in the frame of `a`, in `a`'s frame's frame.
pub fn compose(a: &Pose, b: &Pose) -> Pose {
    let (x, y) = place(a, (b[0], b[1]));
    let t = a[2] + b[2];
    [x, y, t.sin().atan2(t.cos())]
}

/// One scan drawn in the world.
pub struct Placed<'a> {
    /// The scan.
    pub record: &'a Record,
    /// Its features.
    pub features: &'a [Feature],
    /// Where it was taken: the scanner's pose in the world.
    pub pose: Pose,
}

/// A feature of an odometry's map, in the world (mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MapFeature {
    /// A line segment seen from `.0` to `.1`.
    Segment((f64, f64), (f64, f64)),
    /// A point feature (a circle's or a small object's centre).
    Point((f64, f64)),
}

/// A feature odometry's run, in the world.
pub struct OdometryTrack {
    /// Its pose of every scan.
    pub poses: Vec<Pose>,
    /// The covariance of each pose's position (x, y), mm², in the world's axes.
    pub covs: Vec<[[f64; 2]; 2]>,
    /// Scans registered as "degenerate" (indices into `poses`).
    pub degenerate: Vec<usize>,
    /// Scans not registered ("none").
    pub none: Vec<usize>,
    /// Its local map after the last scan.
    pub map: Vec<MapFeature>,
    /// The drawn scans' line segments placed by the odometry's pose.
    pub segments: Vec<((f64, f64), (f64, f64))>,
    /// Whether the scans' own points helped (`pfe plot --points`), not the features alone.
    pub points: bool,
}

/// What [`svg`] draws.
pub struct World<'a> {
    /// The figure's title.
    pub title: String,
    /// What places the scans ("the log's poses" or "the odometry").
    pub placed_by: String,
    /// The frame's name on the axes ("world", or "odometry" for a log without poses).
    pub frame: String,
    /// The scans drawn.
    pub scans: Vec<Placed<'a>>,
    /// Scans read (the drawn ones are every `every`-th).
    pub read: usize,
    /// Only every `every`-th scan is drawn.
    pub every: usize,
    /// The log's own poses of the scans read that have one.
    pub log: Vec<Pose>,
    /// A feature odometry's run beside the log's.
    pub odometry: Option<OdometryTrack>,
}

/// Draw the odometry's position ellipse of every `ELLIPSE_EVERY`-th scan.
const ELLIPSE_EVERY: usize = 25;

/// The SVG of a log in the world frame.
pub fn svg(w: &World) -> String {
    // The view: the points drawn (but their outermost 0.5 % on each side: a few far returns
    // would shrink the scene) and both trajectories (an odometry far off the log's is
    // clipped, not allowed to shrink the scene to nothing: its positions count only within
    // the span of the rest, twice over).
    let mut b: Option<Bounds> = None;
    let mut add = |x: f64, y: f64| match b.as_mut() {
        Some(b) => b.add(x, y),
        None if x.is_finite() && y.is_finite() => {
            b = Some(Bounds {
                x0: x,
                x1: x,
                y0: y,
                y1: y,
            })
        }
        None => {}
    };
    let mut placed_pts: Vec<Vec<(f64, f64)>> = Vec::with_capacity(w.scans.len());
    for p in &w.scans {
        let pts: Vec<(f64, f64)> = (0..p.record.ranges_mm.len())
            .filter_map(|i| p.record.point(i))
            .map(|(x, y)| place(&p.pose, (f64::from(x), f64::from(y))))
            .collect();
        placed_pts.push(pts);
    }
    let quantiles = |mut v: Vec<f64>| -> Option<(f64, f64)> {
        v.retain(|x| x.is_finite());
        v.sort_by(f64::total_cmp);
        let cut = v.len() / 200;
        Some((*v.get(cut)?, *v.get(v.len() - 1 - cut)?))
    };
    let all = placed_pts.iter().flatten();
    if let (Some((x0, x1)), Some((y0, y1))) = (
        quantiles(all.clone().map(|p| p.0).collect()),
        quantiles(all.map(|p| p.1).collect()),
    ) {
        add(x0, y0);
        add(x1, y1);
    }
    for p in &w.log {
        add(p[0], p[1]);
    }
    let core = b.unwrap_or(Bounds {
        x0: -1000.0,
        x1: 1000.0,
        y0: -1000.0,
        y1: 1000.0,
    });
    let mut b = core;
    if let Some(o) = &w.odometry {
        let span = (core.x1 - core.x0).max(core.y1 - core.y0).max(1000.0);
        for p in &o.poses {
            if p[0] > core.x0 - span
                && p[0] < core.x1 + span
                && p[1] > core.y0 - span
                && p[1] < core.y1 + span
            {
                b.add(p[0], p[1]);
            }
        }
    }
    let c = Canvas::new(&b);
    let (sx, sy) = (|x: f64| c.sx(x), |y: f64| c.sy(y));
    let mut s = String::new();
    c.header(
        &mut s,
        &w.title,
        &format!("x, {}", w.frame),
        &format!("y, {}", w.frame),
    );
    let _ = writeln!(s, r#"<g clip-path="url(#plot)">"#);

    // Points of the drawn scans.
    let mut d = String::new();
    for &(x, y) in placed_pts.iter().flatten() {
        let _ = write!(d, "M{:.1},{:.1}h0", sx(x), sy(y));
    }
    let _ = writeln!(
        s,
        r#"<path d="{d}" stroke="{POINT}" stroke-opacity="0.45" stroke-width="1.8" stroke-linecap="round" fill="none"/>"#
    );
    // Their features, placed by the same poses.
    let (mut n_lines, mut n_circles, mut n_objects) = (0, 0, 0);
    let mut lines = String::new();
    for p in &w.scans {
        for f in p.features {
            match f {
                Feature::Line(l) => {
                    n_lines += 1;
                    let a = place(&p.pose, (f64::from(l.start.x), f64::from(l.start.y)));
                    let e = place(&p.pose, (f64::from(l.end.x), f64::from(l.end.y)));
                    let _ = write!(
                        lines,
                        "M{:.1},{:.1}L{:.1},{:.1}",
                        sx(a.0),
                        sy(a.1),
                        sx(e.0),
                        sy(e.1)
                    );
                }
                Feature::Circle(ci) => {
                    n_circles += 1;
                    let (cx, cy) = (f64::from(ci.center.x), f64::from(ci.center.y));
                    let arc: Vec<String> = arc_points(
                        cx,
                        cy,
                        f64::from(ci.radius),
                        f64::from(ci.start_angle),
                        f64::from(ci.end_angle),
                    )
                    .into_iter()
                    .map(|q| {
                        let (x, y) = place(&p.pose, q);
                        format!("{:.1},{:.1}", sx(x), sy(y))
                    })
                    .collect();
                    let _ = writeln!(
                        s,
                        r#"<polyline points="{}" fill="none" stroke="{CIRCLE}" stroke-width="2"/>"#,
                        arc.join(" ")
                    );
                }
                Feature::Object(o) => {
                    n_objects += 1;
                    let (x, y) = place(&p.pose, (f64::from(o.center.x), f64::from(o.center.y)));
                    let r = (0.5 * f64::from(o.extent) * c.scale).max(1.5);
                    let _ = writeln!(
                        s,
                        r#"<circle cx="{:.1}" cy="{:.1}" r="{r:.1}" fill="{OBJECT}" fill-opacity="0.5"/>"#,
                        sx(x),
                        sy(y)
                    );
                }
                _ => {}
            }
        }
    }
    let _ = writeln!(
        s,
        r#"<path d="{lines}" stroke="{LINE}" stroke-opacity="0.6" stroke-width="1.2" fill="none"/>"#
    );

    // The odometry: its position ellipses, its map, the drawn scans' lines by its poses.
    let mut too_large = 0;
    if let Some(o) = &w.odometry {
        for (k, (p, cov)) in o.poses.iter().zip(&o.covs).enumerate() {
            if k % ELLIPSE_EVERY != 0 && k + 1 != o.poses.len() {
                continue;
            }
            let (a, bb, th) = ellipse(*cov, 3.0);
            // An ellipse wider than a quarter of the view says only "lost": counted, not drawn.
            if !(a.is_finite() && bb.is_finite()) || a > 0.25 * c.span {
                too_large += 1;
            } else {
                let _ = writeln!(
                    s,
                    r#"<ellipse class="odometry-cov" cx="{:.1}" cy="{:.1}" rx="{:.2}" ry="{:.2}" transform="rotate({:.2} {:.1} {:.1})" fill="none" stroke="{ODOMETRY}" stroke-opacity="0.7" stroke-width="0.8"/>"#,
                    sx(p[0]),
                    sy(p[1]),
                    a * c.scale,
                    bb * c.scale,
                    -th.to_degrees(),
                    sx(p[0]),
                    sy(p[1])
                );
            }
        }
        let mut d = String::new();
        for (a, e) in &o.segments {
            let _ = write!(
                d,
                "M{:.1},{:.1}L{:.1},{:.1}",
                sx(a.0),
                sy(a.1),
                sx(e.0),
                sy(e.1)
            );
        }
        let _ = writeln!(
            s,
            r#"<path d="{d}" stroke="{ODOMETRY}" stroke-opacity="0.35" stroke-width="0.7" fill="none"/>"#
        );
        let mut d = String::new();
        for m in &o.map {
            match m {
                MapFeature::Segment(a, e) => {
                    let _ = write!(
                        d,
                        "M{:.1},{:.1}L{:.1},{:.1}",
                        sx(a.0),
                        sy(a.1),
                        sx(e.0),
                        sy(e.1)
                    );
                }
                MapFeature::Point(p) => {
                    let _ = write!(d, "M{:.1},{:.1}m-3,0h6m-3,-3v6", sx(p.0), sy(p.1));
                }
            }
        }
        let _ = writeln!(
            s,
            r#"<path class="odometry-map" d="{d}" stroke="{MAP}" stroke-width="2.6" stroke-linecap="round" fill="none"/>"#
        );
    }
    // The trajectories on top: the log's, then the odometry's.
    let polyline = |poses: &[Pose]| -> String {
        poses
            .iter()
            .filter(|p| p[0].is_finite() && p[1].is_finite())
            .map(|p| format!("{:.1},{:.1}", sx(p[0]), sy(p[1])))
            .collect::<Vec<_>>()
            .join(" ")
    };
    let _ = writeln!(
        s,
        r#"<polyline class="log-trajectory" points="{}" fill="none" stroke="{LOG}" stroke-width="1.6"/>"#,
        polyline(&w.log)
    );
    if let Some(o) = &w.odometry {
        let _ = writeln!(
            s,
            r#"<polyline class="odometry-trajectory" points="{}" fill="none" stroke="{ODOMETRY}" stroke-width="1.6" stroke-dasharray="6 3"/>"#,
            polyline(&o.poses)
        );
        for &k in &o.none {
            if let Some(p) = o.poses.get(k) {
                let _ = writeln!(
                    s,
                    r#"<path d="M{:.1},{:.1}m-4,-4l8,8m0,-8l-8,8" stroke="{ODOMETRY}" stroke-width="1.8"/>"#,
                    sx(p[0]),
                    sy(p[1])
                );
            }
        }
    }
    // The first pose: where both trajectories start.
    if let Some(p) = w.scans.first().map(|p| p.pose).or(w.log.first().copied()) {
        let _ = writeln!(
            s,
            r#"<circle cx="{:.1}" cy="{:.1}" r="4" fill="white" stroke="black" stroke-width="1.5"/>"#,
            sx(p[0]),
            sy(p[1])
        );
    }
    let _ = writeln!(s, "</g>");

    // Legend.
    let lx = LEFT + c.plot_w + 20.0;
    let ly = TOP + 10.0;
    let drawn = w.scans.len();
    let mut entries: Vec<(String, String)> = vec![
        (
            format!(
                r#"<circle cx="{:.1}" cy="{:.1}" r="1.6" fill="{POINT}"/>"#,
                lx + 12.0,
                ly
            ),
            if w.every > 1 {
                format!("points of {drawn} scans (1 in {})", w.every)
            } else {
                format!("points of {drawn} scans")
            },
        ),
        (
            format!(
                r#"<line x1="{lx:.1}" y1="{0:.1}" x2="{1:.1}" y2="{0:.1}" stroke="{LINE}" stroke-width="2"/>"#,
                ly + 22.0,
                lx + 24.0
            ),
            format!("lines ({n_lines})"),
        ),
        (
            format!(
                r#"<line x1="{lx:.1}" y1="{0:.1}" x2="{1:.1}" y2="{0:.1}" stroke="{CIRCLE}" stroke-width="2"/>"#,
                ly + 44.0,
                lx + 24.0
            ),
            format!("circles/arcs ({n_circles})"),
        ),
        (
            format!(
                r#"<circle cx="{:.1}" cy="{:.1}" r="4" fill="{OBJECT}" fill-opacity="0.5"/>"#,
                lx + 12.0,
                ly + 66.0
            ),
            format!("small objects ({n_objects})"),
        ),
        (
            format!(
                r#"<line x1="{lx:.1}" y1="{0:.1}" x2="{1:.1}" y2="{0:.1}" stroke="{LOG}" stroke-width="1.6"/>"#,
                ly + 88.0,
                lx + 24.0
            ),
            format!("log's poses ({})", w.log.len()),
        ),
    ];
    if let Some(o) = &w.odometry {
        let ok = o.poses.len() - o.degenerate.len() - o.none.len();
        entries.push((
            format!(
                r#"<line x1="{lx:.1}" y1="{0:.1}" x2="{1:.1}" y2="{0:.1}" stroke="{ODOMETRY}" stroke-width="1.6" stroke-dasharray="6 3"/>"#,
                ly + 110.0,
                lx + 24.0
            ),
            format!(
                "odometry{} ({} scans)",
                if o.points { " with points" } else { ", features" },
                o.poses.len()
            ),
        ));
        entries.push((
            String::new(),
            format!(
                "  {ok} ok, {} degenerate, {} none (×)",
                o.degenerate.len(),
                o.none.len()
            ),
        ));
        entries.push((
            format!(
                r#"<ellipse cx="{:.1}" cy="{:.1}" rx="10" ry="5" fill="none" stroke="{ODOMETRY}" stroke-width="0.8"/>"#,
                lx + 12.0,
                ly + 154.0
            ),
            format!("its 3σ position (1 in {ELLIPSE_EVERY})"),
        ));
        entries.push((
            format!(
                r#"<line x1="{lx:.1}" y1="{0:.1}" x2="{1:.1}" y2="{0:.1}" stroke="{ODOMETRY}" stroke-opacity="0.45" stroke-width="0.8"/>"#,
                ly + 176.0,
                lx + 24.0
            ),
            if o.segments.is_empty() {
                "(lines placed by it: blue)".to_string()
            } else {
                "lines by its poses".to_string()
            },
        ));
        entries.push((
            format!(
                r#"<line x1="{lx:.1}" y1="{0:.1}" x2="{1:.1}" y2="{0:.1}" stroke="{MAP}" stroke-width="2.6"/>"#,
                ly + 198.0,
                lx + 24.0
            ),
            format!("its local map at the end ({})", o.map.len()),
        ));
    }
    for (k, (icon, text)) in entries.iter().enumerate() {
        s.push_str(icon);
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{:.1}">{}</text>"#,
            lx + 32.0,
            ly + 22.0 * k as f64 + 4.0,
            escape(text)
        );
    }
    let note_y = ly + 22.0 * entries.len() as f64 + 12.0;
    let _ = writeln!(
        s,
        r#"<text x="{lx:.1}" y="{note_y:.1}" font-size="11" fill="dimgray">{} scans, placed by {}</text>"#,
        w.read,
        escape(&w.placed_by)
    );
    if too_large > 0 {
        let _ = writeln!(
            s,
            r#"<text x="{lx:.1}" y="{:.1}" font-size="11" fill="dimgray">{too_large} odometry ellipses over ¼ view: not drawn</text>"#,
            note_y + 16.0
        );
    }
    s.push_str("</svg>\n");
    // The legend's longest text (DejaVu Sans at 12 px: about 7 px a character) widens the
    // figure rather than run off its edge (a long log's counts, "odometry with points").
    let chars = entries
        .iter()
        .map(|(_, t)| t.chars().count())
        .max()
        .unwrap_or(0);
    let need = (lx + 32.0 + LEGEND_CHAR_W * chars as f64 + 12.0).ceil();
    if need > c.width.round() {
        let (w, h) = (c.width, c.height);
        s = s.replacen(
            &format!(r#"width="{w:.0}" height="{h:.0}" viewBox="0 0 {w:.0} {h:.0}""#),
            &format!(r#"width="{need:.0}" height="{h:.0}" viewBox="0 0 {need:.0} {h:.0}""#),
            1,
        );
    }
    s
}

/// Width allowed a character of the legend's text (DejaVu Sans, 12 px: 7 px on average), px.
pub const LEGEND_CHAR_W: f64 = 7.2;

#[cfg(test)]
mod tests {
    use super::*;

    /// A long log's legend ("1839 ok, 115 degenerate, 54 none (×)") fits in the figure: every
    /// text right of the plot ends, at [`LEGEND_CHAR_W`] a character, before its right edge.
    #[test]
    fn a_long_legend_widens_the_figure() {
        let poses: Vec<Pose> = (0..2008).map(|i| [50.0 * f64::from(i), 0.0, 0.0]).collect();
        let w = World {
            title: "freiburg-campus-corrected.log.gz".into(),
            placed_by: "the log's poses".into(),
            frame: "world".into(),
            scans: Vec::new(),
            read: 2008,
            every: 11,
            log: poses.clone(),
            odometry: Some(OdometryTrack {
                covs: vec![[[1.0, 0.0], [0.0, 1.0]]; poses.len()],
                poses,
                degenerate: (0..115).collect(),
                none: (200..254).collect(),
                map: Vec::new(),
                segments: Vec::new(),
                points: true,
            }),
        };
        let svg = svg(&w);
        let number = |tag: &str, key: &str| -> f64 {
            let at = tag.find(&format!(" {key}=\"")).map(|i| i + key.len() + 3);
            at.and_then(|i| tag[i..].split('"').next())
                .and_then(|v| v.parse().ok())
                .unwrap_or(f64::NAN)
        };
        let width = number(&svg[..svg.find('>').unwrap_or(0)], "width");
        let mut checked = 0;
        for part in svg.split("<text").skip(1) {
            let (Some(end), Some(close)) = (part.find('>'), part.find("</text>")) else {
                continue;
            };
            let x = number(&part[..end], "x");
            let text = &part[end + 1..close];
            if x > LEFT + 820.0 {
                let chars = text
                    .replace("&apos;", "'")
                    .replace("&amp;", "&")
                    .chars()
                    .count();
                assert!(
                    x + LEGEND_CHAR_W * chars as f64 <= width,
                    "{text:?} at {x} runs past {width}"
                );
                checked += 1;
            }
        }
        assert!(
            svg.contains("1839 ok, 115 degenerate, 54 none") && checked >= 8,
            "{checked}"
        );
    }
}
