//! Capture raw LMS200 bytes from a serial port through the firmware driver (`pfe record`).
//!
//! The firmware [`Driver`] runs over the std adapters of [`super::tty`]; every byte the driver
//! reads from the port, up to the end of the last scan's telegram, is written to the capture
//! (the capture format is just the raw device bytes, decodable with `pfe decode`; it holds
//! the scans reported, not those still arriving while the device is stopped). The port is opened before the output is touched, the bytes go
//! to a temporary file beside the output, and that file is renamed to the output at the end,
//! also when the run is stopped or fails halfway with bytes received, so a capture is never
//! lost and an existing file is never emptied by a run that could not start.

use std::fs::File;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use anyhow::{Context, Result};
use lms2xx::driver::{Config, Driver};

use super::tty::{StdClock, StdDelay, TtyPort};

/// Summary of a recording.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RecordSummary {
    /// Scans delivered by the driver.
    pub scans: u32,
    /// Raw bytes written to the capture.
    pub bytes: u64,
    /// Good telegrams.
    pub telegrams_ok: u32,
    /// CRC errors.
    pub crc_errors: u32,
    /// Bytes skipped.
    pub bytes_skipped: u32,
    /// Re-initialisations.
    pub reinits: u32,
    /// True when `stop` ended the run before all scans were recorded.
    pub interrupted: bool,
}

/// How [`record`] treats the output and when it stops early.
#[derive(Clone, Debug, Default)]
pub struct RecordOptions {
    /// Replace an existing output file (otherwise an existing one is an error).
    pub overwrite: bool,
    /// Stop (keeping what was received) once this is set, e.g. by Ctrl-C.
    pub stop: Option<Arc<AtomicBool>>,
}

/// The output exists and [`RecordOptions::overwrite`] is off.
#[derive(Debug)]
pub struct OutputExists(pub PathBuf);

impl std::fmt::Display for OutputExists {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} exists; not overwriting it (--force to replace it)",
            self.0.display()
        )
    }
}

impl std::error::Error for OutputExists {}

/// The temporary file beside `out` that a capture is written to.
fn temporary(out: &Path) -> PathBuf {
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    out.with_file_name(format!(".{name}.part-{}", std::process::id()))
}

/// Records `scans` scans from `port` into `out` with driver config `cfg`.
pub fn record(
    port: &Path,
    cfg: Config,
    scans: u32,
    out: &Path,
    opts: &RecordOptions,
) -> Result<RecordSummary> {
    if !opts.overwrite && out.symlink_metadata().is_ok() {
        return Err(OutputExists(out.to_path_buf()).into());
    }
    pfe_formats::outfile::check_dir(out)?;
    // A port that cannot be opened as a tty is bad input (exit 2), as for `pfe listen`.
    let mut tty = TtyPort::open(port).map_err(|e| crate::Exit::bad_input(format!("{e:#}")))?;
    if let Some(stop) = &opts.stop {
        tty = tty.with_stop(stop.clone());
    }
    let tmp = temporary(out);
    let sink = File::options()
        .write(true)
        .create_new(true)
        .open(&tmp)
        .with_context(|| format!("creating {}", tmp.display()))?;
    let tty = tty.with_capture(Box::new(std::io::BufWriter::new(sink)));
    let capturing = tty.capture_switch();
    let stopped = || {
        opts.stop
            .as_ref()
            .is_some_and(|s| s.load(Ordering::Relaxed))
    };
    let mut lms = Driver::new(tty, StdDelay, StdClock::default(), cfg);
    let mut failure = None;
    let mut interrupted = false;
    for _ in 0..scans {
        if stopped() {
            interrupted = true;
            break;
        }
        if let Err(e) = lms.next_scan() {
            if stopped() {
                interrupted = true;
            } else {
                failure = Some(anyhow::anyhow!("LMS200 on {}: {e}", port.display()));
            }
            break;
        }
    }
    // The capture ends with the last scan's telegram: the scans still arriving while the
    // device is told to stop are not kept, so the capture holds the scans reported.
    capturing.store(false, Ordering::Relaxed);
    // Leave the device quiet (request mode); a failure here does not spoil the capture.
    if !interrupted {
        let _ = lms.stop();
    }
    let c = lms.counters();
    let (mut tty, _, _) = lms.release();
    let flushed = tty.finish();
    let bytes = tty.captured();
    drop(tty);
    let kept = if bytes > 0 && flushed.is_ok() {
        std::fs::rename(&tmp, out)
            .with_context(|| format!("renaming {} to {}", tmp.display(), out.display()))?;
        true
    } else {
        let _ = std::fs::remove_file(&tmp);
        false
    };
    flushed.with_context(|| format!("writing {}", tmp.display()))?;
    if let Some(e) = failure {
        return Err(if kept {
            e.context(format!(
                "the {bytes} bytes received are kept in {}",
                out.display()
            ))
        } else {
            e
        });
    }
    Ok(RecordSummary {
        scans: c.scans,
        bytes,
        telegrams_ok: c.telegrams_ok,
        crc_errors: c.crc_errors,
        bytes_skipped: c.bytes_skipped,
        reinits: c.reinits,
        interrupted,
    })
}
