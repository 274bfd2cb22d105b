//! `pfe eval` (and `cargo xtask eval` through the `eval` example): the paper's comparison on
//! simulated scenes; prints the tables and writes `OUT/EVALUATION.md` and `OUT/eval-*.svg`.

use std::path::PathBuf;

use pfe_eval::scene::SceneKind;
use pfe_eval::{default_methods, evaluate, report, svg, EvalOptions};

/// What `pfe eval --help` says after the options.
const AFTER_HELP: &str = "Runs PFE paper, PFE default, ACF and split-and-merge on simulated \
LMS200 scans with ground truth and prints the tables; with --out DIR also writes \
DIR/EVALUATION.md and DIR/eval-*.svg (DIR must exist). Build in release for times. Files in \
DIR that no pfe command wrote are not replaced (exit 2) unless --force.";

/// Arguments of `pfe eval` (defaults: those of [`EvalOptions::default`], but nothing is
/// written without `--out`).
#[derive(clap::Args, Debug)]
#[command(after_help = AFTER_HELP, args_override_self = true)]
pub struct Args {
    /// Kind of simulated scene: mixed, office, clutter, pillars, corridor or long-corridor.
    #[arg(long, default_value = "mixed")]
    kind: SceneKind,
    /// Scans per noise level, > 0.
    #[arg(long, default_value_t = EvalOptions::default().scans)]
    scans: usize,
    /// Seed of the scenes and the noise.
    #[arg(long, default_value_t = EvalOptions::default().seed)]
    seed: u64,
    /// Range noise σ_r of the main comparison, mm, ≥ 0.
    #[arg(long, default_value_t = EvalOptions::default().sigma)]
    sigma: f32,
    /// Comma-separated σ_r values of the noise sweep, mm, each ≥ 0.
    #[arg(long, value_name = "MM,MM,...", default_value = "1,2,5,10")]
    sweep: String,
    /// Timed passes over the scans (the fastest counts).
    #[arg(long, default_value_t = EvalOptions::default().passes)]
    passes: usize,
    /// Also write EVALUATION.md and the eval-*.svg plots into DIR, a directory that exists
    /// (without it: the tables only).
    #[arg(long, value_name = "DIR", overrides_with = "no_write")]
    out: Option<PathBuf>,
    /// Write no file (the default; cancels an earlier --out).
    #[arg(long, overrides_with = "out")]
    no_write: bool,
    /// The command line the report names as its source [default: cargo xtask eval].
    #[arg(long, value_name = "TEXT")]
    command: Option<String>,
    /// Replace files in --out that no pfe command wrote.
    #[arg(long)]
    force: bool,
}

impl Args {
    /// The evaluation these arguments ask for.
    pub fn options(self) -> anyhow::Result<EvalOptions> {
        let d = EvalOptions::default();
        let sweep = self
            .sweep
            .split(',')
            .map(|s| s.trim().parse::<f32>())
            .collect::<Result<_, _>>()
            .map_err(|e| super::Exit::bad_input(format!("--sweep: {e}")))?;
        let o = EvalOptions {
            kind: self.kind,
            scans: self.scans,
            seed: self.seed,
            sigma: self.sigma,
            sweep,
            passes: self.passes,
            // No default directory: without --out nothing is written.
            out: if self.no_write { None } else { self.out },
            command: self.command.unwrap_or(d.command),
            force: self.force,
        };
        let bad = |s: f32| s.is_nan() || s < 0.0;
        if o.scans == 0 || bad(o.sigma) || o.sweep.iter().any(|s| bad(*s)) {
            return Err(super::Exit::bad_input("--scans must be > 0 and every σ ≥ 0").into());
        }
        Ok(o)
    }
}

/// Parses the evaluation's arguments (`Ok(None)` for `--help`, after printing it).
pub fn parse_args(args: &[String]) -> anyhow::Result<Option<EvalOptions>> {
    super::parse_sub::<Args>("pfe eval", args)?
        .map(Args::options)
        .transpose()
}

/// `pfe eval` from an argument list (the `eval` example's entry point).
pub fn cli(args: &[String]) -> anyhow::Result<()> {
    match parse_args(args)? {
        Some(options) => run_options(&options),
        None => Ok(()),
    }
}

/// Runs `pfe eval`.
pub fn run(args: Args) -> anyhow::Result<()> {
    run_options(&args.options()?)
}

fn run_options(options: &EvalOptions) -> anyhow::Result<()> {
    if cfg!(debug_assertions) {
        eprintln!("warning: debug build: times are not representative (use --release)");
    }
    const FILES: [&str; 5] = [
        "EVALUATION.md",
        "eval-errors.svg",
        "eval-ratios.svg",
        "eval-time.svg",
        "eval-scenes.svg",
    ];
    if let Some(dir) = &options.out {
        let paths: Vec<PathBuf> = FILES.iter().map(|f| dir.join(f)).collect();
        pfe_formats::outfile::check(paths.iter().map(PathBuf::as_path), options.force)?;
    }
    let mut methods = default_methods();
    let ev = evaluate(&mut methods, options);
    let md = report::markdown(&ev);
    print!("{}", report::text(&ev));
    if let Some(dir) = &options.out {
        // Again: a file may have appeared during the run; write all or none.
        let paths: Vec<PathBuf> = FILES.iter().map(|f| dir.join(f)).collect();
        pfe_formats::outfile::check(paths.iter().map(PathBuf::as_path), options.force)?;
        let bodies = [
            md,
            svg::errors_vs_noise(&ev),
            svg::ratios_vs_noise(&ev),
            svg::time_per_scan(&ev),
            svg::scene_gallery(options.seed, options.sigma),
        ];
        for (name, body) in FILES.iter().zip(bodies) {
            let p = dir.join(name);
            pfe_formats::outfile::write(&p, &body, options.force)?;
            eprintln!("wrote {}", p.display());
        }
    }
    Ok(())
}
