//! A round object that is not quite a circle (a pillar of 8–12 flat faces) is typed as a
//! circle, whose fitted centre then depends on the side the scanner sees: the centres of one
//! object seen from many directions and distances must scatter as their covariances say,
//! as they do for a true circle. Rays are cast exactly (independent of pfe-core).
//!
//! (An ellipse is the case this cannot cover: half of one fits a circle within the noise, of
//! a radius that depends on the side seen, so nothing in one scan shows that its centre
//! moves; see docs/TESTING.md.)
#![allow(clippy::indexing_slicing, clippy::unwrap_used)]

use pfe_core::{Config, Extractor, Feature, Scan, ScanGeometry};

const SIGMA: f64 = 5.0;
const VIEWS: usize = 600;

/// Deterministic N(0, 1) and U(0, 1) draws (xorshift and Box–Muller).
struct Noise(u64);

impl Noise {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn gauss(&mut self) -> f64 {
        let (u, v) = (self.uniform().max(1e-300), self.uniform());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

/// Range along the ray at `bearing` to the circle centred at `c` of radius `r`; NaN when the
/// ray misses it.
fn circle_range(bearing: f64, c: [f64; 2], r: f64) -> f64 {
    let (dx, dy) = (bearing.cos(), bearing.sin());
    let b = dx * c[0] + dy * c[1];
    let disc = b * b - (c[0] * c[0] + c[1] * c[1] - r * r);
    if disc < 0.0 {
        f64::NAN
    } else {
        b - disc.sqrt()
    }
}

/// Range along the ray at `bearing` to the regular polygon of `sides` sides centred at `c`,
/// circumradius `r`, a corner at angle `phi`; NaN when the ray misses it.
fn polygon_range(bearing: f64, c: [f64; 2], r: f64, sides: usize, phi: f64) -> f64 {
    let (dx, dy) = (bearing.cos(), bearing.sin());
    let corner = |k: usize| {
        let t = phi + std::f64::consts::TAU * k as f64 / sides as f64;
        [c[0] + r * t.cos(), c[1] + r * t.sin()]
    };
    let mut best = f64::NAN;
    for k in 0..sides {
        let (p, q) = (corner(k), corner(k + 1));
        let (ex, ey) = (q[0] - p[0], q[1] - p[1]);
        let den = dx * ey - dy * ex;
        if den.abs() < 1e-12 {
            continue;
        }
        let t = (p[0] * ey - p[1] * ex) / den;
        let s = (p[0] * dy - p[1] * dx) / den;
        if t > 0.0 && (0.0..=1.0).contains(&s) && (best.is_nan() || t < best) {
            best = t;
        }
    }
    best
}

/// A round object: a circle (radius) or a regular polygon (circumradius, sides).
#[derive(Clone, Copy, Debug)]
enum Shape {
    Circle(f64),
    Polygon(f64, usize),
}

/// The centre error (fitted − true) and stated centre covariance of the one circle found on
/// `shape`, turned at random, at `VIEWS` places 1.5–3 m ahead within ±0.5 rad; views where
/// the extractor finds no circle or several are left out.
fn views(shape: Shape, seed: u64) -> Vec<([f64; 2], [[f64; 2]; 2])> {
    let g = ScanGeometry::LMS200_180_050;
    let config = Config::default().with_sigma_r(SIGMA as f32);
    let mut noise = Noise(seed);
    let mut ex = Extractor::<361, 16>::new();
    let mut out = Vec::new();
    for _ in 0..VIEWS {
        let (d, bearing) = (1500.0 + 1500.0 * noise.uniform(), noise.uniform() - 0.5);
        let c = [d * bearing.cos(), d * bearing.sin()];
        let phi = std::f64::consts::PI * noise.uniform();
        let ranges: Vec<f32> = (0..361)
            .map(|i| {
                let bearing = f64::from(g.bearing(i));
                let r = match shape {
                    Shape::Circle(r) => circle_range(bearing, c, r),
                    Shape::Polygon(r, n) => polygon_range(bearing, c, r, n, phi),
                };
                (r + SIGMA * noise.gauss()) as f32
            })
            .collect();
        ex.extract(&Scan::from_mm(g, &ranges), &config).unwrap();
        let circles: Vec<_> = ex
            .features()
            .iter()
            .filter_map(|f| match f {
                Feature::Circle(c) => Some(c),
                _ => None,
            })
            .collect();
        if let [cf] = circles[..] {
            let e = [f64::from(cf.center.x) - c[0], f64::from(cf.center.y) - c[1]];
            let cov = [
                [f64::from(cf.cov[0][0]), f64::from(cf.cov[0][1])],
                [f64::from(cf.cov[1][0]), f64::from(cf.cov[1][1])],
            ];
            out.push((e, cov));
        }
    }
    out
}

/// Median NIS of the differences of consecutive views' centres with both covariances: what
/// the real-data benchmark measures between scans (χ²₂ median 1.39 when consistent).
fn pair_nis(v: &[([f64; 2], [[f64; 2]; 2])]) -> f64 {
    let mut nis: Vec<f64> = v
        .windows(2)
        .map(|w| {
            let (d, s) = (
                [w[0].0[0] - w[1].0[0], w[0].0[1] - w[1].0[1]],
                [
                    [w[0].1[0][0] + w[1].1[0][0], w[0].1[0][1] + w[1].1[0][1]],
                    [w[0].1[1][0] + w[1].1[1][0], w[0].1[1][1] + w[1].1[1][1]],
                ],
            );
            let det = s[0][0] * s[1][1] - s[0][1] * s[1][0];
            (s[1][1] * d[0] * d[0] - 2.0 * s[0][1] * d[0] * d[1] + s[0][0] * d[1] * d[1]) / det
        })
        .collect();
    nis.sort_by(f64::total_cmp);
    nis[nis.len() / 2]
}

#[test]
fn a_true_circles_centre_scatters_as_stated() {
    let v = views(Shape::Circle(250.0), 7);
    let nis = pair_nis(&v);
    assert!(
        v.len() == VIEWS && (1.1..1.7).contains(&nis),
        "{} {nis}",
        v.len()
    );
}

#[test]
fn a_pillar_of_flat_faces_centre_scatters_as_stated() {
    // Without the covariance's scatter and correlation terms: 2.61, 1.89, 1.64, 2.00, 1.61.
    for shape in [
        Shape::Polygon(250.0, 8),
        Shape::Polygon(250.0, 10),
        Shape::Polygon(250.0, 12),
        Shape::Polygon(150.0, 8),
        Shape::Polygon(150.0, 10),
    ] {
        let v = views(shape, 7);
        let nis = pair_nis(&v);
        assert!(
            v.len() >= 400 && (0.45..1.9).contains(&nis),
            "{shape:?}: {} views, pair NIS median {nis}",
            v.len()
        );
    }
}
