//! `pfe eval` (and `cargo xtask eval` through the `eval` example): the paper's comparison on
//! simulated scenes; prints the tables and writes `OUT/EVALUATION.md` and `OUT/eval-*.svg`.

use std::path::PathBuf;

use pfe_eval::scene::SceneKind;
use pfe_eval::{default_methods, evaluate, report, svg, EvalOptions};

const HELP: &str =
    "pfe eval [--kind mixed|office|clutter|pillars|corridor] [--scans 100] [--seed 1]
         [--sigma 5] [--sweep 1,2,5,10] [--passes 5] [--out docs | --no-write] [--command TEXT]
         [--force]

Runs PFE paper, PFE default, ACF and split-and-merge on simulated LMS200 scans with ground truth,
prints the tables and writes OUT/EVALUATION.md and OUT/eval-*.svg. Build in release for times.
Files in OUT that no pfe command wrote are not replaced (exit 2) unless --force.";

/// Arguments of `pfe eval` (defaults: [`EvalOptions::default`]).
#[derive(clap::Args, Debug)]
#[command(override_help = HELP, args_override_self = true)]
pub struct Args {
    #[arg(long)]
    kind: Option<SceneKind>,
    #[arg(long)]
    scans: Option<usize>,
    #[arg(long)]
    seed: Option<u64>,
    #[arg(long)]
    sigma: Option<f32>,
    /// Comma-separated σ_r values, mm.
    #[arg(long)]
    sweep: Option<String>,
    #[arg(long)]
    passes: Option<usize>,
    #[arg(long, overrides_with = "no_write")]
    out: Option<PathBuf>,
    #[arg(long, overrides_with = "out")]
    no_write: bool,
    #[arg(long)]
    command: Option<String>,
    #[arg(long)]
    force: bool,
}

impl Args {
    /// The evaluation these arguments ask for.
    pub fn options(self) -> anyhow::Result<EvalOptions> {
        let d = EvalOptions::default();
        let sweep = match self.sweep {
            Some(s) => s
                .split(',')
                .map(|s| s.trim().parse::<f32>())
                .collect::<Result<_, _>>()
                .map_err(|e| super::Exit::bad_input(format!("--sweep: {e}")))?,
            None => d.sweep,
        };
        let o = EvalOptions {
            kind: self.kind.unwrap_or(d.kind),
            scans: self.scans.unwrap_or(d.scans),
            seed: self.seed.unwrap_or(d.seed),
            sigma: self.sigma.unwrap_or(d.sigma),
            sweep,
            passes: self.passes.unwrap_or(d.passes),
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
