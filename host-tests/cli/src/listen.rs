//! `pfe listen`: the firmware's feature frames from a serial port, pty, TCP socket, file or
//! stdin as JSON lines (one per scan), a summary on stderr at the end and on Ctrl-C.

use std::collections::HashSet;
use std::io::{self, Write};
use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::sync::mpsc;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use super::input::write_json;
use super::Failure;
use crate::foxglove::{self, FoxgloveServer, FoxgloveWriter};
use crate::link::clock::FirmwareClock;
use crate::link::listen::{ListenJson, ListenStats, Listener, Source};
use pfe_eval::methods::Extraction;
use pfe_formats::Record;

/// The board's feature UART (USART2 of `firmware/board`).
const DEFAULT_PORT: &str = "/dev/ttyUSB1";
/// The board's feature UART rate.
const DEFAULT_BAUD: u32 = 460_800;

/// Arguments of `pfe listen`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Reads the firmware's frames (docs/FRAME.md) and prints one JSON line per \
                        scan (docs/JSON.md). Damaged frames are counted and dropped. Exit code 2 \
                        for bad arguments or a stream with bytes but no valid frame, 1 otherwise."
)]
pub struct Args {
    /// Serial port of the firmware's feature UART (when neither --input nor --tcp is given).
    #[arg(long, default_value = DEFAULT_PORT, conflicts_with_all = ["tcp", "input"])]
    port: PathBuf,
    /// Baud rate of the serial port (or of a tty given as --input).
    #[arg(long, default_value_t = DEFAULT_BAUD)]
    baud: u32,
    /// Read from a TCP socket HOST:PORT instead.
    #[arg(long, conflicts_with = "input")]
    tcp: Option<String>,
    /// Read from a file, a pty or serial device path, or `-` for stdin.
    #[arg(long)]
    input: Option<PathBuf>,
    /// Stop after N scans.
    #[arg(long)]
    scans: Option<u64>,
    /// Stop after S seconds.
    #[arg(long)]
    seconds: Option<f64>,
    /// Write an SVG plot of scans into DIR (DIR is created if missing, its parent must exist;
    /// existing files are kept).
    #[arg(long)]
    svg: Option<PathBuf>,
    /// With --svg: plot every Nth scan only.
    #[arg(long, default_value_t = 1, requires = "svg")]
    svg_every: u64,
    /// Also write the features to a Foxglove MCAP file (`foxglove.SceneUpdate` on /features,
    /// stamped with the firmware's time; log time = receive time), completed at the end.
    #[arg(long)]
    mcap: Option<PathBuf>,
    /// With --mcap: replace an existing file.
    #[arg(long, requires = "mcap")]
    force: bool,
    /// Also serve the features live over Foxglove's WebSocket protocol (ws://BIND) while
    /// listening (clients are disconnected when the input ends).
    #[arg(long)]
    foxglove: bool,
    /// With --foxglove: the address to listen on (port 0 = any free port; the address is
    /// printed on stderr). Other hosts can connect only if this says so.
    #[arg(long, default_value = "127.0.0.1:8765", requires = "foxglove")]
    bind: String,
}

/// Frame of reference of the features in Foxglove.
const FRAME_ID: &str = "laser";

/// Where the scans go besides stdout: a Foxglove file and a Foxglove server.
struct Foxglove {
    file: Option<FoxgloveWriter>,
    server: Option<FoxgloveServer>,
    clock: FirmwareClock,
}

impl Foxglove {
    fn start(a: &Args) -> Result<Self, Failure> {
        let file = match &a.mcap {
            Some(p) => Some(
                pfe_formats::outfile::check_dir(p)
                    .map_err(|e| Failure::input(format!("--mcap {e}")))
                    .and_then(|()| {
                        FoxgloveWriter::create_features_only(p, a.force).map_err(|e| {
                            if e.kind() == io::ErrorKind::AlreadyExists {
                                Failure::input(format!("--mcap: {e}; --force replaces it"))
                            } else {
                                Failure::input(format!("--mcap {}: {e}", p.display()))
                            }
                        })
                    })?,
            ),
            None => None,
        };
        let server = if a.foxglove {
            let s = FoxgloveServer::bind(a.bind.as_str(), "pfe listen", &[foxglove::FEATURES])
                .map_err(|e| Failure::input(format!("--bind {}: {e}", a.bind)))?;
            eprintln!("pfe listen: Foxglove WebSocket on ws://{}", s.local_addr());
            Some(s)
        } else {
            None
        };
        Ok(Self {
            file,
            server,
            clock: FirmwareClock::new(),
        })
    }

    fn scan(
        &mut self,
        time_ms: u32,
        received_ns: u64,
        features: &[pfe_core::Feature],
    ) -> Result<(), Failure> {
        if self.file.is_none() && self.server.is_none() {
            return Ok(());
        }
        let stamp = self.clock.stamp_ns(time_ms, received_ns);
        if let Some(f) = self.file.as_mut() {
            f.write_features(received_ns, stamp, FRAME_ID, features)
                .map_err(|e| Failure::other(format!("writing --mcap: {e}")))?;
        }
        if let Some(s) = &self.server {
            let scene = foxglove::scene_update(stamp, FRAME_ID, features);
            s.publish(0, received_ns, scene.to_string().into_bytes());
        }
        Ok(())
    }

    /// Completes the file (kept only if a scan arrived) and closes the clients' connections.
    fn finish(self, keep: bool) -> Result<(), Failure> {
        if let Some(s) = self.server {
            let dropped = s.dropped();
            s.finish();
            if dropped > 0 {
                eprintln!("pfe listen: {dropped} messages not sent to slow Foxglove clients");
            }
        }
        match self.file {
            Some(f) if keep => {
                let p = f
                    .finish()
                    .map_err(|e| Failure::other(format!("finishing --mcap: {e}")))?;
                eprintln!("pfe listen: wrote {}", p.display());
            }
            _ => {}
        }
        Ok(())
    }
}

fn unix_now_ns() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX))
}

fn summary(s: &ListenStats, why: &str) {
    eprintln!(
        "pfe listen: {why}: {} bytes, {} frames ok ({} scans), {} bad CRC, {} unknown version, \
         {} other damage, {} bytes skipped",
        s.bytes, s.frames_ok, s.scans, s.bad_crc, s.unknown_version, s.bad_other, s.bytes_skipped
    );
}

/// Plots of the scans into a directory, never over a file it did not create.
struct Plots {
    dir: PathBuf,
    every: u64,
    mine: HashSet<PathBuf>,
}

impl Plots {
    fn write(&mut self, j: &ListenJson, features: &[pfe_core::Feature]) -> Result<(), Failure> {
        if self.every == 0 || u64::from(j.seq) % self.every != 0 {
            return Ok(());
        }
        let path = self.dir.join(format!("scan-{:010}.svg", j.seq));
        if path.exists() && !self.mine.contains(&path) {
            eprintln!("pfe listen: {} exists, not overwritten", path.display());
            return Ok(());
        }
        // The frame has no ranges: the plot shows the features only.
        let g = pfe_core::ScanGeometry::LMS200_180_050;
        let record = Record {
            id: u64::from(j.seq),
            geometry: g,
            ranges_mm: vec![f32::NAN; 361],
            time: None,
            pose: None,
            sweeps: None,
        };
        let ex = Extraction {
            marks: Vec::new(),
            features: features.to_vec(),
        };
        let title = format!("pfe listen: scan {} at {} ms", j.seq, j.time_ms);
        std::fs::write(&path, crate::figure::svg(&record, &ex, &title))
            .map_err(|e| Failure::other(format!("writing {}: {e}", path.display())))?;
        self.mine.insert(path);
        Ok(())
    }
}

/// Runs `pfe listen`.
pub fn run(a: Args) -> Result<(), Failure> {
    if a.seconds.is_some_and(|s| !(s.is_finite() && s > 0.0)) {
        return Err(Failure::input("--seconds must be a positive number"));
    }
    if crate::device::tty::baud_rate(a.baud).is_none() {
        return Err(Failure::input(format!("unsupported --baud {}", a.baud)));
    }
    let source = match (&a.tcp, &a.input) {
        (Some(t), _) => Source::Tcp(t.clone()),
        (None, Some(p)) => Source::Input(p.clone()),
        (None, None) => Source::Tty(a.port.clone(), a.baud),
    };
    let mut plots = match &a.svg {
        Some(dir) => {
            // DIR itself, which the user named, not the directories above it.
            if !dir.is_dir() {
                pfe_formats::outfile::check_dir(dir)
                    .map_err(|e| Failure::input(format!("--svg {e}")))?;
                std::fs::create_dir(dir)
                    .map_err(|e| Failure::input(format!("--svg {}: {e}", dir.display())))?;
            }
            Some(Plots {
                dir: dir.clone(),
                every: a.svg_every,
                mine: HashSet::new(),
            })
        }
        None => None,
    };
    let mut fox = Foxglove::start(&a)?;
    let mut reader = source
        .open(a.baud)
        .map_err(|e| Failure::input(format!("{e:#}")))?;
    // `pfe`'s own handler (cli::interrupt): a handler set here would fail, being the second.
    let stop = super::interrupt::flag();
    // The reader runs on its own thread so that --seconds and Ctrl-C end a blocked read.
    let (tx, rx) = mpsc::sync_channel::<io::Result<Vec<u8>>>(64);
    std::thread::spawn(move || {
        let mut buf = vec![0u8; 4096];
        loop {
            let r = match reader.read(&mut buf) {
                Ok(0) => break,
                Ok(n) => Ok(buf[..n].to_vec()),
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                Err(e) => Err(e),
            };
            let end = r.is_err();
            if tx.send(r).is_err() || end {
                break;
            }
        }
    });
    let deadline = a
        .seconds
        .map(|s| Instant::now() + Duration::from_secs_f64(s));
    let mut listener = Listener::new();
    let mut out = io::stdout().lock();
    let mut printed = 0u64;
    let mut why = "end of input";
    let mut failure = None;
    'outer: loop {
        if stop.load(Ordering::SeqCst) {
            why = "interrupted";
            break;
        }
        if deadline.is_some_and(|d| Instant::now() >= d) {
            why = "time limit";
            break;
        }
        let chunk = match rx.recv_timeout(Duration::from_millis(100)) {
            Ok(Ok(c)) => c,
            Ok(Err(e)) => {
                failure = Some(Failure::other(format!("reading: {e}")));
                break;
            }
            Err(mpsc::RecvTimeoutError::Timeout) => continue,
            Err(mpsc::RecvTimeoutError::Disconnected) => break,
        };
        let received_ns = unix_now_ns();
        let received = received_ns as f64 * 1e-9;
        let mut frames = Vec::new();
        listener.feed(&chunk, |f| frames.push(f.clone()));
        for f in frames {
            let j = ListenJson::from_frame(&f, Some(received));
            // On a failure the Foxglove file still gets what came before.
            let written = match plots.as_mut() {
                Some(p) => p.write(&j, &f.features),
                None => Ok(()),
            }
            .and_then(|()| fox.scan(j.time_ms, received_ns, &f.features))
            .and_then(|()| write_json(&mut out, &j));
            let printed_ok = match written {
                Ok(ok) => ok,
                Err(e) => {
                    why = "error";
                    failure = Some(e);
                    break 'outer;
                }
            };
            if !printed_ok {
                why = "output closed";
                break 'outer;
            }
            let _ = out.flush();
            printed += 1;
            if a.scans.is_some_and(|n| printed >= n) {
                why = "scan limit";
                break 'outer;
            }
        }
    }
    let stats = if why == "end of input" {
        listener.finish()
    } else {
        listener.stats()
    };
    summary(&stats, why);
    fox.finish(!stats.nothing_valid())?;
    if let Some(f) = failure {
        return Err(f);
    }
    if stats.nothing_valid() {
        return Err(Failure::input(
            "bytes arrived but no valid frame: is this the firmware's feature output (not the \
             scanner's line), at the right --baud, and firmware of wire version 2?",
        ));
    }
    Ok(())
}
