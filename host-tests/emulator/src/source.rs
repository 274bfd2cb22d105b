//! Where the emulated device's ranges come from: a room, a tagged pattern, or (through
//! [`RangeSource`]) the scene simulator.

/// Where emulated ranges come from. Another module's scene simulator plugs in here.
pub trait RangeSource: Send {
    /// Ranges in mm for `n_values` beams starting at `start_deg` (value 0, right-hand edge,
    /// 0° = straight ahead) in steps of `step_deg` counter-clockwise; NaN = no return.
    fn next_scan(&mut self, n_values: usize, start_deg: f32, step_deg: f32) -> Vec<f32>;
}

/// A rectangular room around the scanner (walls at `x = front`, `y = ±half_width`,
/// `x = -back`), the default source.
#[derive(Clone, Debug)]
pub struct RoomSource {
    /// Distance to the front wall, mm.
    pub front_mm: f32,
    /// Distance to the left and right walls, mm.
    pub half_width_mm: f32,
    /// Distance to the wall behind, mm.
    pub back_mm: f32,
}

impl Default for RoomSource {
    fn default() -> Self {
        Self {
            front_mm: 4000.0,
            half_width_mm: 2500.0,
            back_mm: 1000.0,
        }
    }
}

impl RoomSource {
    /// Range along bearing `deg`, mm.
    pub fn range(&self, deg: f32) -> f32 {
        let (s, c) = deg.to_radians().sin_cos();
        let mut best = f32::INFINITY;
        if c > 1e-6 {
            best = best.min(self.front_mm / c);
        }
        if c < -1e-6 {
            best = best.min(self.back_mm / -c);
        }
        if s.abs() > 1e-6 {
            best = best.min(self.half_width_mm / s.abs());
        }
        best
    }
}

impl RangeSource for RoomSource {
    fn next_scan(&mut self, n: usize, start_deg: f32, step_deg: f32) -> Vec<f32> {
        (0..n)
            .map(|i| self.range(start_deg + step_deg * i as f32))
            .collect()
    }
}

/// A source whose every scan is unique and recognisable: value 0 is `1000 + seq % 4000`,
/// value 1 is `1000 + seq / 4000`, the rest a seq-dependent pattern in 200..7200 mm.
/// [`TaggedSource::tag_of`] recovers `seq` from delivered ranges.
#[derive(Clone, Debug, Default)]
pub struct TaggedSource {
    next: u32,
}

impl TaggedSource {
    /// Ranges of scan `seq` with `n` values.
    pub fn ranges(seq: u32, n: usize) -> Vec<f32> {
        (0..n)
            .map(|i| match i {
                0 => 1000.0 + (seq % 4000) as f32,
                1 => 1000.0 + (seq / 4000) as f32,
                _ => 200.0 + ((seq as usize * 131 + i * 17) % 7000) as f32,
            })
            .collect()
    }
    /// The scan number encoded in the first two range codes (mm).
    pub fn tag_of(codes: &[u16]) -> Option<u32> {
        let a = u32::from(*codes.first()?).checked_sub(1000)?;
        let b = u32::from(*codes.get(1)?).checked_sub(1000)?;
        Some(b * 4000 + a)
    }
}

impl RangeSource for TaggedSource {
    fn next_scan(&mut self, n: usize, _start_deg: f32, _step_deg: f32) -> Vec<f32> {
        let r = Self::ranges(self.next, n);
        self.next += 1;
        r
    }
}

/// Which built-in source a config selects.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SourceKind {
    /// [`RoomSource::default`].
    #[default]
    Room,
    /// [`TaggedSource`].
    Tagged,
}

impl SourceKind {
    /// A fresh source of this kind.
    pub fn build(self) -> Box<dyn RangeSource> {
        match self {
            SourceKind::Room => Box::new(RoomSource::default()),
            SourceKind::Tagged => Box::new(TaggedSource::default()),
        }
    }
}
