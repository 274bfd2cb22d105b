//! The `pfe` command line: one clap tree, one file per subcommand.
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
//! line number and exit code 2; the scans before it are still written. `eval`, `bench`,
//! `emulate` and `record` fail with exit code 1, bad arguments included.

pub mod bench;
pub mod decode;
pub mod emulate;
pub mod eval;
pub mod extract;
mod input;
pub mod listen;
mod lms_args;
pub mod plot;
pub mod record;

use std::ffi::OsString;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

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
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Extract features: one JSON object per scan on stdout, one line each.
    Extract(extract::Args),
    /// Decode an LMS200 capture: one JSON object per good 0xB0 telegram, summary on stderr.
    Decode(decode::Args),
    /// Plot one scan with its mark points and features as SVG (like Fig. 7 of the paper).
    Plot(plot::Args),
    /// Evaluate methods against ground truth (see `pfe eval --help`).
    Eval(eval::Args),
    /// Speed of pfe-paper, pfe-default, split-merge and acf on the same scans.
    Bench(bench::Args),
    /// LMS200 device emulator.
    Emulate(emulate::Args),
    /// Record from a scanner.
    Record(record::Args),
    /// Read the firmware's feature frames: one JSON object per scan on stdout.
    Listen(listen::Args),
}

/// A failure and its exit code.
pub struct Failure {
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

    /// A subcommand's error, named after it: exit code 1.
    fn of(name: &str, e: &anyhow::Error) -> Self {
        let text = format!("{e:#}");
        let text = text.strip_prefix("error: ").unwrap_or(&text);
        Failure::other(format!("{name}: {text}"))
    }
}

/// The subcommands whose argument errors exit with code 1 (not clap's 2).
const EXIT_1_ON_BAD_ARGUMENTS: [&str; 4] = ["eval", "bench", "emulate", "record"];

/// Runs `pfe` with the process's arguments.
pub fn main() -> ExitCode {
    run(std::env::args_os())
}

/// Runs `pfe` with `args` (the first one is the program name).
pub fn run(args: impl IntoIterator<Item = OsString>) -> ExitCode {
    let args: Vec<OsString> = args.into_iter().collect();
    let cli = match Cli::try_parse_from(&args) {
        Ok(cli) => cli,
        Err(e) => {
            let sub = args.get(1).and_then(|a| a.to_str()).unwrap_or("");
            if e.use_stderr() && EXIT_1_ON_BAD_ARGUMENTS.contains(&sub) {
                let text = e.to_string();
                let text = text.strip_prefix("error: ").unwrap_or(&text);
                eprintln!("pfe: error: {sub}: {}", text.trim_end());
                return ExitCode::from(1);
            }
            e.exit()
        }
    };
    let result = match cli.command {
        Command::Extract(a) => extract::run(a),
        Command::Decode(a) => decode::run(a),
        Command::Plot(a) => plot::run(a),
        Command::Eval(a) => eval::run(a).map_err(|e| Failure::of("eval", &e)),
        Command::Bench(a) => bench::run(a).map_err(|e| Failure::of("bench", &e)),
        Command::Emulate(a) => emulate::run(a).map_err(|e| Failure::of("emulate", &e)),
        Command::Record(a) => record::run(a).map_err(|e| Failure::of("record", &e)),
        Command::Listen(a) => listen::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            eprintln!("pfe: error: {}", f.message);
            ExitCode::from(f.code)
        }
    }
}

/// Parses one subcommand's arguments (`args` without the program or subcommand name) for the
/// in-process entry points (`cli`): `Ok(None)` after printing `--help`.
fn parse_sub<T: clap::Args>(name: &'static str, args: &[String]) -> anyhow::Result<Option<T>> {
    let cmd = T::augment_args(clap::Command::new(name));
    let parsed =
        cmd.try_get_matches_from(std::iter::once(name.to_string()).chain(args.iter().cloned()));
    match parsed.and_then(|mut m| T::from_arg_matches_mut(&mut m)) {
        Ok(a) => Ok(Some(a)),
        Err(e)
            if matches!(
                e.kind(),
                clap::error::ErrorKind::DisplayHelp | clap::error::ErrorKind::DisplayVersion
            ) =>
        {
            print!("{e}");
            Ok(None)
        }
        Err(e) => Err(e.into()),
    }
}
