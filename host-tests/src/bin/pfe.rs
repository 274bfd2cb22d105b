//! `pfe`: run the prediction-based feature extractor on recorded scans.
//!
//! ```text
//! pfe extract --format csv|carmen|lms200|hokuyo [--config paper|default] FILE   # JSON lines
//! pfe decode  --format lms200 FILE                                              # raw telegrams
//! pfe plot FILE --format F [--config C] --scan K -o out.svg                     # Fig. 7-style SVG
//! pfe eval|bench|emulate|record ...                                             # see their --help
//! ```
//!
//! FILE may be gzipped (detected from its content) or `-` for stdin. Bad input (a malformed
//! line, an unknown format, an unreadable file) gives a one-line error on stderr with the
//! line number and exit code 2; the scans before it are still written.
#![forbid(unsafe_code)]

use std::io::{self, IsTerminal, Read, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use clap::{Parser, Subcommand, ValueEnum};
use host_tests::formats::{self, lms200, Format, Record, ScanJson};
use host_tests::methods::{Method, Pfe};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use pfe_core::Config;
use serde::Serialize;

/// Prediction-based feature extraction (Zhao & Chen 2011) on recorded 2D laser scans.
#[derive(Parser, Debug)]
#[command(
    name = "pfe",
    version,
    about = "Prediction-based feature extraction (Zhao & Chen 2011) on recorded 2D laser scans",
    after_help = "FILE may be gzipped (detected from its content) or - for stdin. Bad input gives a \
                  one-line error with the line number and exit code 2; the scans before it are \
                  still written."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// Named extractor configurations.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum ConfigName {
    /// The paper's method, faithfully (d_0 = 50 mm, λ = 2, d_f = 20 mm, Kåsa circle fit).
    Paper,
    /// The best measured configuration (noise threshold, fit comparison, Hyper + refinement).
    Default,
}

impl ConfigName {
    /// The extractor for a scanner with range noise `sigma_r` mm (the paper's thresholds do
    /// not depend on it; its covariances do).
    fn method(self, sigma_r: f32) -> Pfe {
        match self {
            ConfigName::Paper => Pfe::new("pfe-paper", Config::paper().with_sigma_r(sigma_r)),
            ConfigName::Default => Pfe::new("pfe-default", Config::default().with_sigma_r(sigma_r)),
        }
    }
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Extract features: one JSON object per scan on stdout, one line each.
    Extract {
        /// Input format.
        #[arg(long, short)]
        format: Format,
        /// Extractor configuration.
        #[arg(long, short, default_value = "default")]
        config: ConfigName,
        /// Range noise of the scanner, mm (default: 5 for csv/lms200, 10 for carmen/hokuyo).
        #[arg(long)]
        sigma_r: Option<f32>,
        /// Input file (gzip is read transparently; `-` = stdin).
        file: PathBuf,
    },
    /// Decode an LMS200 capture: one JSON object per good 0xB0 telegram, summary on stderr.
    Decode {
        /// Input format (only `lms200`).
        #[arg(long, short)]
        format: Format,
        /// Input file (`-` = stdin).
        file: PathBuf,
    },
    /// Plot one scan with its mark points and features as SVG (like Fig. 7 of the paper).
    Plot {
        /// Input file.
        file: PathBuf,
        /// Input format.
        #[arg(long, short)]
        format: Format,
        /// Extractor configuration.
        #[arg(long, short, default_value = "default")]
        config: ConfigName,
        /// Range noise of the scanner, mm (default: 5 for csv/lms200, 10 for carmen/hokuyo).
        #[arg(long)]
        sigma_r: Option<f32>,
        /// Scan ID to plot (the csv ID, else the 0-based ordinal).
        #[arg(long, short)]
        scan: u64,
        /// Output SVG file.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Evaluate methods against ground truth (arguments passed through; see `pfe eval --help`).
    #[command(disable_help_flag = true)]
    Eval {
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// Benchmarks (arguments passed through).
    #[command(disable_help_flag = true)]
    Bench {
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// LMS200 device emulator (arguments passed through).
    #[command(disable_help_flag = true)]
    Emulate {
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// Record from a scanner (arguments passed through).
    #[command(disable_help_flag = true)]
    Record {
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
}

/// A failure and its exit code.
struct Failure {
    code: u8,
    message: String,
}

impl Failure {
    /// Bad input: exit code 2.
    fn input(message: impl Into<String>) -> Self {
        Self {
            code: 2,
            message: message.into(),
        }
    }

    /// Anything else: exit code 1.
    fn other(message: impl Into<String>) -> Self {
        Self {
            code: 1,
            message: message.into(),
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Extract {
            format,
            config,
            sigma_r,
            file,
        } => extract(
            format,
            config.method(sigma_r.unwrap_or(format.sigma_r())),
            &file,
        ),
        Command::Decode { format, file } => decode(format, &file),
        Command::Plot {
            file,
            format,
            config,
            sigma_r,
            scan,
            output,
        } => plot(
            &file,
            format,
            config.method(sigma_r.unwrap_or(format.sigma_r())),
            scan,
            &output,
        ),
        Command::Eval { args } => delegate("eval", host_tests::eval::cli(&args)),
        Command::Bench { args } => delegate("bench", host_tests::eval::bench::cli(&args)),
        Command::Emulate { args } => delegate("emulate", host_tests::emulator::cli(&args)),
        Command::Record { args } => delegate("record", host_tests::record::cli(&args)),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            eprintln!("pfe: error: {}", f.message);
            ExitCode::from(f.code)
        }
    }
}

fn delegate(name: &str, r: anyhow::Result<()>) -> Result<(), Failure> {
    r.map_err(|e| {
        let text = format!("{e:#}");
        let text = text.strip_prefix("error: ").unwrap_or(&text);
        Failure::other(format!("{name}: {text}"))
    })
}

/// Opens `file` with a byte-counting progress bar on stderr (hidden when stderr is not a
/// terminal).
fn open(file: &Path, format: Format) -> Result<(Box<dyn io::BufRead>, ProgressBar), Failure> {
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
    let input = formats::open_for(file, format, move |r| {
        Box::new(b.wrap_read(r)) as Box<dyn Read>
    })
    .map_err(|e| Failure::input(format!("{}: cannot open: {e}", file.display())))?;
    Ok((input, bar))
}

/// Writes one JSON line; a closed pipe ends the run quietly.
fn write_json<W: Write, T: Serialize>(out: &mut W, value: &T) -> Result<bool, Failure> {
    let r = serde_json::to_writer(&mut *out, value)
        .map_err(io::Error::from)
        .and_then(|()| out.write_all(b"\n"));
    match r {
        Ok(()) => Ok(true),
        Err(e) if e.kind() == io::ErrorKind::BrokenPipe => Ok(false),
        Err(e) => Err(Failure::other(format!("cannot write output: {e}"))),
    }
}

fn flush<W: Write>(out: &mut W) -> Result<(), Failure> {
    match out.flush() {
        Err(e) if e.kind() != io::ErrorKind::BrokenPipe => {
            Err(Failure::other(format!("cannot write output: {e}")))
        }
        _ => Ok(()),
    }
}

fn extract(format: Format, mut method: Pfe, file: &Path) -> Result<(), Failure> {
    let (input, bar) = open(file, format)?;
    let stdout = io::stdout();
    let mut out = io::BufWriter::with_capacity(1 << 16, stdout.lock());
    let t0 = Instant::now();
    let (mut scans, mut features) = (0u64, 0u64);
    let mut error = None;
    for record in formats::scans(format, input) {
        let record = match record {
            Ok(r) => r,
            Err(e) => {
                error = Some(Failure::input(format!("{}: {e}", file.display())));
                break;
            }
        };
        let ex = method.extract(&record.geometry, &record.ranges_mm);
        scans += 1;
        features += ex.features.len() as u64;
        if scans % 256 == 0 {
            bar.set_message(format!("{scans} scans"));
        }
        if !write_json(&mut out, &ScanJson::new(record.id, &ex))? {
            break;
        }
    }
    flush(&mut out)?;
    bar.finish_and_clear();
    if let Some(e) = error {
        return Err(e);
    }
    let s = t0.elapsed().as_secs_f64();
    eprintln!(
        "pfe: {scans} scans, {features} features ({:.2} per scan), {:.3} s, {:.0} scans/s",
        features as f64 / scans.max(1) as f64,
        s,
        scans as f64 / s.max(1e-9)
    );
    Ok(())
}

/// One line of `pfe decode` output.
#[derive(Serialize)]
struct TelegramJson<'a> {
    scan: u64,
    unit: &'static str,
    ranges: &'a [u16],
    status: u8,
}

fn decode(format: Format, file: &Path) -> Result<(), Failure> {
    if format != Format::Lms200 {
        return Err(Failure::input(format!(
            "decode reads only --format lms200 (got {format})"
        )));
    }
    let (input, bar) = open(file, format)?;
    let stdout = io::stdout();
    let mut out = io::BufWriter::with_capacity(1 << 16, stdout.lock());
    let mut reader = lms200::Reader::new(input);
    let mut error = None;
    for t in reader.by_ref() {
        let t = match t {
            Ok(t) => t,
            Err(e) => {
                error = Some(Failure::input(format!("{}: {e}", file.display())));
                break;
            }
        };
        let j = TelegramJson {
            scan: t.ordinal,
            unit: t.unit.name(),
            ranges: &t.ranges,
            status: t.status,
        };
        if !write_json(&mut out, &j)? {
            break;
        }
    }
    flush(&mut out)?;
    bar.finish_and_clear();
    let s = reader.summary();
    eprintln!(
        "pfe: {} bytes: {} telegrams good, {} dropped for CRC, {} bytes skipped \
         ({} dropped for length, {} malformed B0, {} other telegrams)",
        s.bytes, s.good, s.crc_errors, s.skipped, s.bad_length, s.malformed, s.other_telegrams
    );
    error.map_or(Ok(()), Err)
}

fn plot(
    file: &Path,
    format: Format,
    mut method: Pfe,
    scan: u64,
    output: &Path,
) -> Result<(), Failure> {
    let (input, bar) = open(file, format)?;
    let mut found: Option<Record> = None;
    let mut count = 0u64;
    for record in formats::scans(format, input) {
        let record = record.map_err(|e| Failure::input(format!("{}: {e}", file.display())))?;
        count += 1;
        if record.id == scan {
            found = Some(record);
            break;
        }
    }
    bar.finish_and_clear();
    let record = found.ok_or_else(|| {
        Failure::input(format!(
            "{}: no scan with ID {scan} ({count} scans read)",
            file.display()
        ))
    })?;
    let ex = method.extract(&record.geometry, &record.ranges_mm);
    let name = file
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let title = format!("{name} — scan {scan} — {}", method.name());
    let svg = host_tests::plot::svg(&record, &ex, &title);
    std::fs::write(output, svg)
        .map_err(|e| Failure::other(format!("{}: cannot write: {e}", output.display())))?;
    eprintln!(
        "pfe: wrote {} ({} marks, {} features)",
        output.display(),
        ex.marks.len(),
        ex.features.len()
    );
    Ok(())
}
