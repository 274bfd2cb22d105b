//! `pfe bench`: host speed of every method on the same scans ([`pfe_eval::bench`]).

use std::path::PathBuf;

use pfe_eval::bench::{budget_lines, scaling, table, write_markdown, BenchOptions};

/// Arguments of `pfe bench`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Number of simulated scans.
    #[arg(long, default_value_t = 200)]
    sim_scans: usize,
    /// Seed of the simulated scans.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Also time real scans: the CARMEN logs (*.log, *.clf, gzipped or not) in this
    /// directory (without it: simulated scans only; a directory with no scan in it: exit 2).
    #[arg(long, value_name = "DIR")]
    carmen: Option<PathBuf>,
    /// At most this many scans from each CARMEN log (0 = all).
    #[arg(long, default_value_t = 200)]
    per_log: usize,
    /// Timed passes per data set and method; the median is reported.
    #[arg(long, default_value_t = 11)]
    reps: usize,
    /// Time only this method (`pfe-default`, `pfe-paper`, `acf`, `split-merge`; in the
    /// interleaved data set `pfe-default` is the one told 2 sweeps): for profiling one method.
    #[arg(long, value_name = "METHOD")]
    only: Option<String>,
    /// Time only these data sets (`simulated`, `interleaved`, `carmen`; repeatable; default
    /// all, carmen when --carmen is given).
    #[arg(long = "dataset", value_name = "NAME", value_parser = ["simulated", "interleaved", "carmen"])]
    datasets: Vec<String>,
    /// Print machine-readable JSON instead of the table.
    #[arg(long)]
    json: bool,
    /// Also time every method against the number of beams (0.25° scans cut to their first n
    /// beams) and write the tables into the `host` section of this Markdown file, with the
    /// plot next to it (`perf-scaling.svg`).
    #[arg(long)]
    md: Option<PathBuf>,
    /// Replace --md and its plot even when no pfe command wrote them.
    #[arg(long, requires = "md")]
    force: bool,
    /// Report the budgets but exit 0 when one is broken (CI: host timings depend on the
    /// machine and its load, so they are reported there, not asserted).
    #[arg(long)]
    report_only: bool,
}

/// `pfe bench` from an argument list.
pub fn cli(args: &[String]) -> anyhow::Result<()> {
    super::parse_sub::<Args>("pfe bench", args)?.map_or(Ok(()), run)
}

/// Runs `pfe bench`.
pub fn run(args: Args) -> anyhow::Result<()> {
    if let Some(md) = &args.md {
        let plot = pfe_formats::outfile::beside(md, "perf-scaling.svg");
        pfe_formats::outfile::check(
            std::iter::once(md.as_path()).chain(plot.as_deref()),
            args.force,
        )?;
    }
    if let Some(dir) = &args.carmen {
        if !dir.is_dir() {
            let why = if dir.exists() {
                "not a directory (give the folder of CARMEN logs)"
            } else {
                "no such directory"
            };
            return Err(
                super::Exit::bad_input(format!("--carmen {}: {why}", dir.display())).into(),
            );
        }
    }
    let report = pfe_eval::bench::run(&BenchOptions {
        sim_scans: args.sim_scans,
        seed: args.seed,
        carmen: args.carmen.clone(),
        per_log: args.per_log,
        reps: args.reps,
        only: args.only.clone(),
        datasets: args.datasets.clone(),
    })
    .map_err(|e| match e.downcast::<pfe_eval::bench::NoScans>() {
        Ok(none) => super::Exit::bad_input(none.to_string()).into(),
        Err(e) => e,
    })?;
    let (budgets, met) = budget_lines(&report);
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
        eprintln!("{}", budgets.join("\n"));
    } else {
        println!("{}\n{}", table(&report), budgets.join("\n"));
    }
    if let Some(md) = &args.md {
        let sweep = scaling(args.sim_scans.clamp(1, 50), args.seed, args.reps);
        write_markdown(md, &report, &budgets, &sweep, args.force)?;
        eprintln!("wrote {} and perf-scaling.svg next to it", md.display());
    }
    if !met && !args.report_only {
        anyhow::bail!("a host budget is not met (see above; --report-only to exit 0)");
    }
    Ok(())
}
