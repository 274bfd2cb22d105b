//! What to simulate ([`Scenario`]: scene kind, seed, noise, resolution, range mode, the
//! robot's motion) and what comes out ([`SimScan`]).

use pfe_core::{BeamTiming, Motion, Point, ScanGeometry};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::generate::{build_scene, long_corridor};
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
    /// A corridor 30–80 m long and 2–4 m wide with doors and recesses, for the 80 m (cm)
    /// mode: walls seen far away at grazing incidence. Not part of `Mixed`.
    LongCorridor,
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
            SceneKind::LongCorridor => "long-corridor",
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
            "long-corridor" => Ok(SceneKind::LongCorridor),
            o => Err(format!(
                "unknown scene kind `{o}` (office, clutter, pillars, corridor, mixed, long-corridor)"
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

/// Range unit and maximum range of the simulated LMS200.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RangeMode {
    /// 8 m mode, ranges in mm (1 mm quantum).
    Mm,
    /// 80 m mode, ranges in cm (10 mm quantum), simulated up to 80 m.
    Cm,
}

impl RangeMode {
    /// mm per raw code unit (the quantum).
    pub fn mm_per_unit(&self) -> f32 {
        match self {
            RangeMode::Mm => 1.0,
            RangeMode::Cm => 10.0,
        }
    }

    /// Maximum range, mm.
    pub fn r_max(&self) -> f32 {
        match self {
            RangeMode::Mm => 8000.0,
            RangeMode::Cm => 80000.0,
        }
    }
}

/// Range noise grows with the incidence angle β as `σ(β) = σ_r · min(1 + c · tan²β, cap)`
/// with `c` = this constant (when [`Scenario::incidence_noise`] is on). The form and both
/// constants are a model choice (a weaker, stretched return at oblique incidence), not a
/// fitted LMS200 characteristic: σ grows by 30 % at 60°, doubles near 72°, and is capped at
/// [`INCIDENCE_NOISE_CAP`] beyond 80°.
pub const INCIDENCE_NOISE_C: f64 = 0.1;

/// Cap of the incidence noise factor (see [`INCIDENCE_NOISE_C`]).
pub const INCIDENCE_NOISE_CAP: f64 = 4.0;

/// The factor by which the range noise grows at incidence angle `beta` (rad).
pub fn incidence_noise_factor(beta: f64) -> f64 {
    let t = beta.tan();
    (1.0 + INCIDENCE_NOISE_C * t * t).min(INCIDENCE_NOISE_CAP)
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
    /// Forward speed of the robot during the scan, mm/s (default 0). Each beam is cast from
    /// the pose at its time ([`Resolution::beam_time`]); the truth stays in the frame of beam 0.
    pub v: f32,
    /// Turn rate of the robot during the scan, rad/s (default 0, counter-clockwise positive).
    pub omega: f32,
    /// The extractors are told the motion ([`SimScan::odometry`]) (default off).
    pub odometry_given: bool,
    /// Range unit and maximum range (default [`RangeMode::Mm`]).
    pub range_mode: RangeMode,
    /// Noise grows with the incidence angle ([`incidence_noise_factor`]) (default off).
    pub incidence_noise: bool,
    /// Every beam taken in one mirror turn, at any resolution (default off: the LMS2xx
    /// interleaves sweeps below 1°). No LMS2xx does this; it is the control that tells what
    /// interleaving costs a moving scanner beyond the motion itself.
    pub one_sweep: bool,
}

/// One simulated scan with its ground truth.
#[derive(Clone, Debug, PartialEq)]
pub struct SimScan {
    /// Beam geometry.
    pub geometry: ScanGeometry,
    /// Measured ranges, mm (integers), NaN for no return.
    pub ranges_mm: Vec<f32>,
    /// The same as raw LMS codes (units of `mm_per_unit`), [`NO_RETURN_CODE`](super::NO_RETURN_CODE)
    /// for no return.
    pub raw: Vec<u16>,
    /// mm per raw code (1 in mm mode, 10 in cm mode).
    pub mm_per_unit: f32,
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
    /// Number of interleaved sweeps the scan is made of (1, 2 or 4).
    pub sweeps: usize,
    /// The robot's motion during the scan with the LMS2xx beam timing, when the scenario gives
    /// odometry (`None` otherwise, also when it moves).
    pub odometry: Option<Motion>,
}
impl Scenario {
    /// Defaults: σ_r = 5 mm, 0.5°, no bias, no mixed pixels, standing still, mm mode,
    /// incidence-independent noise.
    pub fn new(kind: SceneKind, seed: u64) -> Self {
        Self {
            kind,
            seed,
            sigma_r: 5.0,
            resolution: Resolution::Half,
            bias: false,
            mixed_pixels: false,
            v: 0.0,
            omega: 0.0,
            odometry_given: false,
            range_mode: RangeMode::Mm,
            incidence_noise: false,
            one_sweep: false,
        }
    }

    /// The same scenario with the robot moving at `v` mm/s and turning at `omega` rad/s.
    pub fn with_motion(mut self, v: f32, omega: f32) -> Self {
        self.v = v;
        self.omega = omega;
        self
    }

    /// The scan geometry: the resolution's, with the range mode's maximum range.
    pub fn geometry(&self) -> ScanGeometry {
        let mut g = self.resolution.geometry();
        g.r_max = self.range_mode.r_max();
        g
    }

    /// The robot's motion with the LMS2xx beam timing of the resolution (one sweep when
    /// [`one_sweep`](Self::one_sweep)).
    pub fn motion(&self) -> Motion {
        let deg = self.resolution.degrees() as f32;
        let timing = match self.one_sweep {
            true => BeamTiming::uniform(BeamTiming::LMS2XX_TURN / 360.0 * deg),
            false => BeamTiming::lms2xx(deg),
        };
        Motion {
            v: self.v,
            omega: self.omega,
            timing,
        }
    }

    /// Number of interleaved sweeps the scan is made of.
    pub fn sweeps(&self) -> usize {
        match self.one_sweep {
            true => 1,
            false => self.resolution.sweeps(),
        }
    }

    /// Scanner pose `[x, y, θ]` when beam `i` is taken, in the frame of beam 0.
    pub fn pose(&self, i: usize) -> [f64; 3] {
        super::motion::pose_at(
            f64::from(self.v),
            f64::from(self.omega),
            match self.one_sweep {
                true => i as f64 * self.resolution.degrees() * super::motion::DEGREE_S,
                false => self.resolution.beam_time(i),
            },
        )
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
        let scene = match kind {
            SceneKind::LongCorridor => long_corridor(&mut rng),
            k => build_scene(k, &mut rng),
        };
        let pose = scene.sample_pose(&mut rng);
        let shapes: Vec<Shape> = scene.shapes.iter().map(|s| s.to_frame(pose)).collect();
        render(&shapes, self, &mut rng)
    }
}
impl SimScan {
    /// What an extractor may know about how the scan was taken: the odometry (when given) and
    /// the number of sweeps.
    pub fn context(&self) -> crate::methods::ScanContext {
        crate::methods::ScanContext {
            odometry: self.odometry,
            sweeps: self.sweeps,
            quantum: self.mm_per_unit,
        }
    }

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
