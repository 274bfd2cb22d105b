//! Hand-written grouped bar charts of the real-data benchmark (no plotting crate).

use std::fmt::Write as _;

use crate::svg::{esc, fmt_tick, nice_ceiling, COLORS};

/// Bars of every series (`name`, one value per group) side by side in each group; y linear
/// from 0, or logarithmic (`log_y`, values ≤ 0 or NaN not drawn); a dashed line at
/// `reference` when given.
pub fn grouped_bars(
    title: &str,
    ylabel: &str,
    groups: &[String],
    series: &[(String, Vec<f64>)],
    reference: Option<(f64, &str)>,
    log_y: bool,
) -> String {
    let (w, h) = (900.0f64, 380.0f64);
    let (l, r, t, b) = (60.0, 150.0, 30.0, 70.0);
    let (pw, ph) = (w - l - r, h - t - b);
    let values = series
        .iter()
        .flat_map(|s| s.1.iter().copied())
        .chain(reference.map(|r| r.0))
        .filter(|v| v.is_finite() && (*v > 0.0 || !log_y));
    let (lo, hi) = if log_y {
        let (mn, mx) = values.fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
        let lo = if mn.is_finite() {
            mn.log10().floor()
        } else {
            -1.0
        };
        (lo, (mx.max(10f64.powf(lo + 1.0))).log10().ceil())
    } else {
        (0.0, nice_ceiling(values.fold(0.0f64, f64::max)))
    };
    let y_of = |v: f64| {
        let u = if log_y { v.log10() } else { v };
        t + ph * (1.0 - ((u - lo) / (hi - lo)).clamp(0.0, 1.0))
    };
    let mut out = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif"><rect width="100%" height="100%" fill="white"/>"#
    );
    let _ = write!(
        out,
        r#"<text x="{l}" y="18" font-size="13" font-weight="bold">{}</text><text x="14" y="{:.1}" font-size="11" transform="rotate(-90 14 {:.1})" text-anchor="middle">{}</text>"#,
        esc(title),
        t + ph / 2.0,
        t + ph / 2.0,
        esc(ylabel)
    );
    let ticks: Vec<f64> = if log_y {
        (lo as i32..=hi as i32).map(|e| 10f64.powi(e)).collect()
    } else {
        (0..=4).map(|k| hi * f64::from(k) / 4.0).collect()
    };
    for v in ticks {
        let y = y_of(v);
        let _ = write!(
            out,
            r##"<line x1="{l}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#eee"/><text x="{:.1}" y="{:.1}" font-size="10" text-anchor="end">{}</text>"##,
            l + pw,
            l - 4.0,
            y + 3.0,
            fmt_tick(v)
        );
    }
    let gw = pw / groups.len().max(1) as f64;
    let bw = gw * 0.8 / series.len().max(1) as f64;
    for (g, name) in groups.iter().enumerate() {
        let x0 = l + gw * g as f64 + gw * 0.1;
        for (k, (_, ys)) in series.iter().enumerate() {
            let v = ys.get(g).copied().unwrap_or(f64::NAN);
            if !v.is_finite() || (log_y && v <= 0.0) {
                continue;
            }
            let y = y_of(v);
            let base = if log_y { t + ph } else { y_of(0.0) };
            let _ = write!(
                out,
                r#"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="{}"><title>{}: {v:.3}</title></rect>"#,
                x0 + bw * k as f64,
                y.min(base),
                (bw - 1.0).max(0.5),
                (base - y).abs(),
                COLORS[k % COLORS.len()],
                esc(name)
            );
        }
        let xc = l + gw * (g as f64 + 0.5);
        let _ = write!(
            out,
            r#"<text x="{xc:.1}" y="{:.1}" font-size="10" text-anchor="end" transform="rotate(-30 {xc:.1} {:.1})">{}</text>"#,
            t + ph + 14.0,
            t + ph + 14.0,
            esc(name)
        );
    }
    if let Some((v, label)) = reference {
        let y = y_of(v);
        let _ = write!(
            out,
            r##"<line x1="{l}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#333" stroke-dasharray="5,4"/><text x="{:.1}" y="{:.1}" font-size="10">{}</text>"##,
            l + pw,
            l + pw + 4.0,
            y + 3.0,
            esc(label)
        );
    }
    let _ = write!(
        out,
        r##"<rect x="{l}" y="{t}" width="{pw:.1}" height="{ph:.1}" fill="none" stroke="#888"/>"##
    );
    for (k, (name, _)) in series.iter().enumerate() {
        let y = t + 20.0 + 16.0 * k as f64;
        let _ = write!(
            out,
            r#"<rect x="{:.1}" y="{:.1}" width="12" height="10" fill="{}"/><text x="{:.1}" y="{:.1}" font-size="11">{}</text>"#,
            l + pw + 12.0,
            y - 9.0,
            COLORS[k % COLORS.len()],
            l + pw + 28.0,
            y,
            esc(name)
        );
    }
    out.push_str("</svg>\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_one_bar_per_finite_value() {
        let svg = grouped_bars(
            "t",
            "y",
            &["a".into(), "b".into()],
            &[
                ("m1".into(), vec![1.0, 2.0]),
                ("m2".into(), vec![f64::NAN, 10.0]),
            ],
            Some((1.39, "χ²₂ median")),
            true,
        );
        assert!(svg.starts_with("<svg") && svg.ends_with("</svg>\n"));
        assert_eq!(svg.matches("<title>").count(), 3);
    }
}
