//! Readers for recorded scans: one scan per line of `csv`, CARMEN logs (`FLASER`, `ROBOTLASER1`
//! or `RAWLASER1` lines), Hokuyo text dumps, and raw byte captures of a SICK LMS200 serial line.
//!
//! Every reader streams (line by line, or chunk by chunk for LMS200 captures), so files larger
//! than memory are fine, and reads gzip transparently (detected by its magic bytes). Each scan
//! comes out as a [`Record`]: the beam geometry and one range per beam in mm, `NaN` for no
//! return, so indices count every beam, valid or not. A malformed input yields an
//! [`InputError`] carrying the line number (or byte offset) and reading stops there.
//!
//! ```
//! use pfe_formats::{scans, Format};
//! let text = "7,-90,1,1000,0,1000\n";
//! let records: Vec<_> = scans(Format::Csv, Box::new(text.as_bytes())).collect();
//! let r = records[0].as_ref().unwrap();
//! assert_eq!((r.id, r.ranges_mm.len()), (7, 3));
//! assert!(r.ranges_mm[1].is_nan()); // 0 = no return
//! ```

#![forbid(unsafe_code)]

pub mod carmen;
pub mod csv;
pub mod docs;
pub mod hokuyo;
pub mod json;
pub mod lms200;
pub mod outfile;
mod quantum;
#[cfg(feature = "mcap")]
pub mod ros2;
#[cfg(feature = "mcap")]
pub mod ros2_stream;

pub use json::{FeatureJson, ScanJson, StatusJson};
pub use quantum::range_quantum;

use std::fmt;
use std::fs::File;
use std::io::{self, BufRead, BufReader, Read};
use std::path::Path;

use pfe_core::{Feature, ScanGeometry};

/// Capacity of the host extractor: any scanner up to 2048 beams, 256 features.
pub const MAX_BEAMS: usize = 2048;
/// Feature capacity of the host extractor.
pub const MAX_FEATURES: usize = 256;

/// What a method found in one scan. Indices count every beam, valid or not.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Extraction {
    /// Mark (boundary) points, increasing.
    pub marks: Vec<usize>,
    /// Features in scan order.
    pub features: Vec<Feature>,
}

/// Input file formats understood by `pfe`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// `ID,START_DEG,STEP_DEG,R_0,...,R_{N-1}`, ranges in mm (0 or ≥ 8183 = no return).
    Csv,
    /// CARMEN log: `FLASER` (180° field), `ROBOTLASER1` or `RAWLASER1` lines (metres, gzip
    /// allowed).
    Carmen,
    /// Raw byte capture of an LMS200 serial line (0xB0 telegrams, damage skipped).
    Lms200,
    /// `topic stamp angle_min angle_increment range_min range_max n r_0 ... r_{n-1}`.
    Hokuyo,
    /// ROS 2 bag (MCAP) with `sensor_msgs/msg/LaserScan` messages (see [`ros2`]).
    Mcap,
}

impl Format {
    /// Every format, in the order `pfe --help` lists them.
    pub const ALL: [Format; 5] = [
        Format::Csv,
        Format::Carmen,
        Format::Lms200,
        Format::Hokuyo,
        Format::Mcap,
    ];

    /// Range noise assumed for this format's data, mm: the LMS200 data sheet's 5 mm for
    /// mm-mode data (csv, lms200); 10 mm for CARMEN logs (cm-quantised LMS data) and for the
    /// Hokuyo URG-04LX (±10 mm at short range); 10 mm for ROS 2 bags, whose scanners are mostly
    /// of the Hokuyo URG and SICK LMS/TiM class. The `pfe` CLI's default for `--sigma-r`, and
    /// `pfe bench`'s σ_r for the CARMEN logs.
    pub fn sigma_r(self) -> f32 {
        match self {
            Format::Csv => 5.0,
            Format::Lms200 => pfe_core::config::LMS2XX_SIGMA_R,
            Format::Carmen | Format::Hokuyo | Format::Mcap => 10.0,
        }
    }
}

impl Format {
    /// Beam-to-beam systematic range error assumed for this format's data, mm
    /// (`pfe_core::Config::sigma_sys`): 5 mm for a real scanner's data (a SICK LMS200's data
    /// sheet: ±15 mm typical, taken as 3σ; the Hokuyo URG-04LX's ±10 mm accuracy is of that
    /// order too); 0 for csv, the simulator's format, whose scans have none. The `pfe` CLI's
    /// default for `--sigma-sys`.
    pub fn sigma_sys(self) -> f32 {
        match self {
            Format::Csv => 0.0,
            Format::Lms200 => pfe_core::config::LMS2XX_SIGMA_SYS,
            Format::Carmen | Format::Hokuyo | Format::Mcap => 5.0,
        }
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Format::Csv => "csv",
            Format::Carmen => "carmen",
            Format::Lms200 => "lms200",
            Format::Hokuyo => "hokuyo",
            Format::Mcap => "mcap",
        })
    }
}

/// One scan read from a file.
#[derive(Clone, Debug, PartialEq)]
pub struct Record {
    /// Scan ID: the csv ID column, otherwise the 0-based ordinal of the scan in the file.
    pub id: u64,
    /// Beam geometry (bearing of beam `i` = start + i·step; x forward, y left).
    pub geometry: ScanGeometry,
    /// One range per beam, mm; `NaN` = no return.
    pub ranges_mm: Vec<f32>,
    /// Time of the scan, s, when the format gives one (CARMEN).
    pub time: Option<f64>,
    /// Pose of the scanner (x m, y m, θ rad) when the format gives one (CARMEN).
    pub pose: Option<[f64; 3]>,
    /// The interleaved sweeps the input says the scan is made of (a CARMEN `ROBOTLASER1` or
    /// `RAWLASER1` line of a laser that is not a SICK LMS: 1); `None`: its format's rule
    /// ([`sweeps_of`]).
    pub sweeps: Option<u8>,
}

impl Record {
    /// Cartesian point of beam `i` in mm, if it has a return.
    pub fn point(&self, i: usize) -> Option<(f32, f32)> {
        let r = *self.ranges_mm.get(i)?;
        if !(r.is_finite() && r > 0.0 && r <= self.geometry.r_max) {
            return None;
        }
        let b = self.geometry.bearing(i);
        Some((r * b.cos(), r * b.sin()))
    }
}

/// Where in the input something went wrong.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// 1-based line number of a text format.
    Line(u64),
    /// 0-based byte offset of a binary format.
    Byte(u64),
}

/// A malformed or unreadable input.
#[derive(Debug)]
pub struct InputError {
    /// Where.
    pub location: Location,
    /// What, in one line.
    pub message: String,
}

impl InputError {
    /// An error at line `line`.
    pub fn line(line: u64, message: impl Into<String>) -> Self {
        Self {
            location: Location::Line(line),
            message: message.into(),
        }
    }
}

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.location {
            Location::Line(n) => write!(f, "line {n}: {}", self.message),
            Location::Byte(n) => write!(f, "byte {n}: {}", self.message),
        }
    }
}

impl std::error::Error for InputError {}

/// Stream of scans, stopping after the first error.
pub type Scans = Box<dyn Iterator<Item = Result<Record, InputError>>>;

/// Opens a text file `path` (`-` = stdin), decompressing gzip when the data starts with the
/// gzip magic bytes; see [`open_for`].
pub fn open(
    path: &Path,
    wrap: impl FnOnce(Box<dyn Read>) -> Box<dyn Read>,
) -> io::Result<Box<dyn BufRead>> {
    open_for(path, Format::Csv, wrap)
}

/// Opens `path` (`-` = stdin) for reading `format`, decompressing gzip when the data starts
/// with the gzip magic bytes (for the binary `lms200` format only when the name ends in
/// `.gz`, since a raw capture may start with any bytes; the same for `mcap`). `wrap` may wrap the raw file reader
/// (e.g. with a progress bar counting bytes).
pub fn open_for(
    path: &Path,
    format: Format,
    wrap: impl FnOnce(Box<dyn Read>) -> Box<dyn Read>,
) -> io::Result<Box<dyn BufRead>> {
    let raw: Box<dyn Read> = if path.as_os_str() == "-" {
        Box::new(io::stdin())
    } else {
        Box::new(File::open(path)?)
    };
    let mut reader = BufReader::with_capacity(1 << 16, wrap(raw));
    let sniff =
        !matches!(format, Format::Lms200 | Format::Mcap) || path.to_string_lossy().ends_with(".gz");
    if sniff && reader.fill_buf()?.starts_with(&[0x1f, 0x8b]) {
        Ok(Box::new(BufReader::with_capacity(
            1 << 16,
            flate2::bufread::MultiGzDecoder::new(reader),
        )))
    } else {
        Ok(Box::new(reader))
    }
}

/// The scans of `input` in `format`.
pub fn scans(format: Format, input: Box<dyn BufRead>) -> Scans {
    match format {
        Format::Csv => Box::new(csv::Reader::new(input)),
        Format::Carmen => Box::new(carmen::Reader::new(input)),
        Format::Hokuyo => Box::new(hokuyo::Reader::new(input)),
        Format::Lms200 => Box::new(lms200::Reader::new(input).filter_map(|t| match t {
            Ok(t) => {
                let record = t.record();
                if record.is_none() {
                    eprintln!(
                        "pfe: telegram {}: {} values match no LMS200 variant (181, 361, 101, \
                         201 or 401): its beams' angles are unknown, skipped",
                        t.ordinal,
                        t.ranges.len()
                    );
                }
                record.map(Ok)
            }
            Err(e) => Some(Err(e)),
        })),
        #[cfg(feature = "mcap")]
        Format::Mcap => ros2_stream::records(input),
        #[cfg(not(feature = "mcap"))]
        Format::Mcap => {
            drop(input);
            Box::new(std::iter::once(Err(InputError {
                location: Location::Byte(0),
                message:
                    "ROS 2 bags are not read: pfe-formats was built without its `mcap` feature"
                        .into(),
            })))
        }
    }
}

/// Longest accepted text line, bytes (a 2048-beam scan in any text format is far shorter).
pub const MAX_LINE: u64 = 1 << 20;

/// Line-by-line reader with line numbers, a bounded line length and a reused buffer.
pub(crate) struct Lines {
    input: Box<dyn BufRead>,
    buf: Vec<u8>,
    line: u64,
    done: bool,
}

impl Lines {
    pub(crate) fn new(input: Box<dyn BufRead>) -> Self {
        Self {
            input,
            buf: Vec::new(),
            line: 0,
            done: false,
        }
    }

    /// The next line (without its line ending) and its 1-based number; `None` at the end or
    /// after an error.
    pub(crate) fn next_line(&mut self) -> Option<Result<(u64, &str), InputError>> {
        if self.done {
            return None;
        }
        self.buf.clear();
        self.line += 1;
        let line = self.line;
        let n = match (&mut self.input)
            .take(MAX_LINE)
            .read_until(b'\n', &mut self.buf)
        {
            Ok(n) => n,
            Err(e) => {
                self.done = true;
                return Some(Err(InputError::line(line, format!("cannot read: {e}"))));
            }
        };
        if n == 0 {
            self.done = true;
            return None;
        }
        if n as u64 == MAX_LINE && self.buf.last() != Some(&b'\n') {
            self.done = true;
            return Some(Err(InputError::line(
                line,
                format!("line longer than {MAX_LINE} bytes"),
            )));
        }
        while matches!(self.buf.last(), Some(b'\n' | b'\r')) {
            self.buf.pop();
        }
        match std::str::from_utf8(&self.buf) {
            Ok(s) => Some(Ok((line, s))),
            Err(_) => {
                self.done = true;
                Some(Err(InputError::line(line, "not UTF-8 text")))
            }
        }
    }

    /// The next line that is neither blank nor a `#` comment, trimmed, and its number.
    pub(crate) fn next_data_line(&mut self) -> Option<Result<(u64, &str), InputError>> {
        loop {
            match self.next_line()? {
                Ok((_, text)) if is_blank_or_comment(text) => {}
                Ok((line, _)) => {
                    let text = std::str::from_utf8(&self.buf).unwrap_or("").trim();
                    return Some(Ok((line, text)));
                }
                Err(e) => return Some(Err(e)),
            }
        }
    }

    /// Stops reading (after an error).
    pub(crate) fn stop(&mut self) {
        self.done = true;
    }
}

fn is_blank_or_comment(text: &str) -> bool {
    let t = text.trim();
    t.is_empty() || t.starts_with('#')
}

/// Most characters of a bad field quoted in an error message.
pub const MAX_QUOTE: usize = 80;

/// `token` quoted for an error message: escaped like `{:?}`, cut after [`MAX_QUOTE`]
/// characters with "…" (a garbage "field" may be a megabyte long).
///
/// ```
/// use pfe_formats::quote;
/// assert_eq!(quote("x1000"), r#""x1000""#);
/// assert_eq!(quote(&"a".repeat(500)).chars().count(), 80 + 3);
/// ```
pub fn quote(token: &str) -> String {
    let head: String = token.chars().take(MAX_QUOTE).collect();
    let more = if head.len() < token.len() { "…" } else { "" };
    format!("\"{}{more}\"", head.escape_debug())
}

/// Parses a number field, naming it in the error.
pub(crate) fn number<T: std::str::FromStr>(
    line: u64,
    what: &str,
    token: Option<&str>,
) -> Result<T, InputError> {
    let token = token.ok_or_else(|| InputError::line(line, format!("missing {what}")))?;
    token
        .trim()
        .parse()
        .map_err(|_| InputError::line(line, format!("{what} is not a number: {}", quote(token))))
}

/// Checks a beam count against the extractor's capacity.
pub(crate) fn check_beams(line: u64, n: usize) -> Result<(), InputError> {
    if n == 0 {
        Err(InputError::line(line, "no ranges"))
    } else if n > MAX_BEAMS {
        Err(InputError::line(
            line,
            format!("{n} ranges, more than the {MAX_BEAMS} the extractor holds"),
        ))
    } else {
        Ok(())
    }
}

/// The `n` ranges in metres that `tokens` hold next on text line `line`, in mm. `bad` names
/// what is wrong with a reading that is an error (`None`: it is fine); a reading that `valid`
/// rejects has no return (NaN). `record` names the line's kind for a line with fewer ranges.
pub(crate) fn ranges_mm<'a>(
    line: u64,
    (record, n): (&str, usize),
    tokens: &mut impl Iterator<Item = &'a str>,
    bad: impl Fn(f32) -> Option<&'static str>,
    valid: impl Fn(f32) -> bool,
) -> Result<Vec<f32>, InputError> {
    let mut ranges = Vec::with_capacity(n);
    for k in 0..n {
        let token = tokens.next().ok_or_else(|| {
            InputError::line(line, format!("{record} declares {n} ranges but has {k}"))
        })?;
        let r: f32 = number(line, &format!("range {k}"), Some(token))?;
        if let Some(what) = bad(r) {
            return Err(InputError::line(
                line,
                format!("range {k} is {what}: {}", quote(token)),
            ));
        }
        let mm = r * 1000.0;
        ranges.push(if valid(mm) { mm } else { f32::NAN });
    }
    Ok(ranges)
}

/// The record read from `line`, once its geometry is usable.
pub(crate) fn checked_record(
    line: u64,
    id: u64,
    geometry: ScanGeometry,
    ranges_mm: Vec<f32>,
) -> Result<Record, InputError> {
    check_geometry(line, &geometry)?;
    Ok(Record {
        id,
        geometry,
        ranges_mm,
        time: None,
        pose: None,
        sweeps: None,
    })
}

/// Checks a geometry built from a line.
fn check_geometry(line: u64, g: &ScanGeometry) -> Result<(), InputError> {
    if g.is_valid() {
        Ok(())
    } else {
        Err(InputError::line(
            line,
            format!(
                "unusable geometry (start {} rad, step {} rad, max range {} mm)",
                g.start_angle, g.angle_step, g.r_max
            ),
        ))
    }
}

/// The interleaved sweeps of a scan of `geometry` read as `format`: a SICK LMS2xx's (LMS200
/// telegrams and CARMEN logs) at 0.5° are 2, at 0.25° 4 ([`pfe_core::BeamTiming::lms2xx`]);
/// 1 otherwise (1° or a step no LMS2xx has), and for every other format (no interleaving
/// known). A record's own [`Record::sweeps`] comes first. `--sweeps auto` detects them from the
/// scan where the format cannot say ([`AutoSweeps`]).
///
/// ```
/// use pfe_formats::{sweeps_of, Format};
/// use pfe_core::ScanGeometry;
/// assert_eq!(sweeps_of(Format::Carmen, &ScanGeometry::lms200(180.0, 0.5)), 2);
/// assert_eq!(sweeps_of(Format::Lms200, &ScanGeometry::lms200(100.0, 0.25)), 4);
/// assert_eq!(sweeps_of(Format::Carmen, &ScanGeometry::lms200(180.0, 1.0)), 1);
/// // Not an LMS2xx's step (a Hokuyo URG's 360° / 1024).
/// assert_eq!(sweeps_of(Format::Carmen, &ScanGeometry::lms200(240.0, 0.3515625)), 1);
/// assert_eq!(sweeps_of(Format::Csv, &ScanGeometry::lms200(180.0, 0.5)), 1);
/// ```
pub fn sweeps_of(format: Format, geometry: &pfe_core::ScanGeometry) -> u8 {
    sweeps_told(format, geometry).unwrap_or(1)
}

/// The interleaved sweeps `format` says a scan of `geometry` is made of: a SICK LMS2xx's at
/// one of its steps (0.25°, 0.5°, 1°) for LMS200 telegrams and CARMEN logs; `None` where the
/// format cannot say (CSV, Hokuyo, ROS 2 bags, another step).
pub fn sweeps_told(format: Format, geometry: &pfe_core::ScanGeometry) -> Option<u8> {
    match format {
        Format::Lms200 | Format::Carmen => {
            let deg = geometry.angle_step.abs().to_degrees();
            // Only an LMS2xx's own steps: another scanner's (a Hokuyo URG's 0.352°) is not.
            let lms = [0.25f32, 0.5, 1.0]
                .iter()
                .any(|r| (deg / r - 1.0).abs() < 0.01);
            lms.then(|| geometry.lms2xx_sweeps())
        }
        _ => None,
    }
}

/// `--sweeps auto` over the scans of one input: a record's own [`Record::sweeps`], else what
/// its format says ([`sweeps_told`]), else the sweeps detected from the scan itself
/// ([`pfe_core::interleave::detect`]), held: once a scan of an input shows 2 (4) sweeps, the
/// later scans of the same geometry are taken as at least as many (a robot that stops shows no
/// offset between its sweeps; aligning them then changes nothing, and one false detection
/// costs little: a scan declared 2 sweeps whose offset is not significant is extracted as one).
///
/// ```
/// use pfe_formats::{AutoSweeps, Format, Record};
/// use pfe_core::ScanGeometry;
/// let g = ScanGeometry::lms200(180.0, 0.5);
/// // A wall 2 m ahead; the odd beams 8 mm further (a scanner moving back between sweeps).
/// let ranges: Vec<f32> = (0..361)
///     .map(|i| {
///         let c = g.bearing(i).cos();
///         (if c > 0.3 { 2000.0 / c } else { f32::NAN }) + (i % 2) as f32 * 8.0
///     })
///     .collect();
/// let still: Vec<f32> = ranges.iter().enumerate().map(|(i, r)| r - (i % 2) as f32 * 8.0).collect();
/// let record = |ranges: &[f32]| Record {
///     id: 0, geometry: g, ranges_mm: ranges.to_vec(), time: None, pose: None, sweeps: None,
/// };
/// let mut auto = AutoSweeps::new(Format::Csv);
/// assert_eq!(auto.sweeps(&record(&still)), 1);
/// assert_eq!(auto.sweeps(&record(&ranges)), 2);
/// assert_eq!(auto.sweeps(&record(&still)), 2, "held");
/// // The format says: no detection.
/// assert_eq!(AutoSweeps::new(Format::Carmen).sweeps(&record(&still)), 2);
/// ```
#[derive(Clone, Debug)]
pub struct AutoSweeps {
    format: Format,
    /// The geometry (start, step, beams) and the most sweeps detected on it so far.
    held: Option<((u32, u32, usize), u8)>,
}

impl AutoSweeps {
    /// No scan seen yet, of `format`.
    pub fn new(format: Format) -> Self {
        Self { format, held: None }
    }

    /// The sweeps `record` (the input's next scan) is taken as.
    pub fn sweeps(&mut self, record: &Record) -> u8 {
        if let Some(s) = record.sweeps {
            return s;
        }
        if let Some(s) = sweeps_told(self.format, &record.geometry) {
            return s;
        }
        let g = &record.geometry;
        let key = (
            g.start_angle.to_bits(),
            g.angle_step.to_bits(),
            record.ranges_mm.len(),
        );
        let quantum = range_quantum(&record.ranges_mm, g.r_max);
        let scan = pfe_core::Scan::from_mm(*g, &record.ranges_mm).with_quantum(quantum);
        let found = pfe_core::interleave::detect(&scan).sweeps;
        let held = match self.held {
            Some((k, s)) if k == key => s.max(found),
            _ => found,
        };
        self.held = Some((key, held));
        held
    }
}
