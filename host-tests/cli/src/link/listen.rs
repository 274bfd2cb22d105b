//! `pfe listen`'s library: the firmware's frames from any byte stream to JSON lines.
//!
//! [`Listener`] wraps the firmware's [`FrameDecoder`]: feed it byte chunks, it hands back each
//! good scan frame and counts everything else (bad CRC, unknown version, other damage, bytes
//! skipped), so a damaged frame is dropped and the next one decodes. [`ListenJson`] is one
//! output line: `pfe extract`'s [`ScanJson`] plus what only the link knows (see `docs/JSON.md`).
//!
//! ```
//! use pfe_frame::{write_scan, Counters, ScanHeader};
//! use pfe_cli::link::listen::{Listener, ListenJson};
//! use pfe_testkit::qemu::VecWriter;
//! let mut w = VecWriter(vec![0x55, 0x00]); // a damaged tail, then a frame
//! let h = ScanHeader { seq: 4, time_ms: 250, ..ScanHeader::default() };
//! write_scan(&mut w, &h, &[]).unwrap();
//! let mut l = Listener::new();
//! let mut got = Vec::new();
//! l.feed(&w.0, |f| got.push(ListenJson::from_frame(f, None)));
//! assert_eq!(got.len(), 1);
//! assert_eq!((got[0].seq, got[0].time_ms), (4, 250));
//! assert_eq!((l.stats().frames_ok, l.stats().bad_other, l.stats().bytes_skipped), (1, 1, 2));
//! ```

use std::fs::{File, OpenOptions};
use std::io::{self, Read};
use std::net::TcpStream;
use std::os::fd::AsFd;
use std::os::unix::fs::OpenOptionsExt;
use std::path::Path;

use anyhow::{bail, Context, Result};
use nix::sys::termios::{self, SetArg};
use pfe_frame::{
    max_frame_len, DecodeError, Feed, Frame, FrameDecoder, Header, PoseBlock, PoseCov, PoseStatus,
    ScanHeader, ScanStatus, MAX_FEATURES,
};
use serde::Serialize;

use crate::device::tty::baud_rate;
use crate::odometry::{PoseJson, StepJson};

use pfe_formats::{FeatureJson, ScanJson, StatusJson};

/// Receive buffer: the largest frame the firmware can send.
const BUF: usize = max_frame_len(MAX_FEATURES);

/// What a [`Listener`] has seen so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct ListenStats {
    /// Bytes received.
    pub bytes: u64,
    /// Frames decoded (scans and reports).
    pub frames_ok: u64,
    /// Scan frames among them.
    pub scans: u64,
    /// Frames dropped for a CRC mismatch.
    pub bad_crc: u64,
    /// Intact frames of another wire version, dropped.
    pub unknown_version: u64,
    /// Frames dropped for anything else (COBS, overflow, too short, bad payload).
    pub bad_other: u64,
    /// Bytes of dropped frames (and of a partial frame at the end), skipped.
    pub bytes_skipped: u64,
}

impl ListenStats {
    /// True when bytes arrived but not one frame decoded.
    pub fn nothing_valid(&self) -> bool {
        self.bytes > 0 && self.frames_ok == 0
    }
}

/// Sans-IO receiver of the firmware's frames.
pub struct Listener {
    dec: Box<FrameDecoder<BUF>>,
    stats: ListenStats,
    /// Bytes of the frame being received.
    pending: u64,
}

impl Default for Listener {
    fn default() -> Self {
        Self::new()
    }
}

impl Listener {
    /// A listener with nothing received.
    pub fn new() -> Self {
        Self {
            dec: Box::new(FrameDecoder::new()),
            stats: ListenStats::default(),
            pending: 0,
        }
    }

    /// Counts so far (bytes of an unfinished frame are not yet counted as skipped).
    pub fn stats(&self) -> ListenStats {
        self.stats
    }

    /// Counts at the end of the stream: an unfinished frame's bytes are skipped.
    pub fn finish(&mut self) -> ListenStats {
        self.stats.bytes_skipped += std::mem::take(&mut self.pending);
        self.stats
    }

    /// Feeds `data`; calls `on_scan` for every good scan frame, in order.
    pub fn feed(&mut self, mut data: &[u8], mut on_scan: impl FnMut(&Frame)) {
        self.stats.bytes += data.len() as u64;
        while !data.is_empty() {
            let before = data.len();
            match self.dec.feed(data) {
                Feed::Consumed => {
                    self.pending += before as u64;
                    return;
                }
                Feed::Frame { frame, remaining } => {
                    self.pending = 0;
                    self.stats.frames_ok += 1;
                    if frame.scan().is_some() {
                        self.stats.scans += 1;
                        on_scan(&frame);
                    }
                    data = remaining;
                }
                Feed::Error { error, remaining } => {
                    let used = (before - remaining.len()) as u64;
                    self.stats.bytes_skipped += std::mem::take(&mut self.pending) + used;
                    match error {
                        DecodeError::Crc { .. } => self.stats.bad_crc += 1,
                        DecodeError::UnknownVersion { .. } => self.stats.unknown_version += 1,
                        _ => self.stats.bad_other += 1,
                    }
                    data = remaining;
                }
            }
        }
    }
}

/// The link counters of a scan frame, as output.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct CountersJson {
    /// Scanner telegrams received with a good CRC (cumulative).
    pub telegrams: u32,
    /// Scanner telegrams dropped for a bad CRC or length (cumulative).
    pub crc_dropped: u32,
    /// Bytes the firmware skipped on the scanner line (cumulative).
    pub bytes_skipped: u32,
    /// Scanner re-initialisations (cumulative).
    pub reinits: u32,
}

/// One line of `pfe listen` output: [`ScanJson`] (scan = seq, no marks) plus the frame's
/// header and the receive time.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ListenJson {
    /// The scan as `pfe extract` prints it.
    #[serde(flatten)]
    pub scan: ScanJson,
    /// Frame sequence number (0 = first scan after the firmware started; wraps).
    pub seq: u32,
    /// Firmware time of the scan, ms (wraps).
    pub time_ms: u32,
    /// Valid readings in the scan.
    pub valid: u16,
    /// Segments found.
    pub segments: u16,
    /// Link counters after this scan.
    pub counters: CountersJson,
    /// The firmware's pose of this scan (its feature odometry), as `pfe odometry` prints it:
    /// `rel`, `pose`, `status`, `direction`, `reason` (absent for frames without a pose block:
    /// versions 2 and 3).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub odometry: Option<StepJson>,
    /// Receive time, Unix seconds (absent in `docs/FRAME.md`'s test vector).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub received: Option<f64>,
}

/// A frame's pose block as `pfe odometry` prints a scan's result.
pub fn step_json(p: &PoseBlock) -> StepJson {
    let pose = |c: &PoseCov| {
        let mut cov = [0.0; 9];
        for (slot, v) in cov.iter_mut().zip(c.cov.iter().flatten()) {
            *slot = *v;
        }
        PoseJson {
            x: c.x,
            y: c.y,
            theta: c.theta,
            cov,
        }
    };
    let (status, direction, reason) = match p.status {
        PoseStatus::Ok => ("ok", None, None),
        PoseStatus::Degenerate { direction } => ("degenerate", Some(direction), None),
        PoseStatus::None(f) => ("none", None, Some(format!("{f:?}"))),
    };
    StepJson {
        rel: pose(&p.rel),
        pose: pose(&p.pose),
        status,
        direction,
        reason,
    }
}

/// The status of a frame as `pfe extract`'s status object.
pub fn status_json(h: &ScanHeader) -> StatusJson {
    let error = match h.status {
        ScanStatus::Ok => None,
        ScanStatus::FeatureCapacity => Some("feature_capacity"),
        ScanStatus::TooManyReadings => Some("too_many_readings"),
        ScanStatus::InvalidInput => Some("invalid_input"),
    };
    StatusJson {
        error: error.map(str::to_string),
        dropped: usize::from(h.dropped),
    }
}

impl ListenJson {
    /// The output line of a scan frame (a report frame gives a line with seq 0 and no
    /// features; [`Listener::feed`] only passes scan frames).
    pub fn from_frame(frame: &Frame, received: Option<f64>) -> Self {
        let h = match frame.header {
            Header::Scan(h) => h,
            Header::Report(_) => ScanHeader::default(),
        };
        let c = h.counters;
        Self {
            scan: ScanJson {
                scan: u64::from(h.seq),
                time: None,
                pose: None,
                marks: None,
                features: frame.features.iter().map(FeatureJson::from).collect(),
                veils: Vec::new(),
                status: status_json(&h),
            },
            seq: h.seq,
            time_ms: h.time_ms,
            valid: h.valid,
            segments: h.segments,
            counters: CountersJson {
                telegrams: c.telegrams_ok,
                crc_dropped: c.crc_dropped,
                bytes_skipped: c.bytes_skipped,
                reinits: c.reinits,
            },
            odometry: frame.pose.as_ref().map(step_json),
            received,
        }
    }
}

/// Opens a serial port or pty read-only, raw 8N1 at `bps` (blocking reads).
pub fn open_tty(path: &Path, bps: u32) -> Result<File> {
    let rate = baud_rate(bps).with_context(|| format!("unsupported baud rate {bps}"))?;
    let file = OpenOptions::new()
        .read(true)
        .custom_flags(nix::libc::O_NOCTTY)
        .open(path)
        .with_context(|| format!("opening {}", path.display()))?;
    let mut t = termios::tcgetattr(file.as_fd())
        .with_context(|| format!("{} is not a tty", path.display()))?;
    termios::cfmakeraw(&mut t);
    termios::cfsetspeed(&mut t, rate)?;
    termios::tcsetattr(file.as_fd(), SetArg::TCSANOW, &t)?;
    Ok(file)
}

/// True when `path` is a terminal (serial port or pty).
pub fn is_tty(path: &Path) -> bool {
    File::open(path)
        .ok()
        .is_some_and(|f| termios::tcgetattr(f.as_fd()).is_ok())
}

/// Where `pfe listen` reads from.
#[derive(Clone, Debug, PartialEq)]
pub enum Source {
    /// A serial port or pty at a baud rate.
    Tty(std::path::PathBuf, u32),
    /// A TCP connection.
    Tcp(String),
    /// A file (a tty path is opened as [`Source::Tty`]), `-` = stdin.
    Input(std::path::PathBuf),
}

impl Source {
    /// Opens the source as a byte stream.
    pub fn open(&self, baud: u32) -> Result<Box<dyn Read + Send>> {
        Ok(match self {
            Source::Tty(p, bps) => Box::new(open_tty(p, *bps)?),
            Source::Tcp(addr) => {
                Box::new(TcpStream::connect(addr).with_context(|| format!("connecting to {addr}"))?)
            }
            Source::Input(p) if p.as_os_str() == "-" => Box::new(io::stdin()),
            Source::Input(p) if is_tty(p) => Box::new(open_tty(p, baud)?),
            Source::Input(p) => {
                if p.is_dir() {
                    bail!("{} is a directory", p.display());
                }
                Box::new(File::open(p).with_context(|| format!("opening {}", p.display()))?)
            }
        })
    }
}
