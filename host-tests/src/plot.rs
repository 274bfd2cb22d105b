//! Hand-written SVG plots of one scan and what the extractor found in it, in the style of
//! Fig. 7 of the paper: scan points, mark points, fitted line segments and circles.
//!
//! The scanner is at the origin; x (forward) points right and y (left) points up, with equal
//! scales on both axes; ticks are in mm or m depending on the extent.
//!
//! ```
//! use host_tests::formats::Record;
//! use host_tests::methods::{Method, Pfe};
//! use pfe_core::ScanGeometry;
//! let g = ScanGeometry::LMS200_180_050;
//! let ranges: Vec<f32> = (0..361).map(|i| 2000.0 / g.bearing(i).cos().max(0.3)).collect();
//! let record = Record { id: 0, geometry: g, ranges_mm: ranges, time: None, pose: None };
//! let ex = Pfe::default_config().extract(&record.geometry, &record.ranges_mm);
//! let svg = host_tests::plot::svg(&record, &ex, "a wall");
//! assert!(svg.starts_with("<svg") && svg.contains("a wall"));
//! ```

use std::fmt::Write;

use pfe_core::Feature;

use crate::formats::Record;
use crate::methods::Extraction;

const POINT: &str = "#5a6b7d";
const MARK: &str = "#d62728";
const LINE: &str = "#1f77b4";
const CIRCLE: &str = "#e67e00";
const GRID: &str = "#e4e4e4";
const BARE_MARK: &str = "#999999";

/// Width of the plot area, px.
const PLOT_W: f64 = 820.0;
/// Largest height of the plot area, px.
const PLOT_H_MAX: f64 = 760.0;
const LEFT: f64 = 70.0;
const TOP: f64 = 44.0;
const BOTTOM: f64 = 56.0;
const LEGEND_W: f64 = 250.0;

/// Axis-aligned bounds in mm.
#[derive(Clone, Copy, Debug)]
struct Bounds {
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
}

impl Bounds {
    fn add(&mut self, x: f64, y: f64) {
        if x.is_finite() && y.is_finite() {
            self.x0 = self.x0.min(x);
            self.x1 = self.x1.max(x);
            self.y0 = self.y0.min(y);
            self.y1 = self.y1.max(y);
        }
    }
}

/// A "nice" tick step (1, 2 or 5 × 10^k) giving about `target` ticks over `span`.
fn tick_step(span: f64, target: f64) -> f64 {
    let raw = (span / target).max(1e-9);
    let mag = 10f64.powf(raw.log10().floor());
    let f = raw / mag;
    let nice = if f < 1.5 {
        1.0
    } else if f < 3.5 {
        2.0
    } else if f < 7.5 {
        5.0
    } else {
        10.0
    };
    nice * mag
}

/// Tick label for `v` mm with step `step` mm, in m when `metres`.
fn tick_label(v: f64, step: f64, metres: bool) -> String {
    // Snap to the step so that rounding never prints "-0".
    let v = (v / step).round() * step + 0.0;
    if metres {
        let decimals = if step >= 1000.0 {
            0
        } else if step >= 100.0 {
            1
        } else {
            2
        };
        let t = format!("{:.*}", decimals, v / 1000.0);
        if t.trim_start_matches(['-', '0', '.']).is_empty() {
            "0".to_string()
        } else {
            t
        }
    } else {
        let t = format!("{v:.0}");
        if t == "-0" {
            "0".to_string()
        } else {
            t
        }
    }
}

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

/// Uncertainty ellipses are drawn at this many σ.
pub const ELLIPSE_SIGMA: f64 = 3.0;

/// The ellipse `xᵀ C⁻¹ x = k²` of a 2×2 covariance `c`: semi-axes (major, minor) and the
/// major axis's angle from x, rad.
///
/// ```
/// let (a, b, th) = host_tests::plot::ellipse([[4.0, 0.0], [0.0, 1.0]], 3.0);
/// assert!((a - 6.0).abs() < 1e-12 && (b - 3.0).abs() < 1e-12 && th.abs() < 1e-12);
/// ```
pub fn ellipse(c: [[f64; 2]; 2], k: f64) -> (f64, f64, f64) {
    let (sxx, syy, sxy) = (c[0][0], c[1][1], 0.5 * (c[0][1] + c[1][0]));
    let mean = 0.5 * (sxx + syy);
    let d = (0.25 * (sxx - syy).powi(2) + sxy * sxy).sqrt();
    let (l1, l2) = (mean + d, (mean - d).max(0.0));
    let th = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    (k * l1.sqrt(), k * l2.sqrt(), th)
}

/// Covariance (mm²) of the point of the line `(α, ρ)` at signed distance `t` along it (from
/// the foot of the normal), from the covariance of (α, ρ): p = ρ n + t d with
/// n = (cos α, sin α), d = (−sin α, cos α), so ∂p/∂α = ρ d − t n and ∂p/∂ρ = n.
pub fn line_point_cov(alpha: f64, rho: f64, t: f64, c: [[f64; 2]; 2]) -> [[f64; 2]; 2] {
    let (n, d) = ((alpha.cos(), alpha.sin()), (-alpha.sin(), alpha.cos()));
    let ja = (rho * d.0 - t * n.0, rho * d.1 - t * n.1);
    let jr = n;
    let cov = |u: (f64, f64), v: (f64, f64)| {
        u.0 * v.0 * c[0][0] + (u.0 * v.1 + u.1 * v.0) * c[0][1] + u.1 * v.1 * c[1][1]
    };
    // J C Jᵀ with J's columns ja, jr: entry (i, j) = Σ J_i· C J_j·.
    let row = |i: usize| match i {
        0 => (ja.0, jr.0),
        _ => (ja.1, jr.1),
    };
    [
        [cov(row(0), row(0)), cov(row(0), row(1))],
        [cov(row(1), row(0)), cov(row(1), row(1))],
    ]
}

/// An SVG ellipse `(a, b, θ)` (data units) centred at pixel `(px, py)`, `k` pixels per unit.
fn ellipse_svg(px: f64, py: f64, (a, b, th): (f64, f64, f64), k: f64, colour: &str) -> String {
    format!(
        r#"<ellipse cx="{px:.1}" cy="{py:.1}" rx="{:.2}" ry="{:.2}" transform="rotate({:.2} {px:.1} {py:.1})" fill="{colour}" fill-opacity="0.18" stroke="{colour}" stroke-width="0.8"/>"#,
        a * k,
        b * k,
        -th.to_degrees()
    )
}

/// The ellipses of a feature: the end points of a line, the centre of a circle (data units,
/// before exaggeration).
fn feature_ellipses(f: &Feature) -> Vec<(f64, f64, (f64, f64, f64))> {
    match f {
        Feature::Line(l) => {
            let (al, rho) = (f64::from(l.alpha), f64::from(l.rho));
            let c = [
                [f64::from(l.var_alpha), f64::from(l.cov_alpha_rho)],
                [f64::from(l.cov_alpha_rho), f64::from(l.var_rho)],
            ];
            [l.start, l.end]
                .iter()
                .map(|p| {
                    let (x, y) = (f64::from(p.x), f64::from(p.y));
                    let t = -x * al.sin() + y * al.cos();
                    let e = ellipse(line_point_cov(al, rho, t, c), ELLIPSE_SIGMA);
                    (x, y, e)
                })
                .collect()
        }
        Feature::Circle(c) => {
            let cov = [
                [f64::from(c.cov[0][0]), f64::from(c.cov[0][1])],
                [f64::from(c.cov[1][0]), f64::from(c.cov[1][1])],
            ];
            vec![(
                f64::from(c.center.x),
                f64::from(c.center.y),
                ellipse(cov, ELLIPSE_SIGMA),
            )]
        }
    }
}

/// The power of ten that makes the largest ellipse at least 6 px across its major semi-axis
/// (at most 10⁴): tiny σ would be invisible at plot scale.
fn exaggeration(ellipses: &[(f64, f64, (f64, f64, f64))], scale: f64) -> f64 {
    let big = ellipses
        .iter()
        .map(|e| e.2 .0)
        .filter(|a| a.is_finite())
        .fold(0.0, f64::max);
    let mut f = 1.0;
    while big * f * scale < 6.0 && f < 1e4 && big > 0.0 {
        f *= 10.0;
    }
    f
}

/// The SVG document for one scan: points, mark points, features, axes and a legend.
pub fn svg(record: &Record, ex: &Extraction, title: &str) -> String {
    let pts: Vec<Option<(f64, f64)>> = (0..record.ranges_mm.len())
        .map(|i| record.point(i).map(|(x, y)| (f64::from(x), f64::from(y))))
        .collect();
    // Extent: the points and the scanner (features lie near their points; large circles are
    // drawn only as far as the view goes).
    let mut b = Bounds {
        x0: 0.0,
        x1: 0.0,
        y0: 0.0,
        y1: 0.0,
    };
    for &(x, y) in pts.iter().flatten() {
        b.add(x, y);
    }
    for f in &ex.features {
        if let Feature::Line(l) = f {
            b.add(f64::from(l.start.x), f64::from(l.start.y));
            b.add(f64::from(l.end.x), f64::from(l.end.y));
        }
    }
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
    let width = LEFT + plot_w + 20.0 + LEGEND_W;
    let height = TOP + plot_h + BOTTOM;
    let sx = |x: f64| LEFT + (x - x0) * scale;
    let sy = |y: f64| TOP + (y1 - y) * scale;

    let mut s = String::new();
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
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">x, forward ({unit})</text>"#,
        LEFT + plot_w / 2.0,
        TOP + plot_h + 40.0
    );
    let _ = writeln!(
        s,
        r#"<text transform="translate(18,{:.1}) rotate(-90)" text-anchor="middle">y, left ({unit})</text>"#,
        TOP + plot_h / 2.0
    );

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
    // Features.
    let (mut n_lines, mut n_circles) = (0, 0);
    for f in &ex.features {
        match f {
            Feature::Line(l) => {
                n_lines += 1;
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
        }
    }
    // Uncertainty: 3σ ellipses, exaggerated by one factor for the whole plot.
    let ellipses: Vec<_> = ex
        .features
        .iter()
        .flat_map(|f| {
            let colour = if matches!(f, Feature::Line(_)) {
                LINE
            } else {
                CIRCLE
            };
            feature_ellipses(f).into_iter().map(move |e| (e, colour))
        })
        .collect();
    let all: Vec<_> = ellipses.iter().map(|(e, _)| *e).collect();
    let factor = exaggeration(&all, scale);
    for ((x, y, e), colour) in &ellipses {
        if e.0.is_finite() && e.1.is_finite() {
            s.push_str(&ellipse_svg(sx(*x), sy(*y), *e, factor * scale, colour));
            s.push('\n');
        }
    }
    // Mark points on top; a mark no feature covers (its segment was too short to fit) grey.
    let covered = |i: usize| {
        ex.features.iter().any(|f| {
            let (a, b) = match f {
                Feature::Line(l) => (l.first, l.last),
                Feature::Circle(c) => (c.first, c.last),
            };
            (usize::from(a)..=usize::from(b)).contains(&i)
        })
    };
    let mut bare = 0;
    for &i in &ex.marks {
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
                r#"<ellipse cx="{:.1}" cy="{:.1}" rx="10" ry="5" fill="{LINE}" fill-opacity="0.18" stroke="{LINE}" stroke-width="0.8"/>"#,
                lx + 12.0,
                ly + 88.0
            ),
            format!("ellipses: {ELLIPSE_SIGMA}σ × {factor}"),
        ),
        (
            format!(
                r#"<circle cx="{:.1}" cy="{:.1}" r="3.8" fill="none" stroke="{BARE_MARK}" stroke-width="1.3"/>"#,
                lx + 12.0,
                ly + 110.0
            ),
            format!("no feature ({bare}): segment too short"),
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
        ly + 144.0,
        pts.len(),
        g.angle_step.to_degrees()
    );
    let _ = writeln!(
        s,
        r#"<text x="{lx:.1}" y="{:.1}" font-size="11" fill="dimgray">max range {:.1} m</text>"#,
        ly + 160.0,
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
mod tests {
    use super::*;

    #[test]
    fn nice_steps() {
        assert_eq!(tick_step(10_000.0, 8.0), 1000.0);
        assert_eq!(tick_step(3_000.0, 8.0), 500.0);
        assert_eq!(tick_step(1_600.0, 8.0), 200.0);
    }

    #[test]
    fn labels() {
        assert_eq!(tick_label(-1e-9, 1000.0, true), "0");
        assert_eq!(tick_label(-0.4, 200.0, false), "0");
        assert_eq!(tick_label(2500.0, 500.0, true), "2.5");
        assert_eq!(tick_label(-3000.0, 1000.0, true), "-3");
    }

    #[test]
    fn arcs_take_the_short_way() {
        let p = arc_points(0.0, 0.0, 1.0, 3.0, -3.0);
        // From 3 rad to −3 rad the short way passes through π, not 0.
        assert!(p.iter().all(|&(x, _)| x < -0.9));
    }

    #[test]
    fn ellipse_axes_match_an_analytic_covariance() {
        // C = R(θ) diag(σ1², σ2²) R(θ)ᵀ with σ1 = 5, σ2 = 2, θ = 30°.
        let (s1, s2, th) = (5.0f64, 2.0f64, 30f64.to_radians());
        let (c, s) = (th.cos(), th.sin());
        let cov = [
            [
                c * c * s1 * s1 + s * s * s2 * s2,
                c * s * (s1 * s1 - s2 * s2),
            ],
            [
                c * s * (s1 * s1 - s2 * s2),
                s * s * s1 * s1 + c * c * s2 * s2,
            ],
        ];
        let (a, b, angle) = super::ellipse(cov, 3.0);
        assert!((a - 15.0).abs() < 1e-9, "{a}");
        assert!((b - 6.0).abs() < 1e-9, "{b}");
        assert!((angle - th).abs() < 1e-9, "{angle}");
        // Isotropic: a circle.
        let (a, b, _) = super::ellipse([[4.0, 0.0], [0.0, 4.0]], 1.0);
        assert!((a - 2.0).abs() < 1e-12 && (b - 2.0).abs() < 1e-12);
    }

    #[test]
    fn line_point_cov_is_the_propagated_covariance() {
        // α = 0, point at t along the line x = ρ: p = (ρ, t) rotated; analytic J C Jᵀ.
        let (rho, t, va, vr, car) = (2000.0, 300.0, 1e-6, 4.0, 1e-4);
        let c = super::line_point_cov(0.0, rho, t, [[va, car], [car, vr]]);
        // ∂p/∂α = (−t, ρ), ∂p/∂ρ = (1, 0).
        let want = [
            [t * t * va - 2.0 * t * car + vr, -t * rho * va + rho * car],
            [-t * rho * va + rho * car, rho * rho * va],
        ];
        for i in 0..2 {
            for j in 0..2 {
                assert!((c[i][j] - want[i][j]).abs() < 1e-9, "{c:?} vs {want:?}");
            }
        }
        // Against finite differences at another angle.
        let (al, rho, t) = (0.7f64, 1500.0f64, -250.0f64);
        let p = |a: f64, r: f64| (r * a.cos() - t * a.sin(), r * a.sin() + t * a.cos());
        let h = 1e-6;
        let ja = (
            (p(al + h, rho).0 - p(al - h, rho).0) / (2.0 * h),
            (p(al + h, rho).1 - p(al - h, rho).1) / (2.0 * h),
        );
        let jr = (
            (p(al, rho + h).0 - p(al, rho - h).0) / (2.0 * h),
            (p(al, rho + h).1 - p(al, rho - h).1) / (2.0 * h),
        );
        let c = super::line_point_cov(al, rho, t, [[va, car], [car, vr]]);
        let xx = ja.0 * ja.0 * va + 2.0 * ja.0 * jr.0 * car + jr.0 * jr.0 * vr;
        let xy = ja.0 * ja.1 * va + (ja.0 * jr.1 + ja.1 * jr.0) * car + jr.0 * jr.1 * vr;
        assert!(
            (c[0][0] - xx).abs() < 1e-5 && (c[0][1] - xy).abs() < 1e-5,
            "{c:?}"
        );
    }

    #[test]
    fn the_plot_draws_uncertainty_and_explains_bare_marks() {
        use crate::formats::Record;
        use crate::methods::{Method, Pfe};
        // A wall x = 2000 from −30° to +30°, then three isolated points (a segment too short).
        let mut ranges: Vec<f32> = (0..61)
            .map(|i| 2000.0 / (f64::from(i - 30).to_radians().cos() as f32))
            .collect();
        ranges.extend([f32::NAN, f32::NAN, 900.0, f32::NAN, f32::NAN]);
        let geometry = pfe_core::ScanGeometry {
            start_angle: -30f32.to_radians(),
            angle_step: 1f32.to_radians(),
            r_max: 8000.0,
        };
        let record = Record {
            id: 0,
            geometry,
            ranges_mm: ranges,
            time: None,
            pose: None,
        };
        let mut m = Pfe::new("pfe", pfe_core::Config::default().with_sigma_r(5.0));
        let ex = m.extract(&record.geometry, &record.ranges_mm);
        assert_eq!(ex.features.len(), 1, "{:?}", ex.features);
        let svg = super::svg(&record, &ex, "t");
        assert_eq!(
            svg.matches("<ellipse").count(),
            2 + 1,
            "two end points + legend icon"
        );
        assert!(svg.contains("ellipses: 3σ × "), "{svg}");
        assert!(svg.contains("no feature (1): segment too short"), "{svg}");
    }
}
