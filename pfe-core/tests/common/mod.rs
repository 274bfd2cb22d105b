//! Exact ray casting of walls and circles for the analytic tests (independent of pfe-core), and
//! a filter of extracted features by beam range.
#![allow(clippy::indexing_slicing)]
#![allow(dead_code)]

/// A primitive of an analytic scene, in mm.
#[derive(Clone, Copy, Debug)]
pub enum Prim {
    /// Segment from (x0, y0) to (x1, y1).
    Seg(f64, f64, f64, f64),
    /// Circle centre (cx, cy), radius.
    Circle(f64, f64, f64),
}

/// Nearest hit of the ray from the origin at `bearing` (rad): (range, primitive index).
pub fn cast(prims: &[Prim], bearing: f64) -> Option<(f64, usize)> {
    let (dx, dy) = (bearing.cos(), bearing.sin());
    let mut best: Option<(f64, usize)> = None;
    for (i, p) in prims.iter().enumerate() {
        let t = match *p {
            Prim::Seg(x0, y0, x1, y1) => {
                let (ex, ey) = (x1 - x0, y1 - y0);
                let den = dx * ey - dy * ex;
                if den.abs() < 1e-12 {
                    None
                } else {
                    let t = (x0 * ey - y0 * ex) / den;
                    let s = (x0 * dy - y0 * dx) / den;
                    (t > 0.0 && (0.0..=1.0).contains(&s)).then_some(t)
                }
            }
            Prim::Circle(cx, cy, r) => {
                let b = dx * cx + dy * cy;
                let c = cx * cx + cy * cy - r * r;
                let disc = b * b - c;
                if disc < 0.0 {
                    None
                } else {
                    let t = b - disc.sqrt();
                    (t > 0.0).then_some(t)
                }
            }
        };
        if let Some(t) = t {
            if best.is_none_or(|(bt, _)| t < bt) {
                best = Some((t, i));
            }
        }
    }
    best
}

/// Ranges (mm, NaN = no return) and the primitive hit by each beam.
pub fn scan(
    prims: &[Prim],
    start: f64,
    step: f64,
    n: usize,
    r_max: f64,
) -> (Vec<f32>, Vec<Option<usize>>) {
    (0..n)
        .map(|i| match cast(prims, start + step * i as f64) {
            Some((t, p)) if t <= r_max => (t as f32, Some(p)),
            _ => (f32::NAN, None),
        })
        .unzip()
}

/// Ground-truth runs of ≥ `min` consecutive beams on one primitive: (first, last, primitive).
pub fn runs(hits: &[Option<usize>], min: usize) -> Vec<(usize, usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < hits.len() {
        let Some(p) = hits[i] else {
            i += 1;
            continue;
        };
        let mut j = i;
        while j + 1 < hits.len() && hits[j + 1] == Some(p) {
            j += 1;
        }
        if j + 1 - i >= min {
            out.push((i, j, p));
        }
        i = j + 1;
    }
    out
}

/// Small deterministic Gaussian noise source (Box–Muller over a xorshift), so tests need no
/// extra crates and give the same numbers everywhere.
pub struct Noise(u64);

impl Noise {
    pub fn new(seed: u64) -> Self {
        Noise(seed.wrapping_mul(0x9E3779B97F4A7C15) | 1)
    }
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    pub fn gauss(&mut self) -> f64 {
        let (u1, u2) = (self.uniform(), self.uniform());
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}

/// The features that cover any beam of `first..=last`.
pub fn overlapping(
    features: &[pfe_core::Feature],
    first: usize,
    last: usize,
) -> Vec<&pfe_core::Feature> {
    features
        .iter()
        .filter(|f| f.last() >= first && f.first() <= last)
        .collect()
}

/// A room 5–9 × 4–7 m seen from a random pose inside it (`noise` draws the size, the pose and
/// a pillar): its four walls as segments, then the pillar, in the scanner's frame.
pub fn room(noise: &mut Noise) -> Vec<Prim> {
    let u = |n: &mut Noise| n.gauss().clamp(-2.0, 2.0) / 4.0 + 0.5;
    let (w, h) = (5000.0 + 4000.0 * u(noise), 4000.0 + 3000.0 * u(noise));
    let (x, y) = (w * (0.3 + 0.3 * u(noise)), h * (0.3 + 0.4 * u(noise)));
    let th = 3.0 * (u(noise) - 0.5);
    let (s, c) = th.sin_cos();
    let local = |px: f64, py: f64| {
        let (dx, dy) = (px - x, py - y);
        (c * dx + s * dy, -s * dx + c * dy)
    };
    let corners = [(0.0, 0.0), (w, 0.0), (w, h), (0.0, h)];
    let mut prims: Vec<Prim> = (0..4)
        .map(|k| {
            let (a, b) = (
                local(corners[k].0, corners[k].1),
                local(corners[(k + 1) % 4].0, corners[(k + 1) % 4].1),
            );
            Prim::Seg(a.0, a.1, b.0, b.1)
        })
        .collect();
    let (px, py) = local(x + 0.5 * (w - x) * u(noise) + 800.0, y + 600.0);
    prims.push(Prim::Circle(px, py, 150.0 + 150.0 * u(noise)));
    prims
}

/// `prims` seen from a scanner at `(x, y)` heading `th` (all in the frame of `prims`).
pub fn seen_from(prims: &[Prim], (ox, oy, th): (f64, f64, f64)) -> Vec<Prim> {
    let (s, c) = th.sin_cos();
    let to = |x: f64, y: f64| {
        let (dx, dy) = (x - ox, y - oy);
        (c * dx + s * dy, -s * dx + c * dy)
    };
    prims
        .iter()
        .map(|p| match *p {
            Prim::Seg(x0, y0, x1, y1) => {
                let (a, b) = (to(x0, y0), to(x1, y1));
                Prim::Seg(a.0, a.1, b.0, b.1)
            }
            Prim::Circle(cx, cy, r) => {
                let (x, y) = to(cx, cy);
                Prim::Circle(x, y, r)
            }
        })
        .collect()
}

/// The ranges of a scan of `geometry` (361 beams) seeing only the wall `x cos α + y sin α = ρ`
/// (`wall`, rad and mm) over the beams within `half` rad of its normal, the others no return;
/// `error(on_wall)` is called for every beam in order and its value added on the wall.
pub fn wall_ranges(
    geometry: pfe_core::ScanGeometry,
    (alpha, rho): (f64, f64),
    half: f64,
    mut error: impl FnMut(bool) -> f64,
) -> Vec<f32> {
    (0..361)
        .map(|i| {
            let off = f64::from(geometry.bearing(i)) - alpha;
            let on = off.abs() < half;
            let e = error(on);
            if on {
                (rho / off.cos() + e) as f32
            } else {
                f32::NAN
            }
        })
        .collect()
}
