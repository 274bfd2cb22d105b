//! The `pfe` command line: one clap tree, one file per subcommand.
//!
//! ```text
//! pfe extract --format csv|carmen|lms200|hokuyo [--config paper|default] FILE   # JSON lines
//! pfe decode  FILE                                                              # raw LMS200 telegrams
//! pfe plot FILE --format F [--config C] --scan K -o out.svg                     # Fig. 7-style SVG
//! pfe plot FILE --format F --scans A..B --html page.html|--sheet grid.svg       # several scans, one scale
//! pfe plot LOG --format carmen --world world.svg [--odometry [--points]]        # the log in the world frame
//! pfe odometry --format F FILE [--mcap run.mcap]                                # poses (JSON), Foxglove
//! pfe eval|bench|emulate|record ...                                             # see their --help
//! pfe completions bash|zsh|fish|elvish|powershell                               # shell completions
//! pfe man [COMMAND]                                                             # man page (roff)
//! ```
//!
//! FILE may be gzipped (detected from its content) or `-` for stdin. Every subcommand exits
//! with the codes of [`EXIT_CODES`]: 2 for bad input (a bad argument, a malformed line, an
//! unknown format, an unreadable file, input with no scan, an output directory that does not
//! exist), with a one-line error on stderr
//! (the scans before it are still written); 1 for any other failure; 130 when interrupted.
//!
//! Besides the subcommands: [`figure`] (one scan as SVG), [`foxglove`] (Foxglove MCAP file and
//! WebSocket), [`link`] (the firmware's frames in, JSON lines out), [`device`] (recording a real
//! LMS200 over a tty).

#![forbid(unsafe_code)]

pub mod bench;
pub mod decode;
pub mod device;
pub mod emulate;
pub mod eval;
pub mod extract;
pub mod figure;
pub mod foxglove;
mod input;
pub mod interrupt;
pub mod link;
pub mod listen;
mod lms_args;
pub mod odometry;
pub mod plot;
pub mod posebench;
pub mod realdata;
pub mod record;

use std::ffi::OsString;
use std::process::ExitCode;

use clap::{CommandFactory, Parser, Subcommand};

/// Prediction-based feature extraction (Zhao & Chen 2011) on recorded 2D laser scans.
#[derive(Parser, Debug)]
#[command(
    name = "pfe",
    version,
    about = "Prediction-based feature extraction (Zhao & Chen 2011) on recorded 2D laser scans",
    after_help = EXIT_CODES
)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Extract features: one JSON object per scan on stdout, one line each.
    Extract(extract::Args),
    /// Decode a raw LMS200 capture: one JSON object per good 0xB0 telegram, summary on stderr.
    Decode(decode::Args),
    /// Plot one scan with its mark points and features as SVG (like Fig. 7 of the paper), a
    /// range of scans as an HTML page or a sheet, or a log in the world frame.
    Plot(plot::Args),
    /// Evaluate PFE, split-and-merge and ACF against ground truth on simulated scans.
    Eval(eval::Args),
    /// Speed of pfe-paper, pfe-default, split-merge and acf on the same scans.
    Bench(bench::Args),
    /// Emulate a SICK LMS200 on a pseudo-terminal or a TCP socket.
    Emulate(emulate::Args),
    /// Record a SICK LMS200's raw bytes through the firmware driver.
    Record(record::Args),
    /// Real-data benchmark without ground truth: features re-found in the next scan via the poses.
    Realdata(realdata::Args),
    /// Read the firmware's feature frames: one JSON object per scan on stdout.
    Listen(listen::Args),
    /// The pose of every scan from its features (pfe-pose): one JSON object per scan.
    Odometry(odometry::Args),
    /// Pose benchmark on CARMEN logs against their poses: a Markdown table.
    Posebench(posebench::Args),
    /// Print a shell completion script on stdout (e.g. for bash: pfe completions bash >
    /// ~/.local/share/bash-completion/completions/pfe).
    Completions {
        /// The shell.
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
    /// Print the man page (roff) on stdout: pfe(1), or pfe-COMMAND(1) of one subcommand
    /// (e.g. pfe man > pfe.1; man ./pfe.1).
    Man {
        /// The subcommand whose page to print (default: pfe's own, which lists them all).
        command: Option<String>,
    },
}

/// The exit codes of every subcommand, as `pfe --help` prints them.
pub const EXIT_CODES: &str = "FILE may be gzipped (detected from its content) or - for stdin.

Exit codes (every subcommand): 0 success; 2 bad input: a bad argument, an unreadable or \
malformed file (one-line error with the line number; the scans before it are still written), \
input with no scan (empty input included), an output that would overwrite a file or go into a \
directory that does not exist (pfe creates none); 1 any other failure (device, I/O, \
a broken budget); 130 interrupted by Ctrl-C (what was recorded is kept), except `pfe listen`, \
whose normal stop is Ctrl-C (exit 0 after its summary).";

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

    /// A subcommand's error, named after it: the code of an [`Exit`], 2 for an existing
    /// output file or a bad argument, 1 otherwise.
    fn of(name: &str, e: &anyhow::Error) -> Self {
        let text = format!("{e:#}");
        let text = text.strip_prefix("error: ").unwrap_or(&text);
        let code = if let Some(exit) = e.downcast_ref::<Exit>() {
            exit.code
        } else if e.is::<crate::device::record::OutputExists>()
            || e.is::<clap::Error>()
            || e.downcast_ref::<pfe_formats::outfile::OutError>()
                .is_some_and(pfe_formats::outfile::OutError::is_refusal)
        {
            2
        } else {
            1
        };
        Failure {
            code,
            message: format!("{name}: {text}"),
        }
    }
}

/// An error from a subcommand returning `anyhow` that sets `pfe`'s exit code.
#[derive(Debug)]
pub struct Exit {
    /// The exit code.
    pub code: u8,
    /// What to print.
    pub message: String,
}

impl Exit {
    /// Bad input (exit code 2).
    pub fn bad_input(message: impl Into<String>) -> Self {
        Exit {
            code: 2,
            message: message.into(),
        }
    }

    /// A run stopped by Ctrl-C or SIGTERM after keeping what it had (exit code 130).
    pub fn interrupted(message: impl Into<String>) -> Self {
        Exit {
            code: 130,
            message: message.into(),
        }
    }
}

impl std::fmt::Display for Exit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for Exit {}

/// Runs `pfe` with the process's arguments.
pub fn main() -> ExitCode {
    run(std::env::args_os())
}

/// Runs `pfe` with `args` (the first one is the program name).
pub fn run(args: impl IntoIterator<Item = OsString>) -> ExitCode {
    let args: Vec<OsString> = args.into_iter().collect();
    interrupt::install();
    let cli = match Cli::try_parse_from(&args) {
        Ok(cli) => cli,
        // Clap prints the error and exits 2 (0 for --help and --version).
        Err(e) => e.exit(),
    };
    let result = match cli.command {
        Command::Extract(a) => extract::run(a),
        Command::Decode(a) => decode::run(a),
        Command::Plot(a) => plot::run(a),
        Command::Eval(a) => eval::run(a).map_err(|e| Failure::of("eval", &e)),
        Command::Bench(a) => bench::run(a).map_err(|e| Failure::of("bench", &e)),
        Command::Emulate(a) => emulate::run(a).map_err(|e| Failure::of("emulate", &e)),
        Command::Record(a) => record::run(a).map_err(|e| Failure::of("record", &e)),
        Command::Realdata(a) => realdata::run(a).map_err(|e| Failure::of("realdata", &e)),
        Command::Listen(a) => listen::run(a),
        Command::Odometry(a) => odometry::run(a),
        Command::Posebench(a) => posebench::run(a).map_err(|e| Failure::of("posebench", &e)),
        Command::Completions { shell } => completions(shell),
        Command::Man { command } => man(command.as_deref()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            eprintln!("pfe: error: {}", f.message);
            ExitCode::from(f.code)
        }
    }
}

/// The clap tree of `pfe`, built (subcommands know their full names, e.g. `pfe extract`).
fn command_tree() -> clap::Command {
    let mut cmd = Cli::command();
    cmd.build();
    cmd
}

/// Writes `bytes` to stdout; a closed pipe is not an error.
fn print_bytes(bytes: &[u8]) -> Result<(), Failure> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match out.write_all(bytes).and_then(|()| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(Failure::other(format!("cannot write output: {e}")))
        }
        _ => Ok(()),
    }
}

/// `pfe completions SHELL`: the completion script of the clap tree.
fn completions(shell: clap_complete::Shell) -> Result<(), Failure> {
    let mut cmd = Cli::command();
    let mut script = Vec::new();
    clap_complete::generate(shell, &mut cmd, "pfe", &mut script);
    print_bytes(&script)
}

/// `pfe man [COMMAND]`: the man page of `pfe` (listing its subcommands) or of one subcommand.
fn man(command: Option<&str>) -> Result<(), Failure> {
    let tree = command_tree();
    let man = match command {
        None => clap_mangen::Man::new(tree),
        Some(name) => {
            let sub = tree.find_subcommand(name).cloned().ok_or_else(|| {
                let names: Vec<&str> = tree.get_subcommands().map(|s| s.get_name()).collect();
                Failure::input(format!(
                    "man: no subcommand {name:?} (one of {})",
                    names.join(", ")
                ))
            })?;
            // pfe-extract(1) and so on, as git and cargo name their subcommands' pages.
            let title = format!("pfe-{}", sub.get_name());
            clap_mangen::Man::new(sub).title(title)
        }
    };
    let mut roff = Vec::new();
    man.source(format!("pfe {}", env!("CARGO_PKG_VERSION")))
        .render(&mut roff)
        .map_err(|e| Failure::other(format!("man: {e}")))?;
    print_bytes(&roff)
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
