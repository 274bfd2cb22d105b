//! `csv`: one scan a line, `ID,START_DEG,STEP_DEG,R_0,...,R_{N-1}`.
//!
//! Ranges in mm; 0, `NaN` or ≥ 8183 (the LMS reserved codes) = no return (a discontinuity),
//! so the maximum range is 8182 mm. Blank lines and lines starting with `#` are skipped. Any
//! other malformed line (missing field, a field that is not a number, a negative or infinite
//! range, more than [`MAX_BEAMS`](crate::MAX_BEAMS) ranges, beams spanning more than
//! 360°) is an error with its line number.
//!
//! ```
//! use pfe_formats::csv::Reader;
//! let mut r = Reader::new(Box::new("1,-90,0.5,1000,9000,1000,1000\n".as_bytes()));
//! let scan = r.next().unwrap().unwrap();
//! assert!((scan.geometry.angle_step - 0.5f32.to_radians()).abs() < 1e-7);
//! assert!(scan.ranges_mm[1].is_nan());
//! ```

use std::io::BufRead;

use pfe_core::ScanGeometry;

use super::{check_beams, checked_record, number, quote, InputError, Lines, Record};

/// Largest valid range, mm (8183 and above are the LMS "no return" codes).
pub const MAX_RANGE_MM: f32 = 8182.0;

/// Streaming csv reader.
pub struct Reader {
    lines: Lines,
}

impl Reader {
    /// Reads scans from `input`.
    pub fn new(input: Box<dyn BufRead>) -> Self {
        Self {
            lines: Lines::new(input),
        }
    }
}

/// Parses one csv line (numbered `line` for errors).
pub fn parse_line(line: u64, text: &str) -> Result<Record, InputError> {
    let mut fields = text.split(',');
    let id: u64 = number(line, "scan ID (field 1)", fields.next())?;
    let start_deg: f32 = number(line, "START_DEG (field 2)", fields.next())?;
    let step_deg: f32 = number(line, "STEP_DEG (field 3)", fields.next())?;
    let mut ranges = Vec::new();
    for (k, token) in fields.enumerate() {
        let what = format!("range {k} (field {})", k + 4);
        let r: f32 = number(line, &what, Some(token))?;
        if r.is_nan() {
            ranges.push(f32::NAN);
            continue;
        }
        if !(r.is_finite() && r >= 0.0) {
            return Err(InputError::line(
                line,
                format!("{what} is not a range in mm: {}", quote(token)),
            ));
        }
        ranges.push(if r == 0.0 || r > MAX_RANGE_MM {
            f32::NAN
        } else {
            r
        });
    }
    check_beams(line, ranges.len())?;
    let span = (ranges.len() as f64 - 1.0) * f64::from(step_deg).abs();
    if span > 360.0 + 1e-9 {
        return Err(InputError::line(
            line,
            format!(
                "{} beams {step_deg}° apart span {span}°, more than a full turn",
                ranges.len()
            ),
        ));
    }
    let geometry = ScanGeometry::new(start_deg.to_radians(), step_deg.to_radians(), MAX_RANGE_MM);
    checked_record(line, id, geometry, ranges)
}

impl Iterator for Reader {
    type Item = Result<Record, InputError>;

    fn next(&mut self) -> Option<Self::Item> {
        let r = match self.lines.next_data_line()? {
            Ok((line, t)) => parse_line(line, t),
            Err(e) => Err(e),
        };
        if r.is_err() {
            self.lines.stop();
        }
        Some(r)
    }
}
