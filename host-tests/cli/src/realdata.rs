//! `pfe realdata`: the real-data benchmark without ground truth ([`pfe_eval::realdata`]).

use std::path::PathBuf;

use pfe_eval::realdata::{report, run_log};
use pfe_formats::Format;

/// Arguments of `pfe realdata`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// CARMEN logs with poses (gzip allowed).
    #[arg(required = true)]
    logs: Vec<PathBuf>,
    /// At most this many scans of each log (0 = all).
    #[arg(long, default_value_t = 0)]
    max_scans: usize,
    /// Range noise σ_r told to every method, mm.
    #[arg(long, default_value_t = Format::Carmen.sigma_r())]
    sigma_r: f32,
    /// Also write this Markdown report, with its plots (SVG) next to it.
    #[arg(long)]
    md: Option<PathBuf>,
    /// Interleaved sweeps each scan is declared to be made of (1, 2 or 4), or `auto`: one for a
    /// ROBOTLASER1/RAWLASER1 line whose laser is not a SICK LMS, else a SICK LMS2xx's (2 at
    /// 0.5°, 4 at 0.25°, 1 otherwise). pfe aligns declared sweeps whose offset shows.
    #[arg(long, default_value = "auto", value_parser = crate::input::sweeps_parser())]
    sweeps: crate::input::Sweeps,
    /// Tell the methods each scan's motion, from the poses and times of the scans before and
    /// after it (when they are at most 1 s apart): pfe's two modes de-skew the beams with it,
    /// interleaved sweeps by the LMS2xx's beam timing (split-and-merge and ACF take none).
    #[arg(long)]
    odometry_from_poses: bool,
    /// Replace --md and its plots even when no pfe command wrote them.
    #[arg(long, requires = "md")]
    force: bool,
    /// The command named in the Markdown report.
    #[arg(long, default_value = "pfe realdata")]
    command: String,
}

/// Runs `pfe realdata`.
pub fn run(args: Args) -> anyhow::Result<()> {
    // Refused outputs are known before the run, not after it.
    if let Some(md) = &args.md {
        let files = report::output_files(md);
        pfe_formats::outfile::check(files.iter().map(PathBuf::as_path), args.force)?;
    }
    // Unreadable logs are known before the run, not after the first ones.
    for log in &args.logs {
        std::fs::File::open(log)
            .map_err(|e| super::Exit::bad_input(format!("{}: {e}", log.display())))?;
    }
    // A log that cannot be compared is named and left out; the others are still compared.
    let mut reports = Vec::new();
    let mut refused = Vec::new();
    for log in &args.logs {
        match compared(log, &args) {
            Ok(r) => {
                println!("{}", report::table(&r));
                reports.push(r);
            }
            Err(e) if e.is::<super::Exit>() => {
                eprintln!("pfe: realdata: {e:#}");
                refused.push(log.display().to_string());
            }
            Err(e) => return Err(e),
        }
    }
    if let (Some(md), false) = (&args.md, reports.is_empty()) {
        report::write_markdown(md, &reports, &args.command, args.force)?;
        let plots = report::output_files(md).len() > 1;
        let and = if plots { " and its plots" } else { "" };
        eprintln!("wrote {}{and}", md.display());
    }
    if !refused.is_empty() {
        return Err(super::Exit::bad_input(format!(
            "{} of {} logs left out: {}",
            refused.len(),
            args.logs.len(),
            refused.join(", ")
        ))
        .into());
    }
    Ok(())
}

/// The benchmark's report of `log`, or bad input ([`super::Exit`]) when it holds a malformed
/// line or no two consecutive scans with a pose.
fn compared(log: &std::path::Path, args: &Args) -> anyhow::Result<pfe_eval::realdata::LogReport> {
    let told = pfe_eval::realdata::Told {
        sweeps: args.sweeps.0,
        odometry_from_poses: args.odometry_from_poses,
    };
    let r =
        run_log(log, args.sigma_r, args.max_scans, told).map_err(|e| match e
            .downcast_ref::<pfe_formats::InputError>()
        {
            Some(_) => super::Exit::bad_input(format!("{e:#}")).into(),
            None => e,
        })?;
    if r.methods.first().map_or(0, |m| m.pairs) == 0 {
        let scans = r.methods.first().map_or(0, |m| m.scans);
        return Err(super::Exit::bad_input(format!(
            "{}: {scans} scan(s) and no two consecutive ones with a pose: nothing to compare \
             (the benchmark needs a CARMEN log whose FLASER or ROBOTLASER1 lines give poses)",
            log.display()
        ))
        .into());
    }
    Ok(r)
}
