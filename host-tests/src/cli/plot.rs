//! `pfe plot`: one scan with its mark points and features as SVG (like Fig. 7 of the paper).

use std::io::Write;
use std::path::PathBuf;

use super::input::{bad_input, nothing_found, open_scans, MethodArgs, Scan};
use super::Failure;
use crate::methods::Method;

/// Arguments of `pfe plot`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Input file.
    file: PathBuf,
    #[command(flatten)]
    method: MethodArgs,
    /// Scan ID to plot (the csv ID, else the 0-based ordinal).
    #[arg(long, short)]
    scan: u64,
    /// Output SVG file (`-` = stdout).
    #[arg(short, long)]
    output: PathBuf,
}

/// Runs `pfe plot`.
pub fn run(a: Args) -> Result<(), Failure> {
    let (file, format, scan, output) = (
        a.file.as_path(),
        a.method.format,
        a.scan,
        a.output.as_path(),
    );
    let mut method = a.method.method();
    let input = open_scans(file, format, a.method.topic.as_deref())?;
    let bar = input.bar.clone();
    let mut found: Option<Scan> = None;
    let mut count = 0u64;
    for s in input.scans {
        let s = s.map_err(|e| bad_input(file, format, count, &e))?;
        count += 1;
        if s.record.id == scan {
            found = Some(s);
            break;
        }
    }
    bar.finish_and_clear();
    if count == 0 && input.bytes.load(std::sync::atomic::Ordering::Relaxed) > 0 {
        return Err(nothing_found(file, format, "scan"));
    }
    let found = found.ok_or_else(|| {
        Failure::input(format!(
            "{}: no scan with ID {scan} ({count} scans read)",
            file.display()
        ))
    })?;
    let record = &found.record;
    let ex = method.extract(&record.geometry, &record.ranges_mm);
    let name = file
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let title = match (&found.frame_id, found.stamp_ns) {
        (Some(frame), Some(t)) => format!(
            "{name} — scan {scan} ({frame}, {}.{:09} s) — {}",
            t / 1_000_000_000,
            t % 1_000_000_000,
            method.name()
        ),
        _ => format!("{name} — scan {scan} — {}", method.name()),
    };
    let svg = crate::plot::svg(record, &ex, &title);
    if output.as_os_str() == "-" {
        let mut out = std::io::stdout().lock();
        match out.write_all(svg.as_bytes()).and_then(|()| out.flush()) {
            Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
                return Err(Failure::other(format!("cannot write output: {e}")));
            }
            _ => {}
        }
    } else {
        std::fs::write(output, svg)
            .map_err(|e| Failure::other(format!("{}: cannot write: {e}", output.display())))?;
    }
    eprintln!(
        "pfe: wrote {} ({} marks, {} features)",
        if output.as_os_str() == "-" {
            "the SVG to stdout".to_string()
        } else {
            output.display().to_string()
        },
        ex.marks.len(),
        ex.features.len()
    );
    Ok(())
}
