//! Raw byte captures of an LMS200 serial line (ACK bytes, replies and 0xB0 telegrams, possibly
//! damaged), decoded with the firmware's incremental telegram decoder.
//!
//! Scan ID = 0-based ordinal of the good 0xB0 telegram. Geometry from the value count: 181 →
//! 180° at 1°, 361 → 180° at 0.5°, 101 / 201 / 401 → 100° at 1° / 0.5° / 0.25°, centred on x,
//! value 0 at the right. Unit (mm or cm) from the count word; in both the 8 m and 80 m modes
//! codes 0 and ≥ 8183 are no return, so the maximum range is 8182 mm (mm) or 81.82 m (cm).

use std::io::BufRead;

use pfe_core::ScanGeometry;

use lms2xx::codec::frame::{Decoder, Event, MAX_TELEGRAM};
use lms2xx::codec::reply::MeasuredValues;
use lms2xx::codec::reply::ReplyOptions;
use lms2xx::codec::types::{MeasuringMode, Unit as LmsUnit};

use super::{InputError, Location, Record};

/// Range unit of a telegram.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unit {
    /// Millimetres.
    Mm,
    /// Centimetres.
    Cm,
}

impl Unit {
    /// Millimetres per code.
    pub fn mm(self) -> f32 {
        match self {
            Unit::Mm => 1.0,
            Unit::Cm => 10.0,
        }
    }

    /// `"mm"` or `"cm"`.
    pub fn name(self) -> &'static str {
        match self {
            Unit::Mm => "mm",
            Unit::Cm => "cm",
        }
    }
}

/// One good 0xB0 telegram.
#[derive(Clone, Debug, PartialEq)]
pub struct Telegram {
    /// 0-based ordinal among the good 0xB0 telegrams.
    pub ordinal: u64,
    /// Range unit.
    pub unit: Unit,
    /// Range values (the 13 range bits of each word).
    pub ranges: Vec<u16>,
    /// Status byte.
    pub status: u8,
}

/// Largest valid code in the 8 m / 80 m modes.
pub const MAX_VALID: u16 = pfe_core::LMS_MAX_VALID_8M;

/// Geometry of a scan of `n` values (`None` for a count no LMS200 variant sends).
///
/// ```
/// use pfe_formats::lms200::{geometry, Unit};
/// let g = geometry(361, Unit::Mm).unwrap();
/// assert!((g.bearing(360) - std::f32::consts::FRAC_PI_2).abs() < 1e-5);
/// assert!(geometry(100, Unit::Mm).is_none());
/// ```
pub fn geometry(n: usize, unit: Unit) -> Option<ScanGeometry> {
    let (field, res) = match n {
        181 => (180.0, 1.0),
        361 => (180.0, 0.5),
        101 => (100.0, 1.0),
        201 => (100.0, 0.5),
        401 => (100.0, 0.25),
        _ => return None,
    };
    let mut g = ScanGeometry::lms200(field, res);
    g.r_max = f32::from(MAX_VALID) * unit.mm();
    Some(g)
}

impl Telegram {
    /// The scan as a [`Record`] (no-return codes as `NaN`); `None` for a count that matches no
    /// LMS200 variant (a partial scan: its beams' angles are unknown).
    pub fn record(&self) -> Option<Record> {
        let geometry = geometry(self.ranges.len(), self.unit)?;
        Some(Record {
            id: self.ordinal,
            geometry,
            ranges_mm: self
                .ranges
                .iter()
                .map(|&v| {
                    if v == 0 || v > MAX_VALID {
                        f32::NAN
                    } else {
                        f32::from(v) * self.unit.mm()
                    }
                })
                .collect(),
            time: None,
            pose: None,
            sweeps: None,
        })
    }
}

/// What the decoder saw in a whole capture.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Summary {
    /// Good 0xB0 telegrams.
    pub good: u64,
    /// Candidate telegrams dropped for a bad CRC.
    pub crc_errors: u64,
    /// Candidate telegrams dropped for an impossible length.
    pub bad_length: u64,
    /// Telegrams with a good CRC that are not 0xB0 (ACK bytes not counted).
    pub other_telegrams: u64,
    /// 0xB0 telegrams with a good CRC whose payload does not match their count word.
    pub malformed: u64,
    /// Good 0xB0 telegrams whose value count no LMS200 variant sends (181, 361, 101, 201, 401),
    /// e.g. partial scans: decoded, but not scans (their beam geometry is unknown).
    pub unknown_count: u64,
    /// Bytes skipped while hunting for a telegram (including a truncated one at the end).
    pub skipped: u64,
    /// Bytes read.
    pub bytes: u64,
}

/// Streaming reader of the good 0xB0 telegrams of a capture, built on the firmware's
/// [`Decoder`] (resynchronising, CRC-checked). Value words are masked
/// to their 13 range bits (measuring mode 0, the 8 m / 80 m modes); a B0 payload one byte
/// longer than its count word says is read as carrying the real-time scan index.
///
/// ```
/// use pfe_formats::lms200::{Reader, Unit};
/// // The protocol fact sheet's test vector: 5 values in mm, status 0x10, after an ACK.
/// let capture: &'static [u8] = &[0x06, 0x02, 0x80, 0x0E, 0x00, 0xB0, 0x05, 0x40, 0xE8, 0x03, 0xE9, 0x03,
///                0xEA, 0x03, 0xEB, 0x03, 0xFF, 0x1F, 0x10, 0x1F, 0x93];
/// let mut r = Reader::new(Box::new(capture));
/// let t = r.next().unwrap().unwrap();
/// assert_eq!((t.unit, t.ranges.as_slice(), t.status), (Unit::Mm, &[1000, 1001, 1002, 1003, 8191][..], 0x10));
/// assert!(r.next().is_none());
/// assert_eq!(r.summary().good, 1);
/// ```
pub struct Reader {
    input: Box<dyn BufRead>,
    decoder: Box<Decoder<MAX_TELEGRAM>>,
    summary: Summary,
    /// Input ended.
    done: bool,
    /// Padding bytes fed after the end (see `next`).
    padding: u64,
}

impl Reader {
    /// Reads telegrams from `input`.
    pub fn new(input: Box<dyn BufRead>) -> Self {
        Self {
            input,
            decoder: Box::new(Decoder::new()),
            summary: Summary::default(),
            done: false,
            padding: 0,
        }
    }

    /// Counts so far (complete once the iterator has ended).
    pub fn summary(&self) -> Summary {
        let st = self.decoder.stats();
        Summary {
            crc_errors: u64::from(st.crc_errors),
            bad_length: u64::from(st.bad_length) + u64::from(st.overflows),
            skipped: (u64::from(st.bytes_skipped) + self.decoder.pending() as u64)
                .saturating_sub(self.padding),
            ..self.summary
        }
    }

    /// Turns a telegram with a good CRC into a scan, counting what is not one.
    fn accept(&mut self, payload: &[u8]) -> Option<Telegram> {
        if payload.first() != Some(&0xB0) {
            self.summary.other_telegrams += 1;
            return None;
        }
        let parsed = MeasuredValues::parse(payload, ReplyOptions::default()).or_else(|_| {
            MeasuredValues::parse(payload, ReplyOptions::default().with_realtime_index(true))
        });
        let (Ok(values), Some(&status)) = (parsed, payload.last()) else {
            self.summary.malformed += 1;
            return None;
        };
        let unit = match values.unit() {
            Some(LmsUnit::Mm) => Unit::Mm,
            Some(LmsUnit::Cm) => Unit::Cm,
            _ => {
                self.summary.malformed += 1;
                return None;
            }
        };
        if geometry(values.words().count(), unit).is_none() {
            self.summary.unknown_count += 1;
        }
        let mode = MeasuringMode::M8_FIELDS_AB_DAZZLE;
        let ranges = values.words().map(|w| w & mode.range_mask()).collect();
        let t = Telegram {
            ordinal: self.summary.good,
            unit,
            ranges,
            status,
        };
        self.summary.good += 1;
        Some(t)
    }
}

impl Iterator for Reader {
    type Item = Result<Telegram, InputError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            // Events still buffered in the decoder (a telegram may start inside a rejected one).
            let (_, ev) = self.decoder.feed(&[]);
            if let Some(Event::Telegram(t)) = ev {
                let payload = t.payload().to_vec();
                if let Some(t) = self.accept(&payload) {
                    return Some(Ok(t));
                }
                continue;
            }
            if ev.is_some() {
                continue;
            }
            if self.done {
                // A truncated telegram at the end may hide good telegrams that started inside
                // it: complete it with padding so that the decoder rejects it and rescans.
                if self.decoder.pending() == 0 || self.padding >= 2 * MAX_TELEGRAM as u64 {
                    return None;
                }
                let (used, ev) = self.decoder.feed(&[0u8; 64]);
                self.padding += used as u64;
                if let Some(Event::Telegram(t)) = ev {
                    let payload = t.payload().to_vec();
                    if let Some(t) = self.accept(&payload) {
                        return Some(Ok(t));
                    }
                }
                continue;
            }
            let chunk = match self.input.fill_buf() {
                Ok(c) => c,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => {
                    self.done = true;
                    return Some(Err(InputError {
                        location: Location::Byte(self.summary.bytes),
                        message: format!("cannot read: {e}"),
                    }));
                }
            };
            if chunk.is_empty() {
                self.done = true;
                continue;
            }
            let (used, ev) = self.decoder.feed(chunk);
            let payload = match ev {
                Some(Event::Telegram(t)) => Some(t.payload().to_vec()),
                _ => None,
            };
            self.input.consume(used);
            self.summary.bytes += used as u64;
            if let Some(p) = payload {
                if let Some(t) = self.accept(&p) {
                    return Some(Ok(t));
                }
            }
        }
    }
}
