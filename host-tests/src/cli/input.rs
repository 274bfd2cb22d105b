//! What `extract`, `decode` and `plot` share: the configuration names, the input with its
//! progress bar, and JSON-lines output.

use std::io::{self, IsTerminal, Read, Write};
use std::path::Path;

use clap::ValueEnum;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use pfe_core::Config;
use serde::Serialize;

use super::Failure;
use crate::formats::{self, Format};
use crate::methods::Pfe;

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
    pub fn method(self, sigma_r: Option<f32>, format: Format) -> Pfe {
        let sigma_r = sigma_r.unwrap_or(format.sigma_r());
        match self {
            ConfigName::Paper => Pfe::new("pfe-paper", Config::paper().with_sigma_r(sigma_r)),
            ConfigName::Default => Pfe::new("pfe-default", Config::default().with_sigma_r(sigma_r)),
        }
    }
}

/// The input format and the extractor to run on it (`extract`, `plot`).
#[derive(clap::Args, Debug)]
pub struct MethodArgs {
    /// Input format.
    #[arg(long, short)]
    pub format: Format,
    /// Extractor configuration.
    #[arg(long, short, default_value = "default")]
    pub config: ConfigName,
    /// Range noise of the scanner, mm, finite and > 0 (default: 5 for csv/lms200, 10 for
    /// carmen/hokuyo).
    #[arg(long, value_parser = sigma_mm)]
    pub sigma_r: Option<f32>,
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

impl MethodArgs {
    /// The extractor these arguments name.
    pub fn method(&self) -> Pfe {
        self.config.method(self.sigma_r, self.format)
    }
}

/// Opens `file` with a byte-counting progress bar on stderr (hidden when stderr is not a
/// terminal).
pub fn open(file: &Path, format: Format) -> Result<(Box<dyn io::BufRead>, ProgressBar), Failure> {
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
