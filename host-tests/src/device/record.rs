//! Capture raw LMS200 bytes from a serial port through the firmware driver (`pfe record`).
//!
//! The firmware [`Driver`] runs over the std adapters of [`super::tty`]; every byte received from
//! the port is written to the capture file (the capture format is just the raw device bytes,
//! decodable with `pfe decode --format lms200`).

use std::fs::File;
use std::path::Path;

use anyhow::{Context, Result};
use firmware::lms::driver::{Config, Driver};

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
}

/// Records `scans` scans from `port` into `out` with driver config `cfg`.
pub fn record(port: &Path, cfg: Config, scans: u32, out: &Path) -> Result<RecordSummary> {
    let sink = File::create(out).with_context(|| format!("creating {}", out.display()))?;
    let tty = TtyPort::open(port)?.with_capture(Box::new(std::io::BufWriter::new(sink)));
    let mut lms = Driver::new(tty, StdDelay, StdClock::default(), cfg);
    for _ in 0..scans {
        lms.next_scan()
            .map_err(|e| anyhow::anyhow!("LMS200 on {}: {e}", port.display()))?;
    }
    // Leave the device quiet (request mode); a failure here does not spoil the capture.
    let _ = lms.stop();
    let c = lms.counters();
    let (mut tty, _, _) = lms.release();
    tty.finish()?;
    Ok(RecordSummary {
        scans: c.scans,
        bytes: tty.captured(),
        telegrams_ok: c.telegrams_ok,
        crc_errors: c.crc_errors,
        bytes_skipped: c.bytes_skipped,
        reinits: c.reinits,
    })
}
