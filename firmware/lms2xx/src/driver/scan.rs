//! The scan the driver delivers: one B0 telegram's values in a fixed buffer.

use crate::codec::reply::{self, Measurement, Status};
use crate::codec::types::{MeasuringMode, Unit, Variant};

/// Most values in one B0 telegram (the largest LMS2xx scan: 100° at 0.25°).
pub const MAX_VALUES: usize = Variant::MAX_VALUES;

/// One decoded B0 scan, copied into the driver's fixed buffer.
#[derive(Clone, Debug, PartialEq)]
pub struct ScanData {
    count_word: u16,
    n: usize,
    words: [u16; MAX_VALUES],
    codes: [u16; MAX_VALUES],
    /// Status byte of the telegram.
    pub status: Status,
    /// Real-time scan index, if the device sends it.
    pub scan_index: Option<u8>,
    /// Measuring mode used to split the words.
    pub mode: MeasuringMode,
    /// Variant the driver configured.
    pub variant: Variant,
    /// Sequence number of this scan in the driver (1 = first).
    pub seq: u32,
    /// The driver's clock when the scan was accepted (its telegram complete), ms.
    pub time_ms: u32,
}

impl Default for ScanData {
    fn default() -> Self {
        Self {
            count_word: 0,
            n: 0,
            words: [0; MAX_VALUES],
            codes: [0; MAX_VALUES],
            status: Status(0),
            scan_index: None,
            mode: MeasuringMode::default(),
            variant: Variant::default(),
            seq: 0,
            time_ms: 0,
        }
    }
}

impl ScanData {
    pub(super) fn fill(
        &mut self,
        v: &reply::MeasuredValues<'_>,
        status: Status,
        mode: MeasuringMode,
    ) {
        self.count_word = v.count_word();
        let mut n = 0;
        for ((w, c), word) in self
            .words
            .iter_mut()
            .zip(self.codes.iter_mut())
            .zip(v.words())
        {
            *w = word;
            *c = word & mode.range_mask();
            n += 1;
        }
        self.n = n;
        self.status = status;
        self.scan_index = v.scan_index();
        self.mode = mode;
    }

    /// Number of values.
    pub fn len(&self) -> usize {
        self.n
    }
    /// True when empty.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }
    /// The raw value words (range and flag bits).
    pub fn words(&self) -> &[u16] {
        self.words.get(..self.n).unwrap_or(&[])
    }
    /// The range codes (range bits only, per measuring mode).
    pub fn codes(&self) -> &[u16] {
        self.codes.get(..self.n).unwrap_or(&[])
    }
    /// The B0 count word.
    pub fn count_word(&self) -> u16 {
        self.count_word
    }
    /// Unit from the count word (falls back to cm for the undefined code).
    pub fn unit(&self) -> Unit {
        Unit::from_count_bits(self.count_word >> reply::count::UNIT_SHIFT).unwrap_or(Unit::Cm)
    }
    /// mm per range unit.
    pub fn mm_per_unit(&self) -> f32 {
        self.unit().mm_per_unit()
    }
    /// Largest valid range code for the measuring mode.
    pub fn max_valid(&self) -> u16 {
        self.mode.max_valid()
    }
    /// Value `i` split into code, flags and meaning.
    pub fn measurement(&self, i: usize) -> Option<Measurement> {
        self.words()
            .get(i)
            .map(|&w| Measurement::decode(w, self.mode))
    }
    /// Range of value `i` in mm, `None` for a reserved code, 0 or out of range.
    pub fn range_mm(&self, i: usize) -> Option<f32> {
        let c = *self.codes().get(i)?;
        (c != 0 && c <= self.max_valid()).then(|| f32::from(c) * self.mm_per_unit())
    }
}
