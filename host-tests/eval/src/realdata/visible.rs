//! What a consumer can use of a scan's features (issue 39): lines the scanner cannot have seen
//! as a surface (at more than [`MAX_INCIDENCE_DEG`] incidence from the scanner at their
//! midpoint, or shorter than [`MIN_LINE_MM`]) and the small objects of a scan (runs of at least
//! [`OBJECT_MIN_POINTS`] returns, a range jump of at least [`OBJECT_JUMP_MM`] or no return on
//! both sides, at most [`OBJECT_MAX_MM`] across) that some feature covers.
//!
//! ```
//! use pfe_eval::realdata::visible::{small_objects, Visibility};
//! use pfe_core::ScanGeometry;
//! let g = ScanGeometry::LMS200_180_050;
//! // A post 1 m ahead over beams 179–181, the rest 5 m away.
//! let ranges: Vec<f32> = (0..361).map(|i| if (179..=181).contains(&i) { 1000.0 } else { 5000.0 }).collect();
//! assert_eq!(small_objects(&g, &ranges), vec![(179, 181)]);
//! let mut v = Visibility::default();
//! v.add(&g, &ranges, &[]);
//! assert_eq!((v.objects, v.covered), (1, 0));
//! ```

use pfe_core::{Feature, ScanGeometry};

/// Incidence beyond which a line is not a surface the beams could have measured, degrees.
pub const MAX_INCIDENCE_DEG: f32 = 85.0;
/// Shortest line a consumer can use, mm.
pub const MIN_LINE_MM: f32 = 10.0;
/// Fewest returns of a small object.
pub const OBJECT_MIN_POINTS: usize = 3;
/// Range jump that separates a small object from its neighbours, mm.
pub const OBJECT_JUMP_MM: f32 = 300.0;
/// Widest small object, mm (the distance between its outermost points).
pub const OBJECT_MAX_MM: f32 = 300.0;

/// A line's incidence from the scanner at its midpoint, degrees: the angle between the beam to
/// its midpoint and its normal (90° for a line through the scanner).
pub fn incidence_deg(alpha: f32, start: [f32; 2], end: [f32; 2]) -> f32 {
    let (mx, my) = (0.5 * (start[0] + end[0]), 0.5 * (start[1] + end[1]));
    let d = mx.hypot(my);
    if d.is_nan() || d <= 0.0 {
        return 90.0;
    }
    let c = ((mx * alpha.cos() + my * alpha.sin()) / d).abs().min(1.0);
    c.acos().to_degrees()
}

/// The point of beam `i` of a scan of `g` with `ranges` (mm, NaN: no return).
fn point(g: &ScanGeometry, ranges: &[f32], i: usize) -> Option<(f32, f32)> {
    let r = *ranges.get(i)?;
    if !r.is_finite() || r <= 0.0 || r > g.r_max {
        return None;
    }
    let b = g.bearing(i);
    Some((r * b.cos(), r * b.sin()))
}

/// The small objects of a scan of `g` with `ranges`: first and last beam of each.
pub fn small_objects(g: &ScanGeometry, ranges: &[f32]) -> Vec<(usize, usize)> {
    let n = ranges.len();
    let mut out = Vec::new();
    let mut i = 0;
    while i < n {
        if point(g, ranges, i).is_none() {
            i += 1;
            continue;
        }
        // The run of returns from i without a jump.
        let mut j = i;
        while j + 1 < n
            && point(g, ranges, j + 1).is_some()
            && (ranges[j + 1] - ranges[j]).abs() < OBJECT_JUMP_MM
        {
            j += 1;
        }
        if j + 1 - i >= OBJECT_MIN_POINTS {
            let (a, b) = (point(g, ranges, i), point(g, ranges, j));
            if let (Some(a), Some(b)) = (a, b) {
                // Across: the widest distance from the first point (a run this short is near
                // straight or a small arc).
                let wide = (i..=j)
                    .filter_map(|k| point(g, ranges, k))
                    .map(|p| (p.0 - a.0).hypot(p.1 - a.1))
                    .fold(0.0f32, f32::max)
                    .max((b.0 - a.0).hypot(b.1 - a.1));
                if wide <= OBJECT_MAX_MM {
                    out.push((i, j));
                }
            }
        }
        i = j + 1;
    }
    out
}

/// One feature as the counts read it (from pfe-core or from pfe's JSON).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Seen {
    /// First and last beam.
    pub first: usize,
    /// Last beam.
    pub last: usize,
    /// For a line: its incidence at the midpoint (degrees) and its length (mm).
    pub line: Option<(f32, f32)>,
}

impl From<&Feature> for Seen {
    fn from(f: &Feature) -> Self {
        let line = match f {
            Feature::Line(l) => {
                let (s, e) = ([l.start.x, l.start.y], [l.end.x, l.end.y]);
                Some((
                    incidence_deg(l.alpha, s, e),
                    (e[0] - s[0]).hypot(e[1] - s[1]),
                ))
            }
            _ => None,
        };
        Self {
            first: f.first(),
            last: f.last(),
            line,
        }
    }
}

/// Counts over scans.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Visibility {
    /// Scans counted.
    pub scans: usize,
    /// Lines.
    pub lines: usize,
    /// Lines at more than [`MAX_INCIDENCE_DEG`].
    pub steep: usize,
    /// Lines shorter than [`MIN_LINE_MM`].
    pub short: usize,
    /// Small objects.
    pub objects: usize,
    /// Small objects at least half of whose returns some feature holds.
    pub covered: usize,
}

impl Visibility {
    /// Counts one scan of `g` with `ranges` and its `features`.
    pub fn add(&mut self, g: &ScanGeometry, ranges: &[f32], features: &[Seen]) {
        self.scans += 1;
        for f in features {
            if let Some((inc, len)) = f.line {
                self.lines += 1;
                self.steep += usize::from(inc > MAX_INCIDENCE_DEG);
                self.short += usize::from(len < MIN_LINE_MM);
            }
        }
        for (a, b) in small_objects(g, ranges) {
            self.objects += 1;
            let returns = (a..=b).filter(|&k| point(g, ranges, k).is_some()).count();
            let held = (a..=b)
                .filter(|&k| point(g, ranges, k).is_some())
                .filter(|&k| features.iter().any(|f| (f.first..=f.last).contains(&k)))
                .count();
            self.covered += usize::from(2 * held >= returns);
        }
    }

    /// Small objects covered, % (100 when there are none).
    pub fn covered_pct(&self) -> f64 {
        match self.objects {
            0 => 100.0,
            n => 100.0 * self.covered as f64 / n as f64,
        }
    }
}
