//! Uncertainty ellipses of features, drawn exaggerated to be visible.

use pfe_core::{Feature, LineFeature};

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

/// The perpendicular σ (mm) of the line `l` at signed distance `t` along it from the foot of
/// its normal: σ(t)² = σ_ρ² + t²σ_α² − 2t·cov(α, ρ) (the point of the line at `t` moves only
/// across the line when α and ρ vary, to first order).
pub fn line_sigma_at(l: &LineFeature, t: f64) -> f64 {
    (f64::from(l.var_rho) + t * t * f64::from(l.var_alpha) - 2.0 * t * f64::from(l.cov_alpha_rho))
        .max(0.0)
        .sqrt()
}

/// The normal `n` and direction `d` of line `l`, and the positions `t` along `d` of its
/// start and end (from the foot of the normal).
pub(super) fn line_frame(l: &LineFeature) -> ((f64, f64), (f64, f64), f64, f64) {
    let al = f64::from(l.alpha);
    let (n, d) = ((al.cos(), al.sin()), (-al.sin(), al.cos()));
    let along = |p: &pfe_core::Point| f64::from(p.x) * d.0 + f64::from(p.y) * d.1;
    (n, d, along(&l.start), along(&l.end))
}

/// Covariance (mm²) of an end point `p` of line `l`: the projection of a measured point on
/// the line, so across the line the line's own σ at `p` ([`line_sigma_at`]) and along it the
/// measured point's range noise `sigma_point` (mm, along its beam) projected on the line.
///
/// ```
/// use pfe_core::{LineFeature, Point};
/// // x = 2000 seen from y = 0 to 1000; σ_ρ = 5 mm, σ_α = 0.01 rad.
/// let l = LineFeature::new(0, 9, 10, 0.0, 2000.0, 1e-4, 25.0, 0.0,
///     Point::new(2000.0, 0.0), Point::new(2000.0, 1000.0));
/// let c = pfe_cli::figure::end_point_cov(&l, &l.end, 10.0);
/// // Across (x): 25 + 1000²·1e-4 = 125 mm²; along (y): 10² · sin²(26.6°) = 20 mm².
/// assert!((c[0][0] - 125.0).abs() < 1e-3 && (c[1][1] - 20.0).abs() < 1e-3, "{c:?}");
/// ```
pub fn end_point_cov(l: &LineFeature, p: &pfe_core::Point, sigma_point: f64) -> [[f64; 2]; 2] {
    let (n, d, _, _) = line_frame(l);
    let (x, y) = (f64::from(p.x), f64::from(p.y));
    let t = x * d.0 + y * d.1;
    let across = line_sigma_at(l, t).powi(2);
    let r = x.hypot(y);
    let cos_bd = if r > 0.0 {
        (x * d.0 + y * d.1) / r
    } else {
        0.0
    };
    let along = (sigma_point * cos_bd).powi(2);
    [
        [
            across * n.0 * n.0 + along * d.0 * d.0,
            across * n.0 * n.1 + along * d.0 * d.1,
        ],
        [
            across * n.0 * n.1 + along * d.0 * d.1,
            across * n.1 * n.1 + along * d.1 * d.1,
        ],
    ]
}

/// The ±`k`σ band of line `l` over its own extent, `k` including any exaggeration: a closed
/// polygon (mm) along one side from start to end, back along the other. Every vertex lies
/// between the start and the end along the line, at most `k` · σ(t) across it.
pub fn line_band(l: &LineFeature, k: f64) -> Vec<(f64, f64)> {
    const STEPS: usize = 16;
    let (n, d, t0, t1) = line_frame(l);
    let rho = f64::from(l.rho);
    let at = |t: f64, s: f64| (n.0 * (rho + s) + d.0 * t, n.1 * (rho + s) + d.1 * t);
    let ts: Vec<f64> = (0..=STEPS)
        .map(|i| t0 + (t1 - t0) * i as f64 / STEPS as f64)
        .collect();
    let mut band: Vec<(f64, f64)> = ts.iter().map(|&t| at(t, k * line_sigma_at(l, t))).collect();
    band.extend(ts.iter().rev().map(|&t| at(t, -k * line_sigma_at(l, t))));
    band
}

/// The ellipses of a feature: the end points of a line ([`end_point_cov`], `sigma_point` the
/// range noise of one point, mm), the centre of a circle or of a small object (data units,
/// before exaggeration).
pub(super) fn feature_ellipses(f: &Feature, sigma_point: f64) -> Vec<(f64, f64, (f64, f64, f64))> {
    match f {
        Feature::Line(l) => [l.start, l.end]
            .iter()
            .map(|p| {
                let e = ellipse(end_point_cov(l, p, sigma_point), ELLIPSE_SIGMA);
                (f64::from(p.x), f64::from(p.y), e)
            })
            .collect(),
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
