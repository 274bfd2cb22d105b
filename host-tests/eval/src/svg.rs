//! Hand-written SVG plots of the evaluation (no plotting crate).

use super::{Evaluation, Level};
use crate::report::{crb_summary, errors, EFFICIENT_Z};
use std::fmt::Write as _;

/// Colours of the methods, in order.
pub(crate) const COLORS: [&str; 6] = [
    "#d62728", "#1f77b4", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b",
];

/// One curve.
struct Series {
    name: String,
    color: &'static str,
    dashed: bool,
    ys: Vec<f64>,
}

/// `s` with `&`, `<` and `>` escaped for SVG text.
pub(crate) fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// A line chart panel at (`x0`, `y0`) of `w × h` px; x and y linear, y from 0.
fn panel(
    out: &mut String,
    at: (f64, f64),
    size: (f64, f64),
    title: &str,
    xlabel: &str,
    xs: &[f64],
    series: &[Series],
) {
    let ((x0, y0), (w, h)) = (at, size);
    let (l, r, t, b) = (55.0, 10.0, 25.0, 40.0);
    let (pw, ph) = (w - l - r, h - t - b);
    let xmax = xs.iter().copied().fold(0.0f64, f64::max).max(1e-9);
    let ymax_raw = series
        .iter()
        .flat_map(|s| s.ys.iter().copied())
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max);
    let ymax = nice_ceiling(ymax_raw);
    let px = |x: f64| x0 + l + pw * x / xmax;
    let py = |y: f64| y0 + t + ph * (1.0 - y / ymax);
    let _ = write!(
        out,
        r#"<text x="{:.1}" y="{:.1}" font-size="13" font-weight="bold">{}</text>"#,
        x0 + l,
        y0 + 16.0,
        esc(title)
    );
    let _ = write!(
        out,
        r##"<rect x="{:.1}" y="{:.1}" width="{pw:.1}" height="{ph:.1}" fill="none" stroke="#888"/>"##,
        x0 + l,
        y0 + t
    );
    for k in 0..=4 {
        let y = ymax * f64::from(k) / 4.0;
        let _ = write!(
            out,
            r##"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#eee"/><text x="{:.1}" y="{:.1}" font-size="10" text-anchor="end">{}</text>"##,
            px(0.0),
            py(y),
            px(xmax),
            py(y),
            x0 + l - 4.0,
            py(y) + 3.0,
            fmt_tick(y)
        );
    }
    for &x in xs {
        let _ = write!(
            out,
            r#"<text x="{:.1}" y="{:.1}" font-size="10" text-anchor="middle">{}</text>"#,
            px(x),
            y0 + t + ph + 14.0,
            fmt_tick(x)
        );
    }
    let _ = write!(
        out,
        r#"<text x="{:.1}" y="{:.1}" font-size="11" text-anchor="middle">{}</text>"#,
        x0 + l + pw / 2.0,
        y0 + h - 6.0,
        esc(xlabel)
    );
    for s in series {
        let pts: Vec<String> = xs
            .iter()
            .zip(&s.ys)
            .filter(|(_, y)| y.is_finite())
            .map(|(x, y)| format!("{:.1},{:.1}", px(*x), py(*y)))
            .collect();
        let dash = if s.dashed {
            r#" stroke-dasharray="5,4""#
        } else {
            ""
        };
        let _ = write!(
            out,
            r#"<polyline points="{}" fill="none" stroke="{}" stroke-width="2"{dash}/>"#,
            pts.join(" "),
            s.color
        );
        for p in &pts {
            let mut it = p.split(',');
            if let (Some(x), Some(y)) = (it.next(), it.next()) {
                let _ = write!(
                    out,
                    r#"<circle cx="{x}" cy="{y}" r="2.5" fill="{}"/>"#,
                    s.color
                );
            }
        }
    }
}

fn legend(out: &mut String, x: f64, y: f64, series: &[Series]) {
    for (i, s) in series.iter().enumerate() {
        let yy = y + 16.0 * i as f64;
        let dash = if s.dashed {
            r#" stroke-dasharray="5,4""#
        } else {
            ""
        };
        let _ = write!(
            out,
            r#"<line x1="{x:.1}" y1="{yy:.1}" x2="{:.1}" y2="{yy:.1}" stroke="{}" stroke-width="2"{dash}/><text x="{:.1}" y="{:.1}" font-size="11">{}</text>"#,
            x + 22.0,
            s.color,
            x + 27.0,
            yy + 4.0,
            esc(&s.name)
        );
    }
}

/// The least of 1, 2, 2.5, 5 or 10 times a power of ten that is at least `v` (1 for NaN or ≤ 0).
pub(crate) fn nice_ceiling(v: f64) -> f64 {
    if v.is_nan() || v <= 0.0 {
        return 1.0;
    }
    let p = 10f64.powf(v.log10().floor());
    for m in [1.0, 2.0, 2.5, 5.0, 10.0] {
        if v <= m * p {
            return m * p;
        }
    }
    10.0 * p
}

/// An axis label: `v` to 3 decimals without trailing zeros.
pub(crate) fn fmt_tick(v: f64) -> String {
    let s = format!("{v:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s.is_empty() || s == "-" {
        "0".to_string()
    } else {
        s.to_string()
    }
}

fn svg_open(w: f64, h: f64) -> String {
    format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif"><rect width="100%" height="100%" fill="white"/>"#
    )
}

fn method_series(sweep: &[Level], metric: impl Fn(&super::MethodResult) -> f64) -> Vec<Series> {
    let names: Vec<String> = sweep
        .first()
        .map(|l| l.results.iter().map(|r| r.name.clone()).collect())
        .unwrap_or_default();
    names
        .iter()
        .enumerate()
        .map(|(i, name)| Series {
            name: name.clone(),
            color: COLORS[i % COLORS.len()],
            dashed: false,
            ys: sweep
                .iter()
                .map(|l| l.results.get(i).map_or(f64::NAN, &metric))
                .collect(),
        })
        .collect()
}

/// Median line |Δρ| and circle centre error against σ_r, per method, with what an efficient
/// estimator would reach (0.674 × the median CRB σ: the median of a Gaussian's |error|).
pub fn errors_vs_noise(ev: &Evaluation) -> String {
    let xs: Vec<f64> = ev.sweep.iter().map(|l| f64::from(l.sigma)).collect();
    let crb = |k: usize| Series {
        name: "CRB: efficient median |error|".to_string(),
        color: "#000",
        dashed: true,
        ys: ev
            .sweep
            .iter()
            .map(|l| EFFICIENT_Z.0 * crb_summary(l)[k].0)
            .collect(),
    };
    let mut rho = method_series(&ev.sweep, |r| errors(r).rho.0);
    rho.push(crb(0));
    let mut ctr = method_series(&ev.sweep, |r| errors(r).center.0);
    ctr.push(crb(2));
    let mut out = svg_open(900.0, 340.0);
    panel(
        &mut out,
        (0.0, 0.0),
        (360.0, 340.0),
        "Line: median |Δρ| (mm)",
        "σ_r (mm)",
        &xs,
        &rho,
    );
    panel(
        &mut out,
        (360.0, 0.0),
        (360.0, 340.0),
        "Circle: median centre error (mm)",
        "σ_r (mm)",
        &xs,
        &ctr,
    );
    legend(&mut out, 735.0, 40.0, &rho);
    out.push_str("</svg>\n");
    out
}

/// FalseMarkRatio and (missed + spurious) / truth against σ_r, per method.
pub fn ratios_vs_noise(ev: &Evaluation) -> String {
    let xs: Vec<f64> = ev.sweep.iter().map(|l| f64::from(l.sigma)).collect();
    let fm = method_series(&ev.sweep, |r| r.score.false_mark_ratio());
    let ms = method_series(&ev.sweep, |r| {
        r.score.missed_ratio() + r.score.spurious_ratio()
    });
    let fi = method_series(&ev.sweep, |r| r.score.false_iden_ratio());
    let mut out = svg_open(1200.0, 340.0);
    panel(
        &mut out,
        (0.0, 0.0),
        (340.0, 340.0),
        "FalseMarkRatio",
        "σ_r (mm)",
        &xs,
        &fm,
    );
    panel(
        &mut out,
        (340.0, 0.0),
        (340.0, 340.0),
        "FalseIdenRatio",
        "σ_r (mm)",
        &xs,
        &fi,
    );
    panel(
        &mut out,
        (680.0, 0.0),
        (340.0, 340.0),
        "(missed + spurious) / truth",
        "σ_r (mm)",
        &xs,
        &ms,
    );
    legend(&mut out, 1035.0, 40.0, &fm);
    out.push_str("</svg>\n");
    out
}

/// Mean execution time per scan at the main σ, one bar per method.
pub fn time_per_scan(ev: &Evaluation) -> String {
    let rs = &ev.main.results;
    let bar_h = 26.0;
    let (l, w) = (110.0, 600.0);
    let h = 50.0 + bar_h * rs.len() as f64 + 30.0;
    let tmax = nice_ceiling(
        rs.iter()
            .map(|r| r.time_per_scan.as_secs_f64() * 1e6)
            .fold(0.0, f64::max),
    );
    let mut out = svg_open(w, h);
    let _ = write!(
        out,
        r#"<text x="{l}" y="20" font-size="13" font-weight="bold">Mean time per scan (µs, release, host CPU; σ_r = {} mm)</text>"#,
        ev.main.sigma
    );
    let pw = w - l - 60.0;
    for (i, r) in rs.iter().enumerate() {
        let t = r.time_per_scan.as_secs_f64() * 1e6;
        let y = 35.0 + bar_h * i as f64;
        let bw = pw * t / tmax;
        let _ = write!(
            out,
            r#"<text x="{:.1}" y="{:.1}" font-size="11" text-anchor="end">{}</text><rect x="{l}" y="{y:.1}" width="{bw:.1}" height="{:.1}" fill="{}"/><text x="{:.1}" y="{:.1}" font-size="11">{t:.1}</text>"#,
            l - 6.0,
            y + bar_h / 2.0 + 4.0,
            esc(&r.name),
            bar_h - 6.0,
            COLORS[i % COLORS.len()],
            l + bw + 4.0,
            y + bar_h / 2.0 + 4.0
        );
    }
    out.push_str("</svg>\n");
    out
}

/// A single line chart (`title`, x axis `xlabel` at `xs`) of named curves, y from 0.
pub fn line_chart(title: &str, xlabel: &str, xs: &[f64], curves: &[(String, Vec<f64>)]) -> String {
    let series: Vec<Series> = curves
        .iter()
        .enumerate()
        .map(|(i, (name, ys))| Series {
            name: name.clone(),
            color: COLORS[i % COLORS.len()],
            dashed: false,
            ys: ys.clone(),
        })
        .collect();
    let (w, h) = (640.0, 340.0);
    let mut out = svg_open(w, h);
    panel(
        &mut out,
        (0.0, 0.0),
        (w - 150.0, h),
        title,
        xlabel,
        xs,
        &series,
    );
    legend(&mut out, w - 140.0, 40.0, &series);
    out.push_str("</svg>\n");
    out
}

/// One scan of each concrete scene kind side by side ([`crate::scene::SimScan::to_svg`]).
pub fn scene_gallery(seed: u64, sigma: f32) -> String {
    use crate::scene::{Scenario, SceneKind};
    let size = 420.0;
    let kinds = SceneKind::CONCRETE;
    let w = size * kinds.len() as f64;
    let mut out = svg_open(w, size + 24.0);
    for (i, k) in kinds.iter().enumerate() {
        let sim = Scenario::new(*k, super::scan_seed(seed, i))
            .with_sigma(sigma)
            .simulate();
        let x = size * i as f64;
        let body = sim.to_svg(size);
        let inner = body
            .split_once('>')
            .map_or("", |(_, rest)| rest)
            .trim_end()
            .trim_end_matches("</svg>");
        let _ = write!(
            out,
            r##"<svg x="{x}" y="24" width="{size}" height="{size}">{inner}</svg><text x="{:.1}" y="17" font-size="13" font-weight="bold">{} ({} truth features)</text><rect x="{x}" y="24" width="{size}" height="{size}" fill="none" stroke="#888"/>"##,
            x + 8.0,
            k.name(),
            sim.truth.len()
        );
    }
    out.push_str("</svg>\n");
    out
}
