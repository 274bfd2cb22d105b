//! Scene simulator with ground truth: 2D scenes of line segments and circles, an exact ray
//! caster and an LMS200 range model (Gaussian noise, optional systematic bias, integer-mm
//! quantisation, no-return codes, optional mixed pixels).
//!
//! Everything is deterministic from [`Scenario::seed`] (ChaCha8). The scanner frame is
//! pfe-core's: x forward, y left, bearings counter-clockwise, beam `i` at
//! `start + i · step`, ranges in mm. Ray casting runs in `f64`; outputs are `f32`/`u16` as
//! the extractors consume them.
//!
//! Ground truth: every beam records the primitive it hit (each wall segment, box side and
//! circle is its own primitive). A ground-truth feature is a maximal run of at least
//! [`MIN_RUN`] consecutive beams on one primitive, with that primitive's exact parameters in
//! the scanner frame; its first and last beams are true mark points.
//!
//! ```
//! use host_tests::sim::{Scenario, SceneKind};
//! let scan = Scenario::new(SceneKind::Office, 7).simulate();
//! assert_eq!(scan.ranges_mm.len(), 361);
//! assert!(scan.truth.iter().all(|f| f.last + 1 - f.first >= 4));
//! assert_eq!(scan.raw, Scenario::new(SceneKind::Office, 7).simulate().raw); // deterministic
//! ```

use pfe_core::{Point, ScanGeometry};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// The raw LMS code written for a beam without return (first reserved code in the 8 m mode).
pub const NO_RETURN_CODE: u16 = 8183;

/// Smallest run of beams on one primitive that is a ground-truth feature (the paper's 4).
pub const MIN_RUN: usize = 4;

/// Free distance straight ahead of a sampled scanner pose, mm.
pub const MIN_FORWARD_MM: f64 = 1500.0;

/// Amplitude of the optional systematic range bias, mm (LMS200 data sheet, 8 m mode).
pub const BIAS_AMPLITUDE_MM: f64 = 15.0;

type V2 = [f64; 2];

fn sub(a: V2, b: V2) -> V2 {
    [a[0] - b[0], a[1] - b[1]]
}
fn add(a: V2, b: V2) -> V2 {
    [a[0] + b[0], a[1] + b[1]]
}
fn scale(a: V2, s: f64) -> V2 {
    [a[0] * s, a[1] * s]
}
fn dot(a: V2, b: V2) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}
fn cross(a: V2, b: V2) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}
fn norm(a: V2) -> f64 {
    a[0].hypot(a[1])
}
fn dir(angle: f64) -> V2 {
    [angle.cos(), angle.sin()]
}
fn wrap_pi(a: f64) -> f64 {
    let mut a = a % TAU;
    if a > PI {
        a -= TAU;
    } else if a <= -PI {
        a += TAU;
    }
    a
}

/// A scene primitive, in mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// A straight segment from `a` to `b` (a wall, a box side).
    Segment {
        /// One end.
        a: [f64; 2],
        /// The other end.
        b: [f64; 2],
    },
    /// A circle (pillar, bin).
    Circle {
        /// Centre.
        center: [f64; 2],
        /// Radius, > 0.
        radius: f64,
    },
}

impl Shape {
    /// Distance `t > 0` along the ray `origin + t · d` (`d` a unit vector) to its first hit of
    /// this shape, or `None`. Rays parallel to a segment do not hit it.
    ///
    /// ```
    /// use host_tests::sim::Shape;
    /// let wall = Shape::Segment { a: [2000.0, -1000.0], b: [2000.0, 1000.0] };
    /// let t = wall.ray_hit([0.0, 0.0], [1.0, 0.0]).unwrap();
    /// assert!((t - 2000.0).abs() < 1e-9);
    /// ```
    pub fn ray_hit(&self, origin: [f64; 2], d: [f64; 2]) -> Option<f64> {
        const EPS: f64 = 1e-9;
        match *self {
            Shape::Segment { a, b } => {
                let e = sub(b, a);
                let den = cross(d, e);
                if den.abs() < 1e-12 * norm(e).max(1.0) {
                    return None;
                }
                let w = sub(a, origin);
                let t = cross(w, e) / den;
                let s = cross(w, d) / den;
                (t > EPS && (0.0..=1.0).contains(&s)).then_some(t)
            }
            Shape::Circle { center, radius } => {
                let c = sub(center, origin);
                let b = dot(d, c);
                let disc = b * b - (dot(c, c) - radius * radius);
                if disc < 0.0 {
                    return None;
                }
                let root = disc.sqrt();
                if b - root > EPS {
                    Some(b - root)
                } else if b + root > EPS {
                    Some(b + root)
                } else {
                    None
                }
            }
        }
    }

    /// Distance from `p` to the shape's outline.
    pub fn distance(&self, p: [f64; 2]) -> f64 {
        match *self {
            Shape::Segment { a, b } => {
                let e = sub(b, a);
                let l2 = dot(e, e);
                let s = if l2 > 0.0 {
                    (dot(sub(p, a), e) / l2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                norm(sub(p, add(a, scale(e, s))))
            }
            Shape::Circle { center, radius } => (norm(sub(p, center)) - radius).abs(),
        }
    }

    /// The shape seen from a scanner at `pose = (x, y, heading)` (world → scanner frame).
    pub fn to_frame(&self, pose: [f64; 3]) -> Shape {
        let (s, c) = pose[2].sin_cos();
        let f = |p: V2| {
            let q = [p[0] - pose[0], p[1] - pose[1]];
            [c * q[0] + s * q[1], -s * q[0] + c * q[1]]
        };
        match *self {
            Shape::Segment { a, b } => Shape::Segment { a: f(a), b: f(b) },
            Shape::Circle { center, radius } => Shape::Circle {
                center: f(center),
                radius,
            },
        }
    }
}

/// The true parameters of a ground-truth feature, in the scanner frame (pfe-core conventions).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TruthKind {
    /// `x cos α + y sin α = ρ`, ρ ≥ 0, α in (−π, π].
    Line {
        /// Normal angle, rad.
        alpha: f64,
        /// Distance from the scanner, mm.
        rho: f64,
    },
    /// A circle.
    Circle {
        /// Centre, mm.
        center: [f64; 2],
        /// Radius, mm.
        radius: f64,
    },
}

impl TruthKind {
    /// True for a line.
    pub fn is_line(&self) -> bool {
        matches!(self, TruthKind::Line { .. })
    }

    /// The parameters of `shape` (in the scanner frame).
    pub fn of(shape: &Shape) -> TruthKind {
        match *shape {
            Shape::Segment { a, b } => {
                let e = sub(b, a);
                let mut alpha = e[1].atan2(e[0]) + FRAC_PI_2;
                let mut rho = dot(a, dir(alpha));
                if rho < 0.0 {
                    rho = -rho;
                    alpha += PI;
                }
                TruthKind::Line {
                    alpha: wrap_pi(alpha),
                    rho,
                }
            }
            Shape::Circle { center, radius } => TruthKind::Circle { center, radius },
        }
    }
}

/// Cramér–Rao bound (standard deviations) of a feature's parameters from its beams.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Crb {
    /// Line: σ_ρ, mm. Circle: RMS centre error `sqrt(σ_a² + σ_b²)`, mm.
    pub position: f64,
    /// Line: σ_α, rad. Circle: σ_R, mm.
    pub shape: f64,
}

/// A ground-truth feature: beams `first..=last` all hit primitive `primitive`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TruthFeature {
    /// Index of the primitive in [`SimScan::shapes`].
    pub primitive: usize,
    /// First beam.
    pub first: usize,
    /// Last beam.
    pub last: usize,
    /// True parameters.
    pub kind: TruthKind,
    /// Cramér–Rao bound of the parameters for these beams and the scan's range noise.
    pub crb: Crb,
}

/// Cramér–Rao bound for estimating `kind` from ranges along `bearings` with independent
/// Gaussian range noise `sigma` (mm): Fisher information `Σ g_i g_iᵀ / σ²`, `g_i` the
/// derivative of beam i's true range with respect to the parameters. Line (ρ, α):
/// `r = ρ / cos(φ − α)`. Circle (a, b, R): with `n` the outward normal at the hit and `u` the
/// beam, `∂r/∂(a, b) = n / (n·u)`, `∂r/∂R = 1 / (n·u)`. `None` when singular.
///
/// ```
/// use host_tests::sim::{crb, TruthKind};
/// let wall = TruthKind::Line { alpha: 0.0, rho: 2000.0 };
/// let bearings: Vec<f64> = (0..41).map(|i| (i as f64 - 20.0).to_radians()).collect();
/// let b = crb(&wall, &bearings, 5.0).unwrap();
/// assert!(b.position < 5.0 / (41f64).sqrt() * 1.01); // ~σ/√n at normal incidence
/// ```
pub fn crb(kind: &TruthKind, bearings: &[f64], sigma: f64) -> Option<Crb> {
    let s2 = sigma * sigma;
    if s2.is_nan() || s2 <= 0.0 {
        return None;
    }
    match *kind {
        TruthKind::Line { alpha, rho } => {
            let mut f = [[0.0f64; 2]; 2];
            for &phi in bearings {
                let c = (phi - alpha).cos();
                if c.abs() < 1e-9 {
                    continue;
                }
                let g = [1.0 / c, rho * (phi - alpha).sin() / (c * c)];
                for (i, row) in f.iter_mut().enumerate() {
                    for (j, v) in row.iter_mut().enumerate() {
                        *v += g[i] * g[j] / s2;
                    }
                }
            }
            let det = f[0][0] * f[1][1] - f[0][1] * f[1][0];
            if det.is_nan() || det.abs() <= 1e-300 {
                return None;
            }
            let (vr, va) = (f[1][1] / det, f[0][0] / det);
            (vr > 0.0 && va > 0.0).then(|| Crb {
                position: vr.sqrt(),
                shape: va.sqrt(),
            })
        }
        TruthKind::Circle { center, radius } => {
            let mut f = [[0.0f64; 3]; 3];
            for &phi in bearings {
                let u = dir(phi);
                let shape = Shape::Circle { center, radius };
                let Some(t) = shape.ray_hit([0.0, 0.0], u) else {
                    continue;
                };
                let n = scale(sub(scale(u, t), center), 1.0 / radius);
                let nu = dot(n, u);
                if nu.abs() < 1e-9 {
                    continue;
                }
                let g = [n[0] / nu, n[1] / nu, 1.0 / nu];
                for (i, row) in f.iter_mut().enumerate() {
                    for (j, v) in row.iter_mut().enumerate() {
                        *v += g[i] * g[j] / s2;
                    }
                }
            }
            let inv = invert3(&f)?;
            let (va, vb, vr) = (inv[0][0], inv[1][1], inv[2][2]);
            (va > 0.0 && vb > 0.0 && vr > 0.0).then(|| Crb {
                position: (va + vb).sqrt(),
                shape: vr.sqrt(),
            })
        }
    }
}

fn invert3(m: &[[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let c = |r: usize, k: usize| -> f64 {
        let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
        let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
        m[r1][k1] * m[r2][k2] - m[r1][k2] * m[r2][k1]
    };
    let det = m[0][0] * c(0, 0) + m[0][1] * c(0, 1) + m[0][2] * c(0, 2);
    if !det.is_finite() || det.abs() <= 1e-300 {
        return None;
    }
    let mut out = [[0.0; 3]; 3];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = c(j, i) / det; // adjugate = transposed cofactors
        }
    }
    Some(out)
}

/// Kind of scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SceneKind {
    /// A room with doors (and rooms behind them), corners, furniture, the odd pillar.
    Office,
    /// A room full of small boxes and bins.
    Clutter,
    /// A hall with free pillars and pillars embedded in the walls.
    Pillars,
    /// A long corridor (grazing incidence) with doors, recesses, junctions, wall columns.
    Corridor,
    /// One of the four above, chosen by the seed.
    Mixed,
}

impl SceneKind {
    /// All concrete kinds (not `Mixed`).
    pub const CONCRETE: [SceneKind; 4] = [
        SceneKind::Office,
        SceneKind::Clutter,
        SceneKind::Pillars,
        SceneKind::Corridor,
    ];

    /// Lower-case name.
    pub fn name(&self) -> &'static str {
        match self {
            SceneKind::Office => "office",
            SceneKind::Clutter => "clutter",
            SceneKind::Pillars => "pillars",
            SceneKind::Corridor => "corridor",
            SceneKind::Mixed => "mixed",
        }
    }
}

impl std::str::FromStr for SceneKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.to_ascii_lowercase().as_str() {
            "office" => Ok(SceneKind::Office),
            "clutter" => Ok(SceneKind::Clutter),
            "pillars" => Ok(SceneKind::Pillars),
            "corridor" => Ok(SceneKind::Corridor),
            "mixed" => Ok(SceneKind::Mixed),
            o => Err(format!(
                "unknown scene kind `{o}` (office, clutter, pillars, corridor, mixed)"
            )),
        }
    }
}

/// Angular resolution of the simulated LMS200 (always 180°, beam 0 at −90°).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Resolution {
    /// 0.25° (721 beams).
    Quarter,
    /// 0.5° (361 beams).
    Half,
    /// 1° (181 beams).
    One,
}

impl Resolution {
    /// Step in degrees.
    pub fn degrees(&self) -> f64 {
        match self {
            Resolution::Quarter => 0.25,
            Resolution::Half => 0.5,
            Resolution::One => 1.0,
        }
    }

    /// Number of beams over 180°.
    pub fn beams(&self) -> usize {
        match self {
            Resolution::Quarter => 721,
            Resolution::Half => 361,
            Resolution::One => 181,
        }
    }

    /// The scan geometry (8 m mode).
    pub fn geometry(&self) -> ScanGeometry {
        ScanGeometry::lms200(180.0, self.degrees() as f32)
    }
}

/// One simulated scan's recipe. Equal scenarios give equal scans.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scenario {
    /// Scene generator.
    pub kind: SceneKind,
    /// Seed of everything random (scene, pose, noise).
    pub seed: u64,
    /// Gaussian range noise σ_r, mm (default 5).
    pub sigma_r: f32,
    /// Angular resolution (default 0.5°).
    pub resolution: Resolution,
    /// Adds the smooth systematic bias [`systematic_bias_mm`] (default off).
    pub bias: bool,
    /// Puts a mixed pixel (a range between foreground and background) at some depth jumps
    /// (default off).
    pub mixed_pixels: bool,
}

/// One simulated scan with its ground truth.
#[derive(Clone, Debug, PartialEq)]
pub struct SimScan {
    /// Beam geometry.
    pub geometry: ScanGeometry,
    /// Measured ranges, mm (integers), NaN for no return.
    pub ranges_mm: Vec<f32>,
    /// The same as raw LMS codes (mm mode), [`NO_RETURN_CODE`] for no return.
    pub raw: Vec<u16>,
    /// Primitive hit by each beam (`None`: no return or a mixed pixel).
    pub beam_primitive: Vec<Option<usize>>,
    /// Ground-truth features, in scan order.
    pub truth: Vec<TruthFeature>,
    /// True mark points (first and last beam of each truth feature), increasing.
    pub true_marks: Vec<usize>,
    /// The scene in the scanner frame (primitive ids index it).
    pub shapes: Vec<Shape>,
    /// Noise-free ranges, mm (NaN for no return).
    pub true_ranges_mm: Vec<f64>,
    /// Range noise σ_r used, mm.
    pub sigma_r: f64,
}

/// The optional systematic range error, mm: a smooth curve within ±[`BIAS_AMPLITUDE_MM`]
/// over 0–8 m (a stand-in for the LMS200's calibration curve).
pub fn systematic_bias_mm(r_mm: f64) -> f64 {
    let x = (r_mm / 8000.0).clamp(0.0, 1.5);
    BIAS_AMPLITUDE_MM * (0.7 * (2.0 * PI * 1.3 * x + 0.4).sin() + 0.3 * (2.0 * x - 1.0))
}

impl Scenario {
    /// Defaults: σ_r = 5 mm, 0.5°, no bias, no mixed pixels.
    pub fn new(kind: SceneKind, seed: u64) -> Self {
        Self {
            kind,
            seed,
            sigma_r: 5.0,
            resolution: Resolution::Half,
            bias: false,
            mixed_pixels: false,
        }
    }

    /// The same scenario with range noise `sigma_r` (mm).
    pub fn with_sigma(mut self, sigma_r: f32) -> Self {
        self.sigma_r = sigma_r;
        self
    }

    /// Builds the scene, places the scanner and measures one scan.
    pub fn simulate(&self) -> SimScan {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let kind = match self.kind {
            SceneKind::Mixed => SceneKind::CONCRETE[rng.gen_range(0..4)],
            k => k,
        };
        let scene = build_scene(kind, &mut rng);
        let pose = scene.sample_pose(&mut rng);
        let shapes: Vec<Shape> = scene.shapes.iter().map(|s| s.to_frame(pose)).collect();
        render(&shapes, self, &mut rng)
    }
}

/// Casts every beam of `geometry` from the origin into `shapes`: nearest hit per beam
/// (range, primitive id), `None` beyond `geometry.r_max`.
pub fn cast(shapes: &[Shape], geometry: &ScanGeometry) -> Vec<Option<(f64, usize)>> {
    let n = beam_count(geometry);
    (0..n)
        .map(|i| {
            let d = dir(bearing(geometry, i));
            let mut best: Option<(f64, usize)> = None;
            for (id, s) in shapes.iter().enumerate() {
                if let Some(t) = s.ray_hit([0.0, 0.0], d) {
                    if best.is_none_or(|(bt, _)| t < bt) {
                        best = Some((t, id));
                    }
                }
            }
            best.filter(|(t, _)| *t <= f64::from(geometry.r_max))
        })
        .collect()
}

/// Bearing of beam `i` in f64.
pub fn bearing(geometry: &ScanGeometry, i: usize) -> f64 {
    f64::from(geometry.start_angle) + f64::from(geometry.angle_step) * i as f64
}

/// Beams of an LMS200-style geometry over 180°.
fn beam_count(geometry: &ScanGeometry) -> usize {
    let step = f64::from(geometry.angle_step).abs();
    if step > 0.0 {
        (PI / step).round() as usize + 1
    } else {
        0
    }
}

/// Measures `shapes` (scanner frame) as `scenario` says, with ground truth.
pub fn render(shapes: &[Shape], scenario: &Scenario, rng: &mut ChaCha8Rng) -> SimScan {
    let geometry = scenario.resolution.geometry();
    let r_max = f64::from(geometry.r_max);
    let hits = cast(shapes, &geometry);
    let n = hits.len();
    let mut true_r: Vec<f64> = hits.iter().map(|h| h.map_or(f64::NAN, |h| h.0)).collect();
    let mut prim: Vec<Option<usize>> = hits.iter().map(|h| h.map(|h| h.1)).collect();
    // Ground truth comes from the clean hits; mixed pixels then remove beams from it.
    if scenario.mixed_pixels {
        let mut i = 0;
        while i + 1 < n {
            let (a, b) = (true_r[i], true_r[i + 1]);
            if a.is_finite() && b.is_finite() && (a - b).abs() > 300.0 && rng.gen_bool(0.5) {
                let j = if rng.gen_bool(0.5) { i } else { i + 1 };
                let w: f64 = rng.gen_range(0.2..0.8);
                true_r[j] = w * a + (1.0 - w) * b;
                prim[j] = None;
                i += 2;
            } else {
                i += 1;
            }
        }
    }
    let sigma = f64::from(scenario.sigma_r).max(0.0);
    let normal = Normal::new(0.0, sigma.max(1e-12)).ok();
    let mut ranges_mm = vec![f32::NAN; n];
    let mut raw = vec![NO_RETURN_CODE; n];
    for i in 0..n {
        let t = true_r[i];
        if !t.is_finite() {
            prim[i] = None;
            continue;
        }
        let mut r = t;
        if scenario.bias {
            r += systematic_bias_mm(t);
        }
        if sigma > 0.0 {
            if let Some(nd) = &normal {
                r += nd.sample(rng);
            }
        }
        let q = r.round();
        if q >= 1.0 && q <= r_max {
            ranges_mm[i] = q as f32;
            raw[i] = q as u16;
        } else {
            prim[i] = None;
        }
    }
    // Truth: maximal runs of ≥ MIN_RUN beams on one primitive.
    let sigma_eff = (sigma * sigma + 1.0 / 12.0).sqrt(); // noise + integer quantisation
    let mut truth = Vec::new();
    let mut i = 0;
    while i < n {
        let Some(id) = prim[i] else {
            i += 1;
            continue;
        };
        let mut j = i;
        while j + 1 < n && prim[j + 1] == Some(id) {
            j += 1;
        }
        if j + 1 - i >= MIN_RUN {
            if let Some(shape) = shapes.get(id) {
                let kind = TruthKind::of(shape);
                let bearings: Vec<f64> = (i..=j).map(|k| bearing(&geometry, k)).collect();
                truth.push(TruthFeature {
                    primitive: id,
                    first: i,
                    last: j,
                    kind,
                    crb: crb(&kind, &bearings, sigma_eff).unwrap_or_default(),
                });
            }
        }
        i = j + 1;
    }
    let mut true_marks: Vec<usize> = truth.iter().flat_map(|f| [f.first, f.last]).collect();
    true_marks.dedup();
    SimScan {
        geometry,
        ranges_mm,
        raw,
        beam_primitive: prim,
        truth,
        true_marks,
        shapes: shapes.to_vec(),
        true_ranges_mm: true_r,
        sigma_r: sigma,
    }
}

impl SimScan {
    /// Cartesian points of the measured ranges (`None`: no return).
    pub fn points(&self) -> Vec<Option<Point>> {
        self.ranges_mm
            .iter()
            .enumerate()
            .map(|(i, &r)| {
                r.is_finite()
                    .then(|| Point::from_polar(r, self.geometry.bearing(i)))
            })
            .collect()
    }
}

// ------------------------------------------------------------------------------------------
// Scene generators. All lengths in mm. Each builds in its own axis-aligned frame; the random
// scanner heading rotates the view.

/// Something the scanner must not stand inside.
#[derive(Clone, Debug)]
enum Solid {
    /// Convex polygon (counter-clockwise or clockwise).
    Poly(Vec<V2>),
    Disc(V2, f64),
}

impl Solid {
    fn contains(&self, p: V2, margin: f64) -> bool {
        match self {
            Solid::Disc(c, r) => norm(sub(p, *c)) < r + margin,
            Solid::Poly(v) => {
                let n = v.len();
                let mut sign = 0.0f64;
                for k in 0..n {
                    let (a, b) = (v[k], v[(k + 1) % n]);
                    let c = cross(sub(b, a), sub(p, a));
                    if sign == 0.0 {
                        sign = c.signum();
                    } else if c.signum() != sign && c != 0.0 {
                        return false;
                    }
                }
                true
            }
        }
    }
}

/// A scene under construction.
#[derive(Clone, Debug, Default)]
struct Scene {
    shapes: Vec<Shape>,
    solids: Vec<Solid>,
    /// Where the scanner may stand: x range, y range.
    area: [f64; 4],
    /// Heading: `None` uniform, `Some((mean, spread))` mean ± spread (also mean + π).
    heading: Option<(f64, f64)>,
}

impl Scene {
    fn seg(&mut self, a: V2, b: V2) {
        if norm(sub(b, a)) > 1.0 {
            self.shapes.push(Shape::Segment { a, b });
        }
    }

    fn circle(&mut self, c: V2, r: f64) {
        self.shapes.push(Shape::Circle {
            center: c,
            radius: r,
        });
        self.solids.push(Solid::Disc(c, r));
    }

    /// A rectangle box centred at `c`, sides `w × h`, rotated by `angle`.
    fn rect(&mut self, c: V2, w: f64, h: f64, angle: f64) {
        let (u, v) = (dir(angle), dir(angle + FRAC_PI_2));
        let corners: Vec<V2> = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .iter()
            .map(|(sx, sy)| add(c, add(scale(u, sx * w / 2.0), scale(v, sy * h / 2.0))))
            .collect();
        for k in 0..4 {
            self.seg(corners[k], corners[(k + 1) % 4]);
        }
        self.solids.push(Solid::Poly(corners));
    }

    /// Whether a disc of radius `r` at `c` is clear of all solids and shapes.
    fn free(&self, c: V2, r: f64) -> bool {
        self.solids.iter().all(|s| !s.contains(c, r))
            && self.shapes.iter().all(|s| s.distance(c) > r)
    }

    /// A wall from `a` to `b` (room on its left) with `doors` gaps; behind a gap, with some
    /// probability, the wall of the next room. Returns the intervals (along the wall) that
    /// stayed solid.
    fn wall(
        &mut self,
        rng: &mut ChaCha8Rng,
        a: V2,
        b: V2,
        doors: usize,
        recess: bool,
    ) -> Vec<(f64, f64)> {
        let len = norm(sub(b, a));
        let u = scale(sub(b, a), 1.0 / len);
        let out = [u[1], -u[0]]; // right of a→b = outside the room
        let mut gaps: Vec<(f64, f64)> = Vec::new();
        for _ in 0..doors {
            let w = rng.gen_range(800.0..1300.0);
            if len < w + 1200.0 {
                break;
            }
            let s = rng.gen_range(500.0..len - w - 500.0);
            if gaps
                .iter()
                .all(|&(g0, g1)| s + w + 300.0 < g0 || s > g1 + 300.0)
            {
                gaps.push((s, s + w));
            }
        }
        gaps.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut solid = Vec::new();
        let mut pos = 0.0;
        let at = |s: f64| add(a, scale(u, s));
        for &(g0, g1) in &gaps {
            solid.push((pos, g0));
            self.seg(at(pos), at(g0));
            if recess && rng.gen_bool(0.5) {
                // A recessed door: the door leaf set back into the wall.
                let depth = rng.gen_range(100.0..300.0);
                let (p0, p1) = (
                    add(at(g0), scale(out, depth)),
                    add(at(g1), scale(out, depth)),
                );
                self.seg(at(g0), p0);
                self.seg(p0, p1);
                self.seg(p1, at(g1));
            } else if rng.gen_bool(0.7) {
                // The far wall of the room behind, parallel.
                let depth = rng.gen_range(1500.0..5000.0);
                let ext = rng.gen_range(1000.0..3000.0);
                self.seg(
                    add(at(g0 - ext), scale(out, depth)),
                    add(at(g1 + ext), scale(out, depth)),
                );
                // Side walls of the gap (door jambs) as thin returns are short: skipped.
            }
            pos = g1;
        }
        solid.push((pos, len));
        self.seg(at(pos), at(len));
        solid
    }

    /// A pillar embedded in the wall `a → b` (room on the left) at arc length `s`.
    fn wall_pillar(&mut self, a: V2, b: V2, s: f64, r: f64, protrude: f64) {
        let len = norm(sub(b, a));
        let u = scale(sub(b, a), 1.0 / len);
        let inward = [-u[1], u[0]];
        let c = add(add(a, scale(u, s)), scale(inward, protrude - r));
        self.circle(c, r);
    }

    /// A rectangular pilaster (or cabinet) `width × depth` standing against the wall `a → b`
    /// (room on the left) at arc length `s`.
    fn pilaster(&mut self, a: V2, b: V2, s: f64, width: f64, depth: f64) {
        let len = norm(sub(b, a));
        let u = scale(sub(b, a), 1.0 / len);
        let inward = [-u[1], u[0]];
        let c = add(add(a, scale(u, s)), scale(inward, depth / 2.0));
        self.rect(c, width, depth, u[1].atan2(u[0]));
    }

    /// Up to `n` pilasters on the wall `a → b`, where the room side is free.
    fn pilasters(&mut self, rng: &mut ChaCha8Rng, a: V2, b: V2, n: usize, max_depth: f64) {
        let len = norm(sub(b, a));
        let inward = scale([-(b[1] - a[1]), b[0] - a[0]], 1.0 / len);
        for _ in 0..n {
            let width = rng.gen_range(200.0..900.0);
            let depth = rng.gen_range(80.0..max_depth);
            if len < width + 800.0 {
                return;
            }
            let s = rng.gen_range(400.0 + width / 2.0..len - 400.0 - width / 2.0);
            let probe = add(
                add(a, scale(sub(b, a), s / len)),
                scale(inward, depth + 150.0),
            );
            if self
                .solids
                .iter()
                .all(|x| !x.contains(probe, width / 2.0 + depth + 150.0))
            {
                self.pilaster(a, b, s, width, depth);
            }
        }
    }

    /// A random scanner pose: at least 350 mm from everything, not inside a solid, and not
    /// facing an obstacle closer than [`MIN_FORWARD_MM`] straight ahead (a robot does not
    /// drive with its nose against a wall); the last candidate when none qualifies.
    fn sample_pose(&self, rng: &mut ChaCha8Rng) -> [f64; 3] {
        let [x0, x1, y0, y1] = self.area;
        let mut best = [(x0 + x1) / 2.0, (y0 + y1) / 2.0, 0.0];
        for _ in 0..500 {
            let q = [
                rng.gen_range(x0..x1.max(x0 + 1.0)),
                rng.gen_range(y0..y1.max(y0 + 1.0)),
            ];
            let heading = match self.heading {
                None => rng.gen_range(-PI..PI),
                Some((m, s)) => {
                    let base = if rng.gen_bool(0.5) { m } else { m + PI };
                    wrap_pi(base + rng.gen_range(-s..s))
                }
            };
            if !self.free(q, 350.0) {
                continue;
            }
            best = [q[0], q[1], heading];
            let ahead = self
                .shapes
                .iter()
                .filter_map(|s| s.ray_hit(q, dir(heading)))
                .fold(f64::INFINITY, f64::min);
            if ahead >= MIN_FORWARD_MM {
                break;
            }
        }
        best
    }

    /// Places up to `n` items of radius `r(rng)` at free random spots in the area.
    fn scatter(
        &mut self,
        rng: &mut ChaCha8Rng,
        n: usize,
        margin: f64,
        mut place: impl FnMut(&mut Scene, &mut ChaCha8Rng, V2) -> f64,
        size: impl Fn(&mut ChaCha8Rng) -> f64,
    ) {
        let [x0, x1, y0, y1] = self.area;
        let mut placed = 0;
        for _ in 0..20 * n {
            if placed == n {
                break;
            }
            let r = size(rng);
            let (ax0, ax1, ay0, ay1) = (
                x0 + r + margin,
                x1 - r - margin,
                y0 + r + margin,
                y1 - r - margin,
            );
            if ax1 <= ax0 || ay1 <= ay0 {
                break;
            }
            let c = [rng.gen_range(ax0..ax1), rng.gen_range(ay0..ay1)];
            if self.free(c, r + margin) {
                place(self, rng, c);
                placed += 1;
            }
        }
    }
}

/// Four walls of a `w × h` room (counter-clockwise, room inside) with doors.
fn room(
    sc: &mut Scene,
    rng: &mut ChaCha8Rng,
    w: f64,
    h: f64,
    max_doors: usize,
    recess: bool,
) -> [(V2, V2); 4] {
    let walls = [
        ([0.0, 0.0], [w, 0.0]),
        ([w, 0.0], [w, h]),
        ([w, h], [0.0, h]),
        ([0.0, h], [0.0, 0.0]),
    ];
    for &(a, b) in &walls {
        let doors = rng.gen_range(0..=max_doors);
        sc.wall(rng, a, b, doors, recess);
    }
    sc.area = [300.0, w - 300.0, 300.0, h - 300.0];
    walls
}

fn build_scene(kind: SceneKind, rng: &mut ChaCha8Rng) -> Scene {
    let mut sc = Scene::default();
    match kind {
        SceneKind::Office | SceneKind::Mixed => {
            let (w, h) = (
                rng.gen_range(5000.0..12000.0),
                rng.gen_range(3500.0..8000.0),
            );
            let walls = room(&mut sc, rng, w, h, 2, false);
            for &(a, b) in &walls {
                let k = rng.gen_range(1..=3);
                sc.pilasters(rng, a, b, k, 600.0);
            }
            // Furniture: against a wall or free-standing.
            let n = rng.gen_range(6..=11);
            sc.scatter(
                rng,
                n,
                150.0,
                |sc, rng, c| {
                    let (bw, bh) = (rng.gen_range(400.0..1600.0), rng.gen_range(400.0..900.0));
                    let angle = if rng.gen_bool(0.5) {
                        rng.gen_range(0..4) as f64 * FRAC_PI_2
                    } else {
                        rng.gen_range(-PI..PI)
                    };
                    sc.rect(c, bw, bh, angle);
                    0.0
                },
                |rng| rng.gen_range(300.0..600.0),
            );
            if rng.gen_bool(0.4) {
                sc.scatter(
                    rng,
                    1,
                    300.0,
                    |sc, rng, c| {
                        let r = rng.gen_range(150.0..400.0);
                        sc.circle(c, r);
                        0.0
                    },
                    |_| 400.0,
                );
            }
            if rng.gen_bool(0.3) {
                let (a, b) = walls[rng.gen_range(0..4)];
                let len = norm(sub(b, a));
                let r = rng.gen_range(200.0..450.0);
                if len > 4.0 * r {
                    let s = rng.gen_range(2.0 * r..len - 2.0 * r);
                    let p = rng.gen_range(0.3..1.2) * r;
                    sc.wall_pillar(a, b, s, r, p);
                }
            }
        }
        SceneKind::Clutter => {
            let (w, h) = (
                rng.gen_range(5000.0..10000.0),
                rng.gen_range(4000.0..8000.0),
            );
            room(&mut sc, rng, w, h, 1, false);
            let n = rng.gen_range(12..=22);
            sc.scatter(
                rng,
                n,
                200.0,
                |sc, rng, c| {
                    let (bw, bh) = (rng.gen_range(200.0..700.0), rng.gen_range(200.0..700.0));
                    let angle = rng.gen_range(-PI..PI);
                    sc.rect(c, bw, bh, angle);
                    0.0
                },
                |_| 500.0,
            );
            let m = rng.gen_range(0..=3);
            sc.scatter(
                rng,
                m,
                200.0,
                |sc, rng, c| {
                    let r = rng.gen_range(80.0..250.0);
                    sc.circle(c, r);
                    0.0
                },
                |_| 250.0,
            );
        }
        SceneKind::Pillars => {
            let (w, h) = (
                rng.gen_range(6000.0..14000.0),
                rng.gen_range(5000.0..10000.0),
            );
            let walls = room(&mut sc, rng, w, h, 1, false);
            let k = rng.gen_range(2..=4);
            for _ in 0..k {
                let (a, b) = walls[rng.gen_range(0..4)];
                let len = norm(sub(b, a));
                let r = rng.gen_range(150.0..450.0);
                let s = rng.gen_range(2.0 * r..len - 2.0 * r);
                let p = rng.gen_range(0.3..1.3) * r;
                if sc.free(add(a, scale(sub(b, a), s / len)), 2.0 * r) || sc.solids.is_empty() {
                    sc.wall_pillar(a, b, s, r, p);
                }
            }
            for &(a, b) in &walls {
                let k = rng.gen_range(0..=2);
                sc.pilasters(rng, a, b, k, 400.0);
            }
            let n = rng.gen_range(8..=14);
            sc.scatter(
                rng,
                n,
                300.0,
                |sc, rng, c| {
                    let r = rng.gen_range(100.0..500.0);
                    sc.circle(c, r);
                    0.0
                },
                |_| 500.0,
            );
            if rng.gen_bool(0.5) {
                sc.scatter(
                    rng,
                    1,
                    300.0,
                    |sc, rng, c| {
                        let (bw, bh) = (rng.gen_range(400.0..1200.0), rng.gen_range(400.0..1200.0));
                        let angle = rng.gen_range(-PI..PI);
                        sc.rect(c, bw, bh, angle);
                        0.0
                    },
                    |_| 700.0,
                );
            }
        }
        SceneKind::Corridor => {
            let len = rng.gen_range(15000.0..40000.0);
            let wid = rng.gen_range(1500.0..3000.0);
            // Side walls with doors (some recessed), end walls.
            let doors_r = (len / rng.gen_range(2000.0..5000.0)) as usize;
            let doors_l = (len / rng.gen_range(2000.0..5000.0)) as usize;
            let right = sc.wall(rng, [0.0, 0.0], [len, 0.0], doors_r, true);
            let left = sc.wall(rng, [len, wid], [0.0, wid], doors_l, true);
            for (a, b) in [([0.0, 0.0], [len, 0.0]), ([len, wid], [0.0, wid])] {
                let k = (len / rng.gen_range(3000.0..8000.0)) as usize;
                sc.pilasters(rng, a, b, k, 0.15 * wid);
            }
            sc.seg([len, 0.0], [len, wid]);
            sc.seg([0.0, wid], [0.0, 0.0]);
            // Columns in the walls, on solid stretches.
            let cols = rng.gen_range(1..=5);
            for _ in 0..cols {
                let (a, b, solid) = if rng.gen_bool(0.5) {
                    ([0.0, 0.0], [len, 0.0], &right)
                } else {
                    ([len, wid], [0.0, wid], &left)
                };
                let r = rng.gen_range(150.0..350.0);
                if let Some(&(s0, s1)) = solid.get(rng.gen_range(0..solid.len().max(1))) {
                    if s1 - s0 > 4.0 * r {
                        let s = rng.gen_range(s0 + 2.0 * r..s1 - 2.0 * r);
                        let p = rng.gen_range(0.2..0.8) * r;
                        sc.wall_pillar(a, b, s, r, p);
                    }
                }
            }
            if rng.gen_bool(0.3) {
                let r: f64 = rng.gen_range(150.0..300.0_f64).min(wid / 6.0);
                let c = [
                    rng.gen_range(2000.0..len - 2000.0),
                    wid / 2.0 + rng.gen_range(-0.2..0.2) * wid,
                ];
                sc.circle(c, r);
            }
            sc.area = [800.0, len - 800.0, 0.3 * wid, 0.7 * wid];
            sc.heading = Some((0.0, 0.5));
        }
    }
    sc
}

impl SimScan {
    /// An SVG picture of the scan (scanner at the origin, x up): the scene's primitives in
    /// grey, measured points coloured by ground-truth feature (black: not in a feature),
    /// true marks circled in red.
    pub fn to_svg(&self, size_px: f64) -> String {
        use std::fmt::Write as _;
        let r_max = f64::from(self.geometry.r_max);
        let k = size_px / (2.0 * r_max);
        // Scanner frame (x forward, y left) → screen (right = −y, up = x).
        let px = |p: V2| (size_px / 2.0 - p[1] * k, size_px / 2.0 - p[0] * k);
        let mut s = format!(
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{size_px}" height="{size_px}" viewBox="0 0 {size_px} {size_px}"><rect width="100%" height="100%" fill="white"/>"#
        );
        for sh in &self.shapes {
            match *sh {
                Shape::Segment { a, b } => {
                    let ((x1, y1), (x2, y2)) = (px(a), px(b));
                    let _ = write!(
                        s,
                        r#"<line x1="{x1:.1}" y1="{y1:.1}" x2="{x2:.1}" y2="{y2:.1}" stroke="silver" stroke-width="1"/>"#
                    );
                }
                Shape::Circle { center, radius } => {
                    let (x, y) = px(center);
                    let _ = write!(
                        s,
                        r#"<circle cx="{x:.1}" cy="{y:.1}" r="{:.1}" fill="none" stroke="silver"/>"#,
                        radius * k
                    );
                }
            }
        }
        const COLORS: [&str; 6] = [
            "#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2",
        ];
        let mut color = vec!["black"; self.ranges_mm.len()];
        for (fi, f) in self.truth.iter().enumerate() {
            for c in color.iter_mut().take(f.last + 1).skip(f.first) {
                *c = COLORS[fi % COLORS.len()];
            }
        }
        for (i, p) in self.points().iter().enumerate() {
            if let (Some(p), Some(c)) = (p, color.get(i)) {
                let (x, y) = px([f64::from(p.x), f64::from(p.y)]);
                let _ = write!(s, r#"<circle cx="{x:.1}" cy="{y:.1}" r="1.5" fill="{c}"/>"#);
                if self.true_marks.contains(&i) {
                    let _ = write!(
                        s,
                        r#"<circle cx="{x:.1}" cy="{y:.1}" r="4" fill="none" stroke="red"/>"#
                    );
                }
            }
        }
        let (ox, oy) = px([0.0, 0.0]);
        let _ = write!(
            s,
            r#"<circle cx="{ox:.1}" cy="{oy:.1}" r="4" fill="red"/></svg>"#
        );
        s
    }
}
