//! The JSON lines `pfe extract` and `pfe listen` write, one per scan (`docs/JSON.md`).

use pfe_core::Feature;
use serde::Serialize;

use super::Record;
use crate::Extraction;

/// One feature in the `pfe extract` / `pfe listen` JSON output (`docs/JSON.md`).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum FeatureJson {
    /// `x cos α + y sin α = ρ` between `start` and `end`.
    Line {
        /// First beam index.
        first: usize,
        /// Last beam index.
        last: usize,
        /// Valid points fitted.
        points: usize,
        /// Normal angle, rad.
        alpha: f32,
        /// Distance from the scanner, mm.
        rho: f32,
        /// σ_α², rad².
        var_alpha: f32,
        /// σ_ρ², mm².
        var_rho: f32,
        /// cov(α, ρ), rad·mm.
        cov_alpha_rho: f32,
        /// First point projected on the line, mm.
        start: [f32; 2],
        /// Last point projected on the line, mm.
        end: [f32; 2],
    },
    /// A circle or arc.
    Circle {
        /// First beam index.
        first: usize,
        /// Last beam index.
        last: usize,
        /// Valid points fitted.
        points: usize,
        /// Centre, mm.
        center: [f32; 2],
        /// Radius, mm.
        radius: f32,
        /// Covariance of (centre x, centre y, radius), mm², row by row; symmetric to the bit.
        cov: [[f32; 3]; 3],
        /// Bearing from the centre to the first point, rad.
        start_angle: f32,
        /// Bearing from the centre to the last point, rad.
        end_angle: f32,
    },
    /// A small object (a leg, a post): a short run of returns apart from its neighbours.
    Object {
        /// First beam index.
        first: usize,
        /// Last beam index.
        last: usize,
        /// Valid points.
        points: usize,
        /// Centre (the mean of its points), mm.
        center: [f32; 2],
        /// Covariance of the centre, mm², row by row; symmetric to the bit.
        cov: [[f32; 2]; 2],
        /// Extent across, mm.
        extent: f32,
    },
    /// A feature of a kind this version of pfe-formats does not know (never written by this
    /// workspace's pfe-core).
    Unknown {
        /// First beam index.
        first: usize,
        /// Last beam index.
        last: usize,
    },
}

/// `cov` with each off-diagonal pair set to the mean of the two (bit-symmetric output).
fn symmetrised(cov: [[f32; 3]; 3]) -> [[f32; 3]; 3] {
    let mut c = cov;
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        let m = 0.5 * (cov[i][j] + cov[j][i]);
        c[i][j] = m;
        c[j][i] = m;
    }
    c
}

impl From<&Feature> for FeatureJson {
    fn from(f: &Feature) -> Self {
        match f {
            Feature::Line(l) => FeatureJson::Line {
                first: usize::from(l.first),
                last: usize::from(l.last),
                points: usize::from(l.points),
                alpha: l.alpha,
                rho: l.rho,
                var_alpha: l.var_alpha,
                var_rho: l.var_rho,
                cov_alpha_rho: l.cov_alpha_rho,
                start: [l.start.x, l.start.y],
                end: [l.end.x, l.end.y],
            },
            Feature::Circle(c) => FeatureJson::Circle {
                first: usize::from(c.first),
                last: usize::from(c.last),
                points: usize::from(c.points),
                center: [c.center.x, c.center.y],
                radius: c.radius,
                cov: symmetrised(c.cov),
                start_angle: c.start_angle,
                end_angle: c.end_angle,
            },
            Feature::Object(o) => {
                let m = 0.5 * (o.cov[0][1] + o.cov[1][0]);
                FeatureJson::Object {
                    first: usize::from(o.first),
                    last: usize::from(o.last),
                    points: usize::from(o.points),
                    center: [o.center.x, o.center.y],
                    cov: [[o.cov[0][0], m], [m, o.cov[1][1]]],
                    extent: o.extent,
                }
            }
            f => FeatureJson::Unknown {
                first: f.first(),
                last: f.last(),
            },
        }
    }
}

/// How a scan's extraction went: `{"error": null | "feature_capacity" | "too_many_readings" |
/// "invalid_input", "dropped": N}`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct StatusJson {
    /// Why the extraction failed or was incomplete, if it was.
    pub error: Option<String>,
    /// Features found but dropped for the extractor's capacity.
    pub dropped: usize,
}

impl StatusJson {
    /// The status of an extraction's result.
    pub fn of(result: &Result<(), pfe_core::ExtractError>) -> Self {
        use pfe_core::ExtractError as E;
        let (error, dropped) = match result {
            Ok(()) => (None, 0),
            Err(E::FeatureCapacity { dropped }) => (Some("feature_capacity"), *dropped),
            Err(E::TooManyReadings { .. }) => (Some("too_many_readings"), 0),
            Err(_) => (Some("invalid_input"), 0),
        };
        Self {
            error: error.map(str::to_string),
            dropped,
        }
    }
}

/// One line of `pfe extract` output: `{"scan": ID, "marks": [...], "features": [...],
/// "status": {...}}`, with `time` and `pose` when the input has them (`docs/JSON.md`).
///
/// ```
/// use pfe_formats::ScanJson;
/// use pfe_formats::Extraction;
/// let j = ScanJson::new(3, &Extraction { marks: vec![0, 9], features: vec![] });
/// assert_eq!(
///     serde_json::to_string(&j).unwrap(),
///     r#"{"scan":3,"marks":[0,9],"features":[],"status":{"error":null,"dropped":0}}"#
/// );
/// ```
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ScanJson {
    /// Scan ID.
    pub scan: u64,
    /// Timestamp of the input scan, s (CARMEN, Hokuyo), when it has one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time: Option<f64>,
    /// Pose of the robot of the input scan, `[x m, y m, θ rad]` (CARMEN), when it has one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pose: Option<[f64; 3]>,
    /// Mark points (beam indices); absent from `pfe listen` (not on the wire).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub marks: Option<Vec<usize>>,
    /// Features in scan order.
    pub features: Vec<FeatureJson>,
    /// Mixed pixels: points of lines the scanner cannot see, in no feature (beam indices);
    /// absent when there are none.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub veils: Vec<usize>,
    /// How the extraction went.
    pub status: StatusJson,
}

impl ScanJson {
    /// The output line for scan `id` (status ok).
    pub fn new(id: u64, extraction: &Extraction) -> Self {
        Self {
            scan: id,
            time: None,
            pose: None,
            marks: Some(extraction.marks.clone()),
            features: extraction.features.iter().map(FeatureJson::from).collect(),
            veils: Vec::new(),
            status: StatusJson::default(),
        }
    }

    /// With the extraction's mixed pixels (`pfe_core::Extractor::is_veil`).
    pub fn with_veils(mut self, veils: Vec<usize>) -> Self {
        self.veils = veils;
        self
    }

    /// With the extraction's status.
    pub fn with_status(mut self, status: StatusJson) -> Self {
        self.status = status;
        self
    }

    /// With the input scan's time and pose, when its format has them.
    pub fn with_input(mut self, record: &Record) -> Self {
        self.time = record.time;
        self.pose = record.pose;
        self
    }
}
