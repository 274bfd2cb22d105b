//! CARMEN logs: the front laser's scans, from one kind of line ([`Reader`]):
//! - `FLASER n r_1 ... r_n x y θ odom_x odom_y odom_θ timestamp host logger_ts` (old format):
//!   180° field (see the angle convention below), the first pose taken as the laser's;
//! - `ROBOTLASER1 laser_type start_angle field_of_view angular_resolution maximum_range accuracy
//!   remission_mode n r_1 ... r_n num_remissions remission_1 ... laser_x laser_y laser_θ robot_x
//!   robot_y robot_θ tv rv forward_safety_dist side_safety_dist turn_axis timestamp host
//!   logger_ts` (new format; older lines without the remissions and the turn axis are read
//!   too): beam i at `start_angle + i·angular_resolution`, no return at or beyond
//!   `maximum_range`, the laser's pose; a `laser_type` of a scanner that is not a SICK LMS
//!   (2–6: Hokuyo URG, simulated, S300, and in some CARMEN versions lasers emulated from
//!   cameras) declares one sweep ([`Record::sweeps`]);
//! - `RAWLASER1` (the same up to the remissions, then `timestamp host logger_ts`): no pose.
//!
//! Ranges are in metres (x forward, y left, beams counter-clockwise from the right). Every
//! other line (`ODOM`, `PARAM`, `NEFF`, `RLASER`, `ROBOTLASER2`, `TRUEPOS`, … — any upper-case
//! message name — and `#` comments) is skipped; a line that is neither is an error. The pose
//! (`x y θ`, m and rad: in the shared `*-corrected` logs the corrected pose) and the timestamp
//! (s) go to [`Record::pose`] and [`Record::time`] when they are numbers (`None` otherwise).
//!
//! # No return
//! A reading is no return when it is 0 or at or beyond the maximum range `r_max`. For
//! `ROBOTLASER1` and `RAWLASER1` lines that is the line's `maximum_range` (at most 81.83 m, the
//! LMS "8183" code). For `FLASER` lines it is 50 m by default,
//! which removes the 81.83 / 81.91 codes (the LMS "8183"/"8191" in cm) and the ≈ 50–51.2 m
//! no-return values some loggers write. When the log declares `PARAM robot_front_laser_max` of
//! 80 m or more (the Freiburg logs, in the 80 m mode) `r_max` is 81.83 m instead, so that the
//! genuine 50–80 m returns of outdoor logs (freiburg-campus) are kept.
//!
//! # Angle convention
//! A `FLASER` line stores no angles. [`AngleConvention::Auto`] (the default) uses, for n beams:
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
//! use pfe_formats::carmen::Reader;
//! let log = "ODOM 0 0 0 0 0 0 0 x 0\nFLASER 5 1.0 81.83 2.5 2.5 2.5 0 0 0 0 0 0 0 host 0\n";
//! let scan = Reader::new(Box::new(log.as_bytes())).next().unwrap().unwrap();
//! assert_eq!(scan.ranges_mm.len(), 5);
//! assert!((scan.ranges_mm[0] - 1000.0).abs() < 1e-3 && scan.ranges_mm[1].is_nan());
//! assert_eq!((scan.pose, scan.time), (Some([0.0, 0.0, 0.0]), Some(0.0)));
//! ```

use std::f32::consts::PI;
use std::io::BufRead;

use pfe_core::ScanGeometry;

mod laser;

pub use laser::Laser;

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
    /// use pfe_formats::carmen::AngleConvention;
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
        ScanGeometry::new(-PI / 2.0, PI / intervals.max(1) as f32, r_max)
    }
}

/// `RAWLASER1` lines held (unread) while no message with a pose has come (see [`Reader`]).
const HOLD: usize = 512;

/// Streaming reader of the front laser's scans of a CARMEN log.
///
/// A log may hold each scan several times: as `FLASER` (old format), `ROBOTLASER1` (new
/// format, with the laser's pose) and `RAWLASER1` (the driver's, no pose). The reader takes
/// one kind, the first of `FLASER` and `ROBOTLASER1` in the log, and skips the others; a log
/// with neither (no `FLASER` or `ROBOTLASER1` line among its first 512 `RAWLASER1` lines)
/// is read from its `RAWLASER1` lines. Lines of a kind it skips are not read, so they cannot
/// fail it.
pub struct Reader {
    lines: Lines,
    convention: AngleConvention,
    r_max: f32,
    count: u64,
    /// The kind read, once known.
    laser: Option<Laser>,
    /// `RAWLASER1` lines (number, text after the name) met before the kind is known.
    held: std::collections::VecDeque<(u64, String)>,
    /// An error met while lines were held: it comes after them.
    deferred: Option<InputError>,
    /// The odometry pose of the last scan read (`FLASER` only).
    odometry: Option<[f64; 3]>,
}

impl Reader {
    /// Reads scans from `input` with the default angle convention.
    pub fn new(input: Box<dyn BufRead>) -> Self {
        Self::with_convention(input, AngleConvention::Auto)
    }

    /// Reads scans from `input` with `convention` (for `FLASER` lines).
    pub fn with_convention(input: Box<dyn BufRead>, convention: AngleConvention) -> Self {
        Self {
            lines: Lines::new(input),
            convention,
            r_max: DEFAULT_MAX_RANGE_MM,
            count: 0,
            laser: None,
            held: std::collections::VecDeque::new(),
            deferred: None,
            odometry: None,
        }
    }

    /// The wheel-odometry pose (x m, y m, θ rad) of the last scan returned, when its line
    /// carries one as numbers (`FLASER`'s `odom_x odom_y odom_θ`; `None` for the other kinds).
    ///
    /// ```
    /// use pfe_formats::carmen::Reader;
    /// let log = "FLASER 5 1 2 3 4 5 0.5 0 0 10.25 -3 0.5 7.0 host 7.0\n";
    /// let mut r = Reader::new(Box::new(log.as_bytes()));
    /// assert!(r.next().is_some_and(|s| s.is_ok()));
    /// assert_eq!(r.odometry(), Some([10.25, -3.0, 0.5]));
    /// ```
    pub fn odometry(&self) -> Option<[f64; 3]> {
        self.odometry
    }

    /// The kind of message read (`None` before the first scan).
    pub fn laser(&self) -> Option<Laser> {
        self.laser
    }

    fn flaser(&mut self, line: u64, rest: &str) -> Result<Record, InputError> {
        let mut tokens = rest.split_ascii_whitespace();
        let n: usize = number(line, "beam count", tokens.next())?;
        check_beams(line, n)?;
        let r_max = self.r_max;
        let ranges = ranges_mm(line, ("FLASER", n), &mut tokens, not_metres, |mm| {
            mm > 0.0 && mm < r_max
        })?;
        // The laser pose, odometry pose and timestamp must follow the ranges.
        let Some(x) = tokens.next() else {
            return Err(InputError::line(
                line,
                "FLASER line truncated after the ranges (no pose)",
            ));
        };
        let rest: Vec<&str> = tokens.take(6).collect();
        let field = |k: usize| rest.get(k).and_then(|t| t.parse::<f64>().ok());
        let geometry = self.convention.geometry(n, self.r_max);
        let mut record = checked_record(line, 0, geometry, ranges)?;
        record.pose = pose([x.parse::<f64>().ok(), field(0), field(1)]);
        record.time = field(5).filter(|t| t.is_finite());
        self.odometry = pose([field(2), field(3), field(4)]);
        Ok(record)
    }

    /// Reads a scan of kind `laser` from the rest of line `line`.
    fn read(&mut self, line: u64, rest: &str, laser: Laser) -> Result<Record, InputError> {
        self.odometry = None;
        match laser {
            Laser::Flaser => self.flaser(line, rest),
            _ => laser::read(line, rest, laser, self.r_max),
        }
    }

    /// Numbers a scan read for the caller (or passes on the error that ends the stream).
    fn emit(&mut self, r: Result<Record, InputError>) -> Result<Record, InputError> {
        match r {
            Ok(mut record) => {
                record.id = self.count;
                self.count += 1;
                Ok(record)
            }
            Err(e) => {
                // An error ends the stream.
                self.lines.stop();
                self.held.clear();
                self.deferred = None;
                Err(e)
            }
        }
    }
}

impl Iterator for Reader {
    type Item = Result<Record, InputError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            if self.laser == Some(Laser::RawLaser1) {
                if let Some((line, rest)) = self.held.pop_front() {
                    let r = self.read(line, &rest, Laser::RawLaser1);
                    return Some(self.emit(r));
                }
                if let Some(e) = self.deferred.take() {
                    return Some(self.emit(Err(e)));
                }
            }
            let (line, text) = match self.lines.next_line() {
                Some(Ok(l)) => l,
                Some(Err(e)) if !self.held.is_empty() => {
                    self.laser = Some(Laser::RawLaser1);
                    self.deferred = Some(e);
                    continue;
                }
                Some(Err(e)) => return Some(Err(e)),
                None if !self.held.is_empty() => {
                    // A log with only RAWLASER1 scans.
                    self.laser = Some(Laser::RawLaser1);
                    continue;
                }
                None => return None,
            };
            let t = text.trim_start();
            let (kind, rest) = t.split_once(char::is_whitespace).unwrap_or((t, ""));
            let rest = rest.to_string();
            if let Some(laser) = Laser::of(kind) {
                match self.laser {
                    Some(l) if l != laser => continue,
                    Some(_) => {}
                    None if laser == Laser::RawLaser1 => {
                        self.held.push_back((line, rest));
                        if self.held.len() >= HOLD {
                            self.laser = Some(Laser::RawLaser1);
                        }
                        continue;
                    }
                    None => {
                        self.laser = Some(laser);
                        self.held.clear();
                    }
                }
                let r = self.read(line, &rest, laser);
                return Some(self.emit(r));
            }
            match kind {
                "" => continue,
                _ if kind.starts_with('#') => continue,
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
                _ => {
                    let e = InputError::line(
                        line,
                        format!("not a CARMEN log line (starts with {:?})", truncate(kind)),
                    );
                    if !self.held.is_empty() {
                        // The held scans come first.
                        self.laser = Some(Laser::RawLaser1);
                        self.deferred = Some(e);
                        continue;
                    }
                    return Some(self.emit(Err(e)));
                }
            }
        }
    }
}

/// Why a range in metres is an error (`None`: it is fine).
fn not_metres(r: f32) -> Option<&'static str> {
    (!(r.is_finite() && r >= 0.0)).then_some("not a range in metres")
}

/// A pose from its three fields, when all are finite numbers.
fn pose(fields: [Option<f64>; 3]) -> Option<[f64; 3]> {
    match fields {
        [Some(x), Some(y), Some(t)] if x.is_finite() && y.is_finite() && t.is_finite() => {
            Some([x, y, t])
        }
        _ => None,
    }
}

/// Whether the file name `name` is a CARMEN log's: `*.log` or `*.clf`, gzipped or not.
///
/// ```
/// use pfe_formats::carmen::is_log_name;
/// for name in ["intel-corrected.log.gz", "fr079.clf", "mit-killian.clf.gz", "run.log"] {
///     assert!(is_log_name(name), "{name}");
/// }
/// for name in ["README.md", "notes.gz", "x.log.gz.bak"] {
///     assert!(!is_log_name(name), "{name}");
/// }
/// ```
pub fn is_log_name(name: &str) -> bool {
    let n = name.strip_suffix(".gz").unwrap_or(name);
    n.ends_with(".log") || n.ends_with(".clf")
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
mod tests;
