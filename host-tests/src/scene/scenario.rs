//! What to simulate ([`Scenario`]: scene kind, seed, noise, resolution) and what comes out
//! ([`SimScan`]).

use pfe_core::{Point, ScanGeometry};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::generate::build_scene;
use super::{render, Shape, TruthFeature};

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
    /// Adds the smooth systematic bias [`systematic_bias_mm`](super::systematic_bias_mm) (default off).
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
    /// The same as raw LMS codes (mm mode), [`NO_RETURN_CODE`](super::NO_RETURN_CODE) for no return.
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
