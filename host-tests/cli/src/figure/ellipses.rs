//! Uncertainty ellipses of features, drawn exaggerated to be visible.

use pfe_core::Feature;

/// Uncertainty ellipses are drawn at this many σ.
pub const ELLIPSE_SIGMA: f64 = 3.0;

/// The ellipse `xᵀ C⁻¹ x = k²` of a 2×2 covariance `c`: semi-axes (major, minor) and the
/// major axis's angle from x, rad.
///
/// ```
/// let (a, b, th) = pfe_cli::figure::ellipse([[4.0, 0.0], [0.0, 1.0]], 3.0);
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
pub(super) fn ellipse_svg(
    px: f64,
    py: f64,
    (a, b, th): (f64, f64, f64),
    k: f64,
    colour: &str,
) -> String {
    format!(
        r#"<ellipse cx="{px:.1}" cy="{py:.1}" rx="{:.2}" ry="{:.2}" transform="rotate({:.2} {px:.1} {py:.1})" fill="{colour}" fill-opacity="0.18" stroke="{colour}" stroke-width="0.8"/>"#,
        a * k,
        b * k,
        -th.to_degrees()
    )
}

/// The ellipses of a feature: the end points of a line, the centre of a circle or of a small
/// object (data units, before exaggeration).
pub(super) fn feature_ellipses(f: &Feature) -> Vec<(f64, f64, (f64, f64, f64))> {
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
        Feature::Object(o) => {
            let cov = [
                [f64::from(o.cov[0][0]), f64::from(o.cov[0][1])],
                [f64::from(o.cov[1][0]), f64::from(o.cov[1][1])],
            ];
            vec![(
                f64::from(o.center.x),
                f64::from(o.center.y),
                ellipse(cov, ELLIPSE_SIGMA),
            )]
        }
        _ => Vec::new(),
    }
}

/// The power of ten that makes the largest ellipse at least 6 px across its major semi-axis
/// (at most 10⁴): tiny σ would be invisible at plot scale.
pub(super) fn exaggeration(ellipses: &[(f64, f64, (f64, f64, f64))], scale: f64) -> f64 {
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
