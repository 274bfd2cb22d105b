//! Hokuyo (ROS `LaserScan`) text dumps, one scan a line:
//! `topic stamp_s angle_min_rad angle_increment_rad range_min_m range_max_m n r_0 ... r_{n-1}`.
//!
//! Ranges in metres. A reading is no return when it is 0 (non-finite ranges were written as
//! 0), `nan` or `inf`, below `range_min` or above `range_max` (both from the line); a negative
//! range is an error. Blank lines and `#`
//! comments are skipped.
//!
//! ```
//! use pfe_formats::hokuyo::Reader;
//! let text = "/scan 1.5 -1.0 0.5 0.02 5.6 3 1.0 0 0.01\n";
//! let scan = Reader::new(Box::new(text.as_bytes())).next().unwrap().unwrap();
//! assert_eq!(scan.geometry.r_max, 5600.0);
//! assert!(scan.ranges_mm[0] == 1000.0 && scan.ranges_mm[1].is_nan() && scan.ranges_mm[2].is_nan());
//! ```

use std::io::BufRead;

use pfe_core::ScanGeometry;

use super::{check_beams, checked_record, number, ranges_mm, InputError, Lines, Record};

/// Streaming Hokuyo reader.
pub struct Reader {
    lines: Lines,
    count: u64,
}

impl Reader {
    /// Reads scans from `input`.
    pub fn new(input: Box<dyn BufRead>) -> Self {
        Self {
            lines: Lines::new(input),
            count: 0,
        }
    }
}

/// Parses one line (numbered `line`) as scan `id`.
pub fn parse_line(line: u64, id: u64, text: &str) -> Result<Record, InputError> {
    let mut t = text.split_ascii_whitespace();
    let _topic = t.next();
    let stamp: f64 = number(line, "stamp", t.next())?;
    let angle_min: f32 = number(line, "angle_min", t.next())?;
    let angle_inc: f32 = number(line, "angle_increment", t.next())?;
    let range_min: f32 = number(line, "range_min", t.next())?;
    let range_max: f32 = number(line, "range_max", t.next())?;
    let n: usize = number(line, "beam count", t.next())?;
    check_beams(line, n)?;
    let (lo, hi) = (range_min * 1000.0, range_max * 1000.0);
    // NaN and ±inf (as ROS writes non-finite ranges) fail the range test: no return.
    let ranges = ranges_mm(
        line,
        ("line", n),
        &mut t,
        |r| (r < 0.0).then_some("negative"),
        |mm| mm > 0.0 && mm >= lo && mm <= hi,
    )?;
    if let Some(extra) = t.next() {
        return Err(InputError::line(
            line,
            format!(
                "more than the declared {n} ranges (extra {})",
                super::quote(extra)
            ),
        ));
    }
    let geometry = ScanGeometry::new(angle_min, angle_inc, hi);
    let mut record = checked_record(line, id, geometry, ranges)?;
    record.time = Some(stamp).filter(|s| s.is_finite());
    Ok(record)
}

impl Iterator for Reader {
    type Item = Result<Record, InputError>;

    fn next(&mut self) -> Option<Self::Item> {
        let r = match self.lines.next_data_line()? {
            Ok((line, t)) => parse_line(line, self.count, t),
            Err(e) => Err(e),
        };
        match r {
            Ok(_) => self.count += 1,
            Err(_) => self.lines.stop(),
        }
        Some(r)
    }
}

#[cfg(test)]
mod tests {
    use super::parse_line;

    #[test]
    fn the_stamp_is_kept_as_the_scan_time() {
        let r = parse_line(1, 0, "/scan 1483992048.5 -0.1 0.1 0.02 5.6 3 1.0 1.0 1.0")
            .expect("a valid line");
        assert_eq!(r.time, Some(1_483_992_048.5));
        assert_eq!(r.pose, None);
    }
}
