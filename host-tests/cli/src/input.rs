//! What `extract`, `decode` and `plot` share: the configuration names, the input with its
//! progress bar, and JSON-lines output.

use std::io::{self, IsTerminal, Read, Write};
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use clap::ValueEnum;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use pfe_core::Config;
use serde::Serialize;

use super::Failure;
use pfe_eval::methods::Pfe;
use pfe_formats::ros2::{self, Ros2Scan, TopicError};
use pfe_formats::{self as formats, Format, InputError, Record};

/// Named extractor configurations.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ConfigName {
    /// The paper's method, faithfully (d_0 = 50 mm, λ = 2, d_f = 20 mm, Kåsa circle fit).
    Paper,
    /// The best measured configuration (noise threshold, fit comparison, Hyper + refinement).
    Default,
}

impl ConfigName {
    /// The extractor for a scanner with range noise `sigma_r` mm, or the format's default
    /// noise (the paper's thresholds do not depend on it; its covariances do).
    pub fn method(self, sigma_r: Option<f32>, sigma_sys: Option<f32>, format: Format) -> Pfe {
        let sigma_r = sigma_r.unwrap_or(format.sigma_r());
        let sigma_sys = sigma_sys.unwrap_or(format.sigma_sys());
        match self {
            ConfigName::Paper => Pfe::new(
                "pfe-paper",
                Config::paper()
                    .with_sigma_r(sigma_r)
                    .with_sigma_sys(sigma_sys),
            ),
            ConfigName::Default => Pfe::new(
                "pfe-default",
                Config::default()
                    .with_sigma_r(sigma_r)
                    .with_sigma_sys(sigma_sys),
            ),
        }
    }
}

/// [`Format`] on the command line (the names and help of `--format`; pfe-formats has no clap).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum FormatArg {
    /// `ID,START_DEG,STEP_DEG,R_0,...,R_{N-1}`, ranges in mm (0 or ≥ 8183 = no return).
    Csv,
    /// CARMEN log: `FLASER` (180° field), `ROBOTLASER1` or `RAWLASER1` lines (metres, gzip
    /// allowed).
    Carmen,
    /// Raw byte capture of an LMS200 serial line (0xB0 telegrams, damage skipped).
    Lms200,
    /// `topic stamp angle_min angle_increment range_min range_max n r_0 ... r_{n-1}`.
    Hokuyo,
    /// ROS 2 bag (MCAP) with `sensor_msgs/msg/LaserScan` messages (--topic names the topic).
    Mcap,
}

/// The parser of a `--format` argument.
pub(crate) fn format_parser() -> impl clap::builder::TypedValueParser<Value = Format> {
    use clap::builder::TypedValueParser as _;
    clap::builder::EnumValueParser::<FormatArg>::new().map(|f| match f {
        FormatArg::Csv => Format::Csv,
        FormatArg::Carmen => Format::Carmen,
        FormatArg::Lms200 => Format::Lms200,
        FormatArg::Hokuyo => Format::Hokuyo,
        FormatArg::Mcap => Format::Mcap,
    })
}

/// The input format and the extractor to run on it (`extract`, `plot`).
#[derive(clap::Args, Debug)]
pub struct MethodArgs {
    /// Input format.
    #[arg(long, short, value_parser = format_parser())]
    pub format: Format,
    /// Extractor configuration.
    #[arg(long, short, default_value = "default")]
    pub config: ConfigName,
    /// Range noise of the scanner, mm, finite and > 0 (default: 5 for csv/lms200; 10 for
    /// carmen/hokuyo, and for mcap: ROS 2 bags mostly hold Hokuyo URG or SICK LMS/TiM scans,
    /// whose range noise is of that order).
    #[arg(long, value_parser = sigma_mm)]
    pub sigma_r: Option<f32>,
    /// Beam-to-beam systematic range error, mm, finite and ≥ 0, added to the default
    /// configuration's covariances (default: 5 for real scanners' formats, from the LMS200
    /// data sheet's ±15 mm; 0 for csv, the simulator's).
    #[arg(long, value_parser = sigma_sys_mm)]
    pub sigma_sys: Option<f32>,
    /// LaserScan topic of a ROS 2 bag (--format mcap); default: the bag's only LaserScan topic.
    #[arg(long)]
    pub topic: Option<String>,
    /// Interleaved sweeps a scan is made of (1, 2 or 4: beam i in sweep i mod N), whose
    /// offset (a moving robot's) is then estimated from the scan and removed where it shows;
    /// `auto`: what a CARMEN ROBOTLASER1/RAWLASER1 line's laser type says (1 for a scanner
    /// that is not a SICK LMS), else a SICK LMS2xx's for --format lms200 or carmen at its steps
    /// (2 at 0.5°, 4 at 0.25°, 1 at 1°), else (csv, hokuyo, mcap, other steps) detected from
    /// each scan: 2 or 4 where the offset of even and odd beams (or of the 4 phases) against
    /// the surface shows beyond the noise, held for the file's later scans, else 1.
    #[arg(long, default_value = "auto", value_parser = sweeps_parser())]
    pub sweeps: Sweeps,
}

/// `--sweeps`: a number of sweeps, or `None` for `auto`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sweeps(pub Option<u8>);

/// `--sweeps 1|2|4|auto`: the sweeps an LMS2xx interleaves, or `auto`; anything else is
/// refused by clap with the allowed values.
pub fn sweeps_parser() -> impl clap::builder::TypedValueParser<Value = Sweeps> {
    use clap::builder::TypedValueParser as _;
    clap::builder::PossibleValuesParser::new(["auto", "1", "2", "4"])
        .map(|s| Sweeps(s.parse::<u8>().ok()))
}

/// `--sigma-r MM`: a finite range noise above zero (the covariances divide by it).
pub fn sigma_mm(s: &str) -> Result<f32, String> {
    let v: f32 = s
        .trim()
        .parse()
        .map_err(|_| format!("not a number of mm: {s:?}"))?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("must be a finite range noise > 0 mm, got {s}"))
    }
}

/// `--sigma-sys MM`: a finite systematic range error of at least zero.
pub fn sigma_sys_mm(s: &str) -> Result<f32, String> {
    let v: f32 = s
        .trim()
        .parse()
        .map_err(|_| format!("not a number of mm: {s:?}"))?;
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(format!("must be a finite systematic error ≥ 0 mm, got {s}"))
    }
}

impl MethodArgs {
    /// The extractor these arguments name.
    pub fn method(&self) -> Pfe {
        self.config
            .method(self.sigma_r, self.sigma_sys, self.format)
    }

    /// What the extractor is told besides the ranges of `record`: its sweeps (`--sweeps`, or
    /// `auto` through `auto`, which holds what the input's earlier scans showed) and the grid
    /// its ranges lie on.
    pub fn context(
        &self,
        record: &pfe_formats::Record,
        auto: &mut pfe_formats::AutoSweeps,
    ) -> pfe_eval::methods::ScanContext {
        let geometry = &record.geometry;
        pfe_eval::methods::ScanContext {
            odometry: None,
            sweeps: usize::from(self.sweeps.0.unwrap_or_else(|| auto.sweeps(record))),
            quantum: pfe_formats::range_quantum(&record.ranges_mm, geometry.r_max),
        }
    }

    /// `--sweeps auto`'s state over one input of this format.
    pub fn auto_sweeps(&self) -> pfe_formats::AutoSweeps {
        pfe_formats::AutoSweeps::new(self.format)
    }
}

/// An opened input: the reader, its progress bar and the bytes read so far.
pub struct Input {
    /// The (decompressed) input.
    pub reader: Box<dyn io::BufRead>,
    /// Progress on stderr (hidden when stderr is not a terminal).
    pub bar: ProgressBar,
    /// Raw bytes read from the file so far.
    pub bytes: Arc<AtomicU64>,
}

/// Counts the bytes read through it.
struct Counting<R> {
    inner: R,
    bytes: Arc<AtomicU64>,
}

impl<R: Read> Read for Counting<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.bytes.fetch_add(n as u64, Ordering::Relaxed);
        Ok(n)
    }
}

/// Opens `file` with a byte-counting progress bar on stderr (hidden when stderr is not a
/// terminal).
pub fn open(file: &Path, format: Format) -> Result<Input, Failure> {
    let len = std::fs::metadata(file).map(|m| m.len()).unwrap_or(0);
    let bar = if io::stderr().is_terminal() && len > 0 {
        let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
        if let Ok(style) = ProgressStyle::with_template(
            "{spinner} {bytes}/{total_bytes} {wide_bar} {elapsed_precise} ETA {eta} {msg}",
        ) {
            bar.set_style(style);
        }
        bar
    } else {
        ProgressBar::hidden()
    };
    let b = bar.clone();
    let bytes = Arc::new(AtomicU64::new(0));
    let counter = bytes.clone();
    let reader = formats::open_for(file, format, move |r| {
        Box::new(b.wrap_read(Counting {
            inner: r,
            bytes: counter,
        })) as Box<dyn Read>
    })
    .map_err(|e| Failure::input(format!("{}: cannot open: {e}", file.display())))?;
    Ok(Input { reader, bar, bytes })
}

/// Another format in which `file` starts with a good scan (`None` for stdin); `mcap` when it
/// starts with the MCAP magic bytes.
pub fn guess(file: &Path, format: Format) -> Option<Format> {
    if file.as_os_str() == "-" {
        return None;
    }
    if format != Format::Mcap && starts_as_mcap(file) {
        return Some(Format::Mcap);
    }
    Format::ALL
        .iter()
        .copied()
        .filter(|&f| f != format)
        .find(|&f| {
            formats::open_for(file, f, |r| r)
                .ok()
                .and_then(|input| formats::scans(f, input).next())
                .is_some_and(|r| r.is_ok())
        })
}

/// The name of `file` in messages: `stdin` for `-`.
pub fn shown(file: &Path) -> String {
    if file.as_os_str() == "-" {
        "stdin".to_string()
    } else {
        file.display().to_string()
    }
}

/// Bad input for input in which `format` found nothing (`what`: "scan", "telegram"): empty
/// input says so; otherwise the message suggests another format that reads a scan from it.
pub fn nothing_found(file: &Path, format: Format, what: &str, bytes: u64) -> Failure {
    if bytes == 0 {
        return Failure::input(format!("no {what} found in {}: it is empty", shown(file)));
    }
    let hint = match guess(file, format) {
        Some(g) => format!("is it {g}? try --format {g}"),
        None => "is --format right? (csv, carmen, hokuyo, lms200, mcap)".to_string(),
    };
    Failure::input(format!(
        "no {what} found in {} as {format}; {hint}",
        shown(file)
    ))
}

/// Bad input for an error `e` in `file`; when no scan was read before it (`scans`) and
/// another format reads one, the message suggests that format.
pub fn bad_input(file: &Path, format: Format, scans: u64, e: &dyn std::fmt::Display) -> Failure {
    let hint = match (scans == 0).then(|| guess(file, format)).flatten() {
        Some(g) => format!(" (as {format}; is it {g}? try --format {g})"),
        None => String::new(),
    };
    Failure::input(format!("{}: {e}{hint}", file.display()))
}

/// Buffered stdout for JSON lines.
pub fn stdout() -> io::BufWriter<io::StdoutLock<'static>> {
    io::BufWriter::with_capacity(1 << 16, io::stdout().lock())
}

/// Writes one JSON line; a closed pipe ends the run quietly.
pub fn write_json<W: Write, T: Serialize>(out: &mut W, value: &T) -> Result<bool, Failure> {
    let r = serde_json::to_writer(&mut *out, value)
        .map_err(io::Error::from)
        .and_then(|()| out.write_all(b"\n"));
    match r {
        Ok(()) => Ok(true),
        Err(e) if e.kind() == io::ErrorKind::BrokenPipe => Ok(false),
        Err(e) => Err(Failure::other(format!("cannot write output: {e}"))),
    }
}

/// Flushes the output; a closed pipe is not an error.
pub fn flush<W: Write>(out: &mut W) -> Result<(), Failure> {
    match out.flush() {
        Err(e) if e.kind() != io::ErrorKind::BrokenPipe => {
            Err(Failure::other(format!("cannot write output: {e}")))
        }
        _ => Ok(()),
    }
}

/// True when `file` starts with the MCAP magic bytes.
fn starts_as_mcap(file: &Path) -> bool {
    let mut head = [0u8; 8];
    std::fs::File::open(file)
        .and_then(|mut f| f.read_exact(&mut head))
        .is_ok_and(|()| formats::ros2_stream::is_mcap(&head))
}

/// One scan of any input, with the stamp and frame a ROS 2 bag gives it.
pub struct Scan {
    /// The scan.
    pub record: Record,
    /// `header.stamp` of a bag's scan, ns since the epoch.
    pub stamp_ns: Option<u64>,
    /// `header.frame_id` of a bag's scan.
    pub frame_id: Option<String>,
}

/// The scans of an opened input, its progress bar and the bytes read so far.
pub struct Source {
    /// Scans, stopping after the first error.
    pub scans: Box<dyn Iterator<Item = Result<Scan, InputError>>>,
    /// Progress on stderr (hidden when stderr is not a terminal).
    pub bar: ProgressBar,
    /// Raw bytes read so far (for a bag: its size once opened).
    pub bytes: Arc<AtomicU64>,
}

/// Opens `file` as `format`; a ROS 2 bag (`mcap`) is read by path from `topic` (or its only
/// LaserScan topic), stdin is buffered in memory first. `--topic` with another format is bad
/// input.
pub fn open_scans(file: &Path, format: Format, topic: Option<&str>) -> Result<Source, Failure> {
    if format != Format::Mcap {
        if topic.is_some() {
            return Err(Failure::input(format!(
                "--topic is for ROS 2 bags (--format mcap), not {format}"
            )));
        }
        let input = open(file, format)?;
        return Ok(Source {
            scans: Box::new(formats::scans(format, input.reader).map(|r| {
                r.map(|record| Scan {
                    record,
                    stamp_ns: None,
                    frame_id: None,
                })
            })),
            bar: input.bar,
            bytes: input.bytes,
        });
    }
    let opened = if file.as_os_str() == "-" {
        let mut bytes = Vec::new();
        io::stdin()
            .read_to_end(&mut bytes)
            .map_err(|e| Failure::input(format!("-: cannot read: {e}")))?;
        let len = bytes.len() as u64;
        ros2::open_laser_scans(io::Cursor::new(bytes), topic).map(|s| {
            (
                Box::new(s.map(from_bag)) as Box<dyn Iterator<Item = _>>,
                len,
            )
        })
    } else {
        let len = std::fs::metadata(file).map(|m| m.len()).unwrap_or(0);
        ros2::read_laser_scans(file, topic).map(|s| {
            (
                Box::new(s.map(from_bag)) as Box<dyn Iterator<Item = _>>,
                len,
            )
        })
    };
    let (scans, len) = opened.map_err(|e| match e {
        TopicError::Input(e) => bad_input(file, format, 0, &e),
        e => Failure::input(format!("{}: {e}", file.display())),
    })?;
    let bar = if io::stderr().is_terminal() {
        ProgressBar::new_spinner()
    } else {
        ProgressBar::hidden()
    };
    Ok(Source {
        scans,
        bar,
        bytes: Arc::new(AtomicU64::new(len)),
    })
}

fn from_bag(s: Result<Ros2Scan, InputError>) -> Result<Scan, InputError> {
    s.map(|s| Scan {
        record: s.record,
        stamp_ns: Some(s.stamp_ns),
        frame_id: Some(s.frame_id),
    })
}
