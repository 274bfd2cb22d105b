//! CARMEN logs: `FLASER n r_1 ... r_n x y θ odom_x odom_y odom_θ timestamp host logger_ts`.
//!
//! Ranges are in metres; the field of view is 180°, centred on x (x forward, y left, beams
//! counter-clockwise from the right). Every other line (`ODOM`, `PARAM`, `NEFF`, `RLASER`,
//! `TRUEPOS`, … — any upper-case message name — and `#` comments) is skipped; a line that is
//! neither is an error. The first pose (`x y θ`, m and rad: in the shared `*-corrected` logs the
//! corrected pose, taken as the laser's) and the timestamp (s) go to [`Record::pose`] and
//! [`Record::time`] when they are numbers (`None` otherwise).
//!
//! # No return
//! A reading is no return when it is at or beyond the maximum range `r_max`: 50 m by default,
//! which removes the 81.83 / 81.91 codes (the LMS "8183"/"8191" in cm) and the ≈ 50–51.2 m
//! no-return values some loggers write. When the log declares `PARAM robot_front_laser_max` of
//! 80 m or more (the Freiburg logs, in the 80 m mode) `r_max` is 81.83 m instead, so that the
//! genuine 50–80 m returns of outdoor logs (freiburg-campus) are kept.
//!
//! # Angle convention
//! The line stores no angles. [`AngleConvention::Auto`] (the default) uses, for n beams:
//! - n odd (181, 361): bearing_i = −90° + i·180°/(n−1), both end beams present;
//! - n even (180, 360): bearing_i = −90° + i·180°/n, the +90° end beam dropped.
//!
//! Checked on the ten real logs in `../shared/data/carmen` (test `carmen_angle_convention` in
//! `tests/cli_real_data.rs`) on straight walls (runs of ≥ 20 beams within 50 mm of their fitted
//! line). The two conventions differ only in the step, by a factor n/(n−1):
//! - The RMS residual of the walls barely depends on it (a wrong step bends a wall only to
//!   second order): 8.9–20.8 mm under both, differences ≤ 0.15 mm.
//! - The relative directions of wall pairs do: reading with a step (1 + ε) times the true one
//!   turns each wall by ε·u (u: mid bearing + 90° + ½ sin 2·incidence), so pairs that should
//!   be parallel or perpendicular deviate by ε·Δu. ε estimated by least squares over the nearly
//!   rectilinear pairs, reading at 180°/n (so ε ≈ 0 if 180°/n is right, −1/n if 180°/(n−1) is;
//!   the estimator recovers −0.0046 for −0.0055 on synthetic rooms); ± = standard error over 10
//!   blocks of scans:
//!
//! | log | n | pairs | ε | −1/n | verdict |
//! |---|---|---|---|---|---|
//! | aces | 180 | 273 | +0.0015 ± 0.0010 | −0.0056 | 180°/n |
//! | fhw | 180 | 106 | +0.0013 ± 0.0012 | −0.0056 | 180°/n |
//! | infinite-corridor | 180 | 1892 | +0.0019 ± 0.0007 | −0.0056 | 180°/n |
//! | intel | 180 | 571 | −0.0009 ± 0.0005 | −0.0056 | 180°/n |
//! | edmonton | 180 | 13 | +0.0045 | −0.0056 | too few pairs |
//! | freiburg-079 | 360 | 9378 | −0.0010 ± 0.0004 | −0.0028 | 180°/n (favoured) |
//! | freiburg-101 | 360 | 331 | −0.0009 ± 0.0010 | −0.0028 | 180°/n (favoured) |
//! | freiburg-campus | 360 | 1060 | +0.0005 ± 0.0011 | −0.0028 | 180°/n |
//! | acapulco | 181 | 78 | −0.0006 ± 0.0033 | −0.0055 | inconclusive |
//! | csail | 361 | 586 | −0.0010 ± 0.0010 | −0.0028 | inconclusive |
//!
//! So for n even the data confirms 180°/n (decisively for the 180-beam logs). For n odd the
//! check cannot decide; 180°/(n−1) is kept, the layout of the LMS's own 181/361-value scans
//! (both end beams present). In acapulco the last of the 181 values is always exactly 50 (a
//! filler, read as no return).
//!
//! ```
//! use host_tests::formats::carmen::Reader;
//! let log = "ODOM 0 0 0 0 0 0 0 x 0\nFLASER 5 1.0 81.83 2.5 2.5 2.5 0 0 0 0 0 0 0 host 0\n";
//! let scan = Reader::new(Box::new(log.as_bytes())).next().unwrap().unwrap();
//! assert_eq!(scan.ranges_mm.len(), 5);
//! assert!((scan.ranges_mm[0] - 1000.0).abs() < 1e-3 && scan.ranges_mm[1].is_nan());
//! assert_eq!((scan.pose, scan.time), (Some([0.0, 0.0, 0.0]), Some(0.0)));
//! ```

use std::f32::consts::PI;
use std::io::BufRead;

use pfe_core::ScanGeometry;

use super::{check_beams, checked_record, number, ranges_mm, InputError, Lines, Record};

/// Default maximum range, mm: readings at or beyond it are no return.
pub const DEFAULT_MAX_RANGE_MM: f32 = 50_000.0;
/// Maximum range when the log declares an 80 m laser: the LMS "8183" code in cm.
pub const LONG_MAX_RANGE_MM: f32 = 81_830.0;

/// How beam indices map to bearings (the log does not say).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AngleConvention {
    /// `EndToEnd` for odd n, `DropEnd` for even n (see the module docs).
    #[default]
    Auto,
    /// −90° + i·180°/(n−1): the first beam at −90°, the last at +90°.
    EndToEnd,
    /// −90° + i·180°/n: the first beam at −90°, the +90° beam dropped.
    DropEnd,
}

impl AngleConvention {
    /// Geometry of an `n`-beam scan with maximum range `r_max` mm.
    ///
    /// ```
    /// use host_tests::formats::carmen::AngleConvention;
    /// let g = AngleConvention::Auto.geometry(181, 50_000.0);
    /// assert!((g.bearing(180) - std::f32::consts::FRAC_PI_2).abs() < 1e-5);
    /// let g = AngleConvention::Auto.geometry(180, 50_000.0);
    /// assert!((g.angle_step - 1f32.to_radians()).abs() < 1e-7);
    /// ```
    pub fn geometry(self, n: usize, r_max: f32) -> ScanGeometry {
        let end_to_end = match self {
            AngleConvention::Auto => n % 2 == 1,
            AngleConvention::EndToEnd => true,
            AngleConvention::DropEnd => false,
        };
        let intervals = if end_to_end { n.saturating_sub(1) } else { n };
        ScanGeometry {
            start_angle: -PI / 2.0,
            angle_step: PI / intervals.max(1) as f32,
            r_max,
        }
    }
}

/// Streaming reader of the `FLASER` scans of a CARMEN log.
pub struct Reader {
    lines: Lines,
    convention: AngleConvention,
    r_max: f32,
    count: u64,
}

impl Reader {
    /// Reads scans from `input` with the default angle convention.
    pub fn new(input: Box<dyn BufRead>) -> Self {
        Self::with_convention(input, AngleConvention::Auto)
    }

    /// Reads scans from `input` with `convention`.
    pub fn with_convention(input: Box<dyn BufRead>, convention: AngleConvention) -> Self {
        Self {
            lines: Lines::new(input),
            convention,
            r_max: DEFAULT_MAX_RANGE_MM,
            count: 0,
        }
    }

    fn flaser(&mut self, line: u64, rest: &str) -> Result<Record, InputError> {
        let mut tokens = rest.split_ascii_whitespace();
        let n: usize = number(line, "beam count", tokens.next())?;
        check_beams(line, n)?;
        let r_max = self.r_max;
        let ranges = ranges_mm(
            line,
            ("FLASER", n),
            &mut tokens,
            |r| (!(r.is_finite() && r >= 0.0)).then_some("not a range in metres"),
            |mm| mm > 0.0 && mm < r_max,
        )?;
        // The laser pose, odometry pose and timestamp must follow the ranges.
        let Some(x) = tokens.next() else {
            return Err(InputError::line(
                line,
                "FLASER line truncated after the ranges (no pose)",
            ));
        };
        let rest: Vec<&str> = tokens.take(6).collect();
        let field = |k: usize| rest.get(k).and_then(|t| t.parse::<f64>().ok());
        let pose = match (x.parse::<f64>().ok(), field(0), field(1)) {
            (Some(x), Some(y), Some(t)) if x.is_finite() && y.is_finite() && t.is_finite() => {
                Some([x, y, t])
            }
            _ => None,
        };
        let geometry = self.convention.geometry(n, self.r_max);
        let mut record = checked_record(line, self.count, geometry, ranges)?;
        record.pose = pose;
        record.time = field(5).filter(|t| t.is_finite());
        self.count += 1;
        Ok(record)
    }
}

impl Iterator for Reader {
    type Item = Result<Record, InputError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            let (line, text) = match self.lines.next_line()? {
                Ok(l) => l,
                Err(e) => return Some(Err(e)),
            };
            let t = text.trim_start();
            let (kind, rest) = t.split_once(char::is_whitespace).unwrap_or((t, ""));
            let rest = rest.to_string();
            let r = match kind {
                "" => continue,
                _ if kind.starts_with('#') => continue,
                "FLASER" => self.flaser(line, &rest),
                "PARAM" => {
                    let mut p = rest.split_ascii_whitespace();
                    if p.next() == Some("robot_front_laser_max") {
                        if let Some(v) = p.next().and_then(|v| v.parse::<f32>().ok()) {
                            self.r_max = if v >= 80.0 {
                                LONG_MAX_RANGE_MM
                            } else {
                                DEFAULT_MAX_RANGE_MM
                            };
                        }
                    }
                    continue;
                }
                _ if is_message_name(kind) => continue,
                _ => Err(InputError::line(
                    line,
                    format!("not a CARMEN log line (starts with {:?})", truncate(kind)),
                )),
            };
            if r.is_err() {
                self.lines.stop();
            }
            return Some(r);
        }
    }
}

/// CARMEN message names: upper-case letters, digits and `_`, starting with a letter.
fn is_message_name(s: &str) -> bool {
    s.starts_with(|c: char| c.is_ascii_uppercase())
        && s.chars()
            .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_')
}

fn truncate(s: &str) -> String {
    s.chars().take(20).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn first(log: &'static str) -> Record {
        match Reader::new(Box::new(log.as_bytes())).next() {
            Some(Ok(r)) => r,
            other => panic!("no scan: {other:?}"),
        }
    }

    #[test]
    fn pose_and_time_are_the_first_pose_and_the_timestamp() {
        let r = first("FLASER 5 1 2 3 4 5 1.5 -2.25 0.5 9 9 9 32.9068 host 33.5\n");
        assert_eq!(r.pose, Some([1.5, -2.25, 0.5]));
        assert_eq!(r.time, Some(32.9068));
    }

    #[test]
    fn missing_or_bad_pose_fields_give_none() {
        let r = first("FLASER 5 1 2 3 4 5 1.5 nan\n");
        assert_eq!((r.pose, r.time), (None, None));
        let r = first("FLASER 5 1 2 3 4 5 1.5 2 x 0 0 0 t host 0\n");
        assert_eq!((r.pose, r.time), (None, None));
    }
}
