//! Hand-written SVG plots of one scan and what the extractor found in it, in the style of
//! Fig. 7 of the paper: scan points, mark points, fitted line segments and circles.
//!
//! The scanner is at the origin; x (forward) points right and y (left) points up, with equal
//! scales on both axes; ticks are in mm or m depending on the extent.
//!
//! ```
//! use pfe_formats::Record;
//! use pfe_eval::methods::{Method, Pfe};
//! use pfe_core::ScanGeometry;
//! let g = ScanGeometry::LMS200_180_050;
//! let ranges: Vec<f32> = (0..361).map(|i| 2000.0 / g.bearing(i).cos().max(0.3)).collect();
//! let record = Record {
//!     id: 0,
//!     geometry: g,
//!     ranges_mm: ranges,
//!     time: None,
//!     pose: None,
//!     sweeps: None,
//! };
//! let ex = Pfe::default_config().extract(&record.geometry, &record.ranges_mm);
//! let svg = pfe_cli::figure::svg(&record, &ex, "a wall");
//! assert!(svg.starts_with("<svg") && svg.contains("a wall"));
//! ```

mod axes;
mod ellipses;
pub mod world;

pub use ellipses::{ellipse, end_point_cov, line_point_cov, line_sigma_at, ELLIPSE_SIGMA};

use std::fmt::Write;

use pfe_core::Feature;

use axes::{tick_label, tick_step, Bounds};
use ellipses::{ellipse_svg, exaggeration, feature_ellipses, line_band};
use pfe_eval::methods::Extraction;
use pfe_formats::Record;

const POINT: &str = "#5a6b7d";
const MARK: &str = "#d62728";
const LINE: &str = "#1f77b4";
const CIRCLE: &str = "#e67e00";
const OBJECT: &str = "#9b30c8";
const GRID: &str = "#e4e4e4";
const BARE_MARK: &str = "#999999";
const VEIL: &str = "#8c564b";

/// Width of the plot area, px.
const PLOT_W: f64 = 820.0;
/// Largest height of the plot area, px.
const PLOT_H_MAX: f64 = 760.0;
const LEFT: f64 = 70.0;
const TOP: f64 = 44.0;
const BOTTOM: f64 = 56.0;
const LEGEND_W: f64 = 250.0;

/// Points of the arc of a circle feature from its first to its last point, the short way.
fn arc_points(cx: f64, cy: f64, r: f64, a0: f64, a1: f64) -> Vec<(f64, f64)> {
    let tau = std::f64::consts::TAU;
    let mut d = (a1 - a0).rem_euclid(tau);
    if d > std::f64::consts::PI {
        d -= tau;
    }
    let steps = ((d.abs() / 0.05).ceil() as usize).clamp(2, 400);
    (0..=steps)
        .map(|k| {
            let a = a0 + d * k as f64 / steps as f64;
            (cx + r * a.cos(), cy + r * a.sin())
        })
        .collect()
}

/// How [`svg_with`] draws a scan beyond its points and features.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// Points that are mixed pixels (`Extractor::is_veil`, JSON `"veils"`), drawn as such.
    pub veils: Vec<usize>,
    /// Range noise of one point, mm: the along-line σ of a line's end points (0: none drawn).
    pub sigma_point_mm: f64,
    /// The area shown, mm, instead of the scan's own extent (pages of several scans share it).
    pub view: Option<View>,
    /// The ellipses' exaggeration instead of the scan's own (pages of several scans share it).
    pub exaggeration: Option<f64>,
}

/// An area of the plane, mm: x from `x0` to `x1`, y from `y0` to `y1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// Least x, mm.
    pub x0: f64,
    /// Greatest x, mm.
    pub x1: f64,
    /// Least y, mm.
    pub y0: f64,
    /// Greatest y, mm.
    pub y1: f64,
}

impl View {
    /// The smallest view holding both.
    pub fn union(self, o: View) -> View {
        View {
            x0: self.x0.min(o.x0),
            x1: self.x1.max(o.x1),
            y0: self.y0.min(o.y0),
            y1: self.y1.max(o.y1),
        }
    }
}

/// The extent of a scan's plot: its points, its lines' ends and the scanner (mm).
pub fn extent(record: &Record, ex: &Extraction) -> View {
    let mut b = Bounds {
        x0: 0.0,
        x1: 0.0,
        y0: 0.0,
        y1: 0.0,
    };
    for (x, y) in (0..record.ranges_mm.len()).filter_map(|i| record.point(i)) {
        b.add(f64::from(x), f64::from(y));
    }
    for f in &ex.features {
        if let Feature::Line(l) = f {
            b.add(f64::from(l.start.x), f64::from(l.start.y));
            b.add(f64::from(l.end.x), f64::from(l.end.y));
        }
    }
    View {
        x0: b.x0,
        x1: b.x1,
        y0: b.y0,
        y1: b.y1,
    }
}

/// The plot's scale (px per mm) of a view: the width fits the plot area, a tall view its
/// largest height.
fn scale_of(v: &View) -> f64 {
    let span = (v.x1 - v.x0).max(v.y1 - v.y0).max(500.0);
    let pad = 0.04 * span;
    let scale = PLOT_W / (v.x1 - v.x0 + 2.0 * pad);
    let h = v.y1 - v.y0 + 2.0 * pad;
    if h * scale > PLOT_H_MAX {
        PLOT_H_MAX / h
    } else {
        scale
    }
}

/// The exaggeration of the ellipses (a power of ten, see the legend) that makes the largest
/// of `features` visible in view `v`.
pub fn exaggeration_in<'a>(
    v: &View,
    features: impl IntoIterator<Item = &'a Feature>,
    sigma_point_mm: f64,
) -> f64 {
    let all: Vec<_> = features
        .into_iter()
        .flat_map(|f| feature_ellipses(f, sigma_point_mm))
        .collect();
    exaggeration(&all, scale_of(v))
}

/// The plot area of a figure: the data-to-pixel mapping (equal scales), the SVG's size, the
/// axes.
struct Canvas {
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    /// px per mm.
    scale: f64,
    /// The larger side of the data's extent, mm (at least 500).
    span: f64,
    plot_w: f64,
    plot_h: f64,
    width: f64,
    height: f64,
}

impl Canvas {
    /// The plot area of data bounds `b`, padded by 4 %.
    fn new(b: &Bounds) -> Self {
        let span = (b.x1 - b.x0).max(b.y1 - b.y0).max(500.0);
        let pad = 0.04 * span;
        let (x0, x1) = (b.x0 - pad, b.x1 + pad);
        let (mut y0, mut y1) = (b.y0 - pad, b.y1 + pad);
        // Equal aspect: fit the width, then cap the height (a very tall scene scales down).
        let mut scale = PLOT_W / (x1 - x0);
        if (y1 - y0) * scale > PLOT_H_MAX {
            scale = PLOT_H_MAX / (y1 - y0);
        }
        let plot_w = (x1 - x0) * scale;
        // Keep the plot area at least 40 % as tall as wide so flat scenes stay readable.
        let min_h = 0.4 * plot_w;
        if (y1 - y0) * scale < min_h {
            let extra = (min_h / scale - (y1 - y0)) / 2.0;
            y0 -= extra;
            y1 += extra;
        }
        let plot_h = (y1 - y0) * scale;
        Canvas {
            x0,
            x1,
            y0,
            y1,
            scale,
            span,
            plot_w,
            plot_h,
            width: LEFT + plot_w + 20.0 + LEGEND_W,
            height: TOP + plot_h + BOTTOM,
        }
    }

    fn sx(&self, x: f64) -> f64 {
        LEFT + (x - self.x0) * self.scale
    }

    fn sy(&self, y: f64) -> f64 {
        TOP + (self.y1 - y) * self.scale
    }

    /// The SVG's opening, its title, the clip path `plot`, the grid, ticks and axis labels.
    fn header(&self, s: &mut String, title: &str, xlabel: &str, ylabel: &str) {
        let (x0, x1, y0, y1) = (self.x0, self.x1, self.y0, self.y1);
        let (width, height, plot_w, plot_h) = (self.width, self.height, self.plot_w, self.plot_h);
        let sx = |x: f64| self.sx(x);
        let sy = |y: f64| self.sy(y);
        let _ = writeln!(
            s,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0}" height="{height:.0}" viewBox="0 0 {width:.0} {height:.0}" font-family="DejaVu Sans, Helvetica, Arial, sans-serif" font-size="12">"#
        );
        let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="26" font-size="15" font-weight="bold">{}</text>"#,
            LEFT,
            escape(title)
        );
        // Clip everything drawn in data coordinates to the plot area.
        let _ = writeln!(
            s,
            r#"<defs><clipPath id="plot"><rect x="{LEFT:.1}" y="{TOP:.1}" width="{plot_w:.1}" height="{plot_h:.1}"/></clipPath></defs>"#
        );

        // Grid and ticks.
        let step = tick_step((x1 - x0).max(y1 - y0), 8.0);
        let metres = step >= 100.0 && (x1 - x0).max(y1 - y0) >= 2000.0;
        let unit = if metres { "m" } else { "mm" };
        let mut grid = String::new();
        let mut labels = String::new();
        let mut t = (x0 / step).ceil() * step;
        while t <= x1 {
            let px = sx(t);
            let _ = write!(grid, "M{px:.1},{TOP:.1}V{:.1}", TOP + plot_h);
            let _ = writeln!(
                labels,
                r#"<line x1="{px:.1}" y1="{:.1}" x2="{px:.1}" y2="{:.1}" stroke="black"/><text x="{px:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
                TOP + plot_h,
                TOP + plot_h + 5.0,
                TOP + plot_h + 19.0,
                tick_label(t, step, metres)
            );
            t += step;
        }
        let mut t = (y0 / step).ceil() * step;
        while t <= y1 {
            let py = sy(t);
            let _ = write!(grid, "M{LEFT:.1},{py:.1}H{:.1}", LEFT + plot_w);
            let _ = writeln!(
                labels,
                r#"<line x1="{:.1}" y1="{py:.1}" x2="{LEFT:.1}" y2="{py:.1}" stroke="black"/><text x="{:.1}" y="{:.1}" text-anchor="end">{}</text>"#,
                LEFT - 5.0,
                LEFT - 8.0,
                py + 4.0,
                tick_label(t, step, metres)
            );
            t += step;
        }
        let _ = writeln!(
            s,
            r#"<path d="{grid}" stroke="{GRID}" stroke-width="1" fill="none"/>"#
        );
        let _ = writeln!(
            s,
            r#"<rect x="{LEFT:.1}" y="{TOP:.1}" width="{plot_w:.1}" height="{plot_h:.1}" fill="none" stroke="black"/>"#
        );
        s.push_str(&labels);
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{xlabel} ({unit})</text>"#,
            LEFT + plot_w / 2.0,
            TOP + plot_h + 40.0
        );
        let _ = writeln!(
            s,
            r#"<text transform="translate(18,{:.1}) rotate(-90)" text-anchor="middle">{ylabel} ({unit})</text>"#,
            TOP + plot_h / 2.0
        );
    }
}

/// The SVG document for one scan: points, mark points, features, axes and a legend.
pub fn svg(record: &Record, ex: &Extraction, title: &str) -> String {
    svg_with(record, ex, title, &Options::default())
}

/// [`svg`] with [`Options`]: veils, the end points' along-line σ, a fixed view and
/// exaggeration.
pub fn svg_with(record: &Record, ex: &Extraction, title: &str, opts: &Options) -> String {
    let pts: Vec<Option<(f64, f64)>> = (0..record.ranges_mm.len())
        .map(|i| record.point(i).map(|(x, y)| (f64::from(x), f64::from(y))))
        .collect();
    // Extent: the points and the scanner (features lie near their points; large circles are
    // drawn only as far as the view goes), or the view given.
    let v = opts.view.unwrap_or_else(|| extent(record, ex));
    let b = Bounds {
        x0: v.x0,
        x1: v.x1,
        y0: v.y0,
        y1: v.y1,
    };
    let c = Canvas::new(&b);
    let (scale, span, plot_w) = (c.scale, c.span, c.plot_w);
    let (sx, sy) = (|x: f64| c.sx(x), |y: f64| c.sy(y));
    let mut s = String::new();
    c.header(&mut s, title, "x, forward", "y, left");

    let _ = writeln!(s, r#"<g clip-path="url(#plot)">"#);
    // Field of view: the first and last beam as faint rays.
    let reach = span * 2.0;
    for i in [0, record.ranges_mm.len().saturating_sub(1)] {
        let a = f64::from(record.geometry.bearing(i));
        let _ = writeln!(
            s,
            r#"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="silver" stroke-dasharray="4 4"/>"#,
            sx(0.0),
            sy(0.0),
            sx(reach * a.cos()),
            sy(reach * a.sin())
        );
    }
    // Points.
    let mut d = String::new();
    for &(x, y) in pts.iter().flatten() {
        let _ = write!(d, "M{:.1},{:.1}h0", sx(x), sy(y));
    }
    let _ = writeln!(
        s,
        r#"<path d="{d}" stroke="{POINT}" stroke-width="3.2" stroke-linecap="round" fill="none"/>"#
    );
    // Uncertainty: 3σ, exaggerated by one factor for the whole plot (or the page's).
    let factor = opts.exaggeration.unwrap_or_else(|| {
        exaggeration_in(
            &View {
                x0: b.x0,
                x1: b.x1,
                y0: b.y0,
                y1: b.y1,
            },
            &ex.features,
            opts.sigma_point_mm,
        )
    });
    // Veils: mixed pixels along a line of sight, in no feature.
    let veil_pts: Vec<(f64, f64)> = opts
        .veils
        .iter()
        .filter_map(|&i| pts.get(i).copied().flatten())
        .collect();
    let mut d = String::new();
    for &(x, y) in &veil_pts {
        let _ = write!(d, "M{:.1},{:.1}m-3.5,-3.5l7,7m0,-7l-7,7", sx(x), sy(y));
    }
    if !d.is_empty() {
        let _ = writeln!(
            s,
            r#"<path d="{d}" stroke="{VEIL}" stroke-width="1.4" fill="none"/>"#
        );
    }
    // Features.
    let (mut n_lines, mut n_circles, mut n_objects) = (0, 0, 0);
    for f in &ex.features {
        match f {
            Feature::Line(l) => {
                n_lines += 1;
                // Its ±3σ band across the line over the line's own extent.
                let band: Vec<String> = line_band(l, ELLIPSE_SIGMA * factor)
                    .iter()
                    .map(|&(x, y)| format!("{:.1},{:.1}", sx(x), sy(y)))
                    .collect();
                let _ = writeln!(
                    s,
                    r#"<polygon class="band" points="{}" fill="{LINE}" fill-opacity="0.22" stroke="{LINE}" stroke-width="0.5" stroke-opacity="0.6"/>"#,
                    band.join(" ")
                );
                let _ = writeln!(
                    s,
                    r#"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="{LINE}" stroke-width="2.5" stroke-linecap="round" opacity="0.85"/>"#,
                    sx(f64::from(l.start.x)),
                    sy(f64::from(l.start.y)),
                    sx(f64::from(l.end.x)),
                    sy(f64::from(l.end.y))
                );
            }
            Feature::Circle(c) => {
                n_circles += 1;
                let (cx, cy, r) = (
                    f64::from(c.center.x),
                    f64::from(c.center.y),
                    f64::from(c.radius),
                );
                let _ = writeln!(
                    s,
                    r#"<circle cx="{:.1}" cy="{:.1}" r="{:.1}" fill="none" stroke="{CIRCLE}" stroke-width="1" stroke-dasharray="3 3"/>"#,
                    sx(cx),
                    sy(cy),
                    r * scale
                );
                let arc: Vec<String> =
                    arc_points(cx, cy, r, f64::from(c.start_angle), f64::from(c.end_angle))
                        .iter()
                        .map(|&(x, y)| format!("{:.1},{:.1}", sx(x), sy(y)))
                        .collect();
                let _ = writeln!(
                    s,
                    r#"<polyline points="{}" fill="none" stroke="{CIRCLE}" stroke-width="3" stroke-linecap="round"/>"#,
                    arc.join(" ")
                );
                let _ = writeln!(
                    s,
                    r#"<path d="M{:.1},{:.1}m-4,0h8m-4,-4v8" stroke="{CIRCLE}" stroke-width="1.5"/>"#,
                    sx(cx),
                    sy(cy)
                );
            }
            Feature::Object(o) => {
                n_objects += 1;
                // Its extent as a disc as wide (at least 3 px across), a cross at its centre
                // (its 3σ ellipse below).
                let (cx, cy) = (sx(f64::from(o.center.x)), sy(f64::from(o.center.y)));
                let r = (0.5 * f64::from(o.extent) * scale).max(1.5);
                let _ = writeln!(
                    s,
                    r#"<circle class="object" cx="{cx:.1}" cy="{cy:.1}" r="{r:.1}" fill="{OBJECT}" fill-opacity="0.35" stroke="{OBJECT}" stroke-width="1.2"/><path d="M{cx:.1},{cy:.1}m-4,-4l8,8m0,-8l-8,8" stroke="{OBJECT}" stroke-width="1.2"/>"#
                );
            }
            _ => {}
        }
    }
    // The end points' and centres' 3σ ellipses.
    let ellipses: Vec<_> = ex
        .features
        .iter()
        .flat_map(|f| {
            let colour = match f {
                Feature::Line(_) => LINE,
                Feature::Object(_) => OBJECT,
                _ => CIRCLE,
            };
            feature_ellipses(f, opts.sigma_point_mm)
                .into_iter()
                .map(move |e| (e, colour))
        })
        .collect();
    for ((x, y, e), colour) in &ellipses {
        if e.0.is_finite() && e.1.is_finite() {
            s.push_str(&ellipse_svg(sx(*x), sy(*y), *e, factor * scale, colour));
            s.push('\n');
        }
    }
    // Mark points on top; a mark no feature covers (its segment was too short to fit) grey.
    let covered = |i: usize| {
        ex.features
            .iter()
            .any(|f| (f.first()..=f.last()).contains(&i))
    };
    let mut bare = 0;
    for &i in &ex.marks {
        if opts.veils.contains(&i) {
            continue;
        }
        if let Some(Some((x, y))) = pts.get(i) {
            let colour = if covered(i) {
                MARK
            } else {
                bare += 1;
                BARE_MARK
            };
            let _ = writeln!(
                s,
                r#"<circle cx="{:.1}" cy="{:.1}" r="3.8" fill="none" stroke="{colour}" stroke-width="1.3"/>"#,
                sx(*x),
                sy(*y)
            );
        }
    }
    // Scanner.
    let (ox, oy) = (sx(0.0), sy(0.0));
    let _ = writeln!(
        s,
        r#"<path d="M{:.1},{:.1}l-14,-8v16z" fill="black"/><text x="{:.1}" y="{:.1}" font-size="11">scanner</text>"#,
        ox + 6.0,
        oy,
        ox - 8.0,
        oy + 22.0
    );
    let _ = writeln!(s, "</g>");

    // Legend, right of the plot.
    let lx = LEFT + plot_w + 20.0;
    let ly = TOP + 10.0;
    let valid = pts.iter().flatten().count();
    let entries = [
        (
            format!(
                r#"<circle cx="{:.1}" cy="{:.1}" r="1.6" fill="{POINT}"/>"#,
                lx + 12.0,
                ly
            ),
            format!("points ({valid} of {})", pts.len()),
        ),
        (
            format!(
                r#"<circle cx="{:.1}" cy="{:.1}" r="3.8" fill="none" stroke="{MARK}" stroke-width="1.3"/>"#,
                lx + 12.0,
                ly + 22.0
            ),
            format!("mark points ({})", ex.marks.len()),
        ),
        (
            format!(
                r#"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="{LINE}" stroke-width="2.5"/>"#,
                lx,
                ly + 44.0,
                lx + 24.0,
                ly + 44.0
            ),
            format!("lines ({n_lines})"),
        ),
        (
            format!(
                r#"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="{CIRCLE}" stroke-width="3"/>"#,
                lx,
                ly + 66.0,
                lx + 24.0,
                ly + 66.0
            ),
            format!("circles/arcs ({n_circles})"),
        ),
        (
            format!(
                r#"<circle cx="{:.1}" cy="{:.1}" r="5" fill="{OBJECT}" fill-opacity="0.35" stroke="{OBJECT}" stroke-width="1.2"/>"#,
                lx + 12.0,
                ly + 88.0
            ),
            format!("small objects ({n_objects}): extent"),
        ),
        (
            format!(
                r#"<ellipse cx="{:.1}" cy="{:.1}" rx="10" ry="5" fill="{LINE}" fill-opacity="0.18" stroke="{LINE}" stroke-width="0.8"/>"#,
                lx + 12.0,
                ly + 110.0
            ),
            format!("bands, ellipses: {ELLIPSE_SIGMA}σ × {factor}"),
        ),
        (
            format!(
                r#"<circle cx="{:.1}" cy="{:.1}" r="3.8" fill="none" stroke="{BARE_MARK}" stroke-width="1.3"/>"#,
                lx + 12.0,
                ly + 132.0
            ),
            format!("no feature ({bare}): segment too short"),
        ),
        (
            format!(
                r#"<path d="M{:.1},{:.1}m-3.5,-3.5l7,7m0,-7l-7,7" stroke="{VEIL}" stroke-width="1.4"/>"#,
                lx + 12.0,
                ly + 154.0
            ),
            format!("veils ({}): mixed pixels", veil_pts.len()),
        ),
    ];
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
    let g = &record.geometry;
    let _ = writeln!(
        s,
        r#"<text x="{lx:.1}" y="{:.1}" font-size="11" fill="dimgray">{} beams, {:.2}° step</text>"#,
        ly + 188.0,
        pts.len(),
        g.angle_step.to_degrees()
    );
    let _ = writeln!(
        s,
        r#"<text x="{lx:.1}" y="{:.1}" font-size="11" fill="dimgray">max range {:.1} m</text>"#,
        ly + 204.0,
        g.r_max / 1000.0
    );
    s.push_str("</svg>\n");
    s
}

fn escape(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests;
