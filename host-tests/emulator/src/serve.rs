//! Real-time transports for the emulator: a pseudo-terminal (for real clients such as MRPT or
//! `pfe record`) and a TCP socket (for QEMU's `-serial tcp:…`), on which `pfe emulate` runs.

use std::io::{ErrorKind, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::os::fd::{AsFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use nix::fcntl::{fcntl, FcntlArg, OFlag};
use nix::sys::termios::{self, BaudRate, SetArg};

use super::{Emulator, EmulatorConfig, EmulatorReport};

/// When a real-time run stops.
#[derive(Clone, Debug, Default)]
pub struct RunLimits {
    /// Stop once this many B0 telegrams were sent completely.
    pub scans: Option<u32>,
    /// Stop after this much wall time.
    pub max_time: Option<Duration>,
    /// Print every command received to stderr.
    pub trace: bool,
    /// Stop as soon as this flag is set (from another thread).
    pub stop: Option<std::sync::Arc<std::sync::atomic::AtomicBool>>,
}

/// A byte pipe to the host with an optional notion of the host's baud.
trait Wire {
    /// Reads available host bytes; `Ok(None)` when the host closed the connection.
    fn read_host(&mut self, buf: &mut [u8]) -> std::io::Result<Option<usize>>;
    /// Writes device bytes; returns how many were accepted.
    fn write_device(&mut self, bytes: &[u8]) -> std::io::Result<usize>;
    /// The host's baud, or `None` when the wire has none.
    fn host_baud(&mut self) -> Option<u32>;
}

/// True for the errors by which a peer that closed its end shows up (e.g. QEMU exiting).
fn peer_gone(e: &std::io::Error) -> bool {
    matches!(
        e.kind(),
        ErrorKind::ConnectionReset | ErrorKind::ConnectionAborted | ErrorKind::BrokenPipe
    )
}

fn run_realtime(emu: &mut Emulator, wire: &mut dyn Wire, limits: &RunLimits) -> Result<()> {
    let start = Instant::now();
    let mut buf = [0u8; 4096];
    let mut pending: Vec<u8> = Vec::new();
    let mut out = Vec::new();
    let mut seen_cmds = 0;
    loop {
        let now = start.elapsed().as_micros() as u64;
        let hb = wire.host_baud();
        match wire.read_host(&mut buf) {
            Ok(Some(n)) if n > 0 => emu.receive(now, hb, buf.get(..n).unwrap_or(&[])),
            Ok(Some(_)) => {}
            Ok(None) => break,
            Err(e) if peer_gone(&e) => break,
            Err(e) => return Err(e).context("reading from the host"),
        }
        if limits.trace {
            for c in emu.report().commands.get(seen_cmds..).unwrap_or(&[]) {
                eprintln!(
                    "{:10.4} RX cmd {c:02X} (device at {} baud)",
                    now as f64 / 1e6,
                    emu.baud().bps()
                );
            }
            seen_cmds = emu.report().commands.len();
        }
        emu.set_hold(!pending.is_empty());
        out.clear();
        emu.take_ready(now, hb, &mut out);
        pending.extend(&out);
        if !pending.is_empty() {
            let n = match wire.write_device(&pending) {
                Ok(n) => n,
                Err(e) if peer_gone(&e) => break,
                Err(e) => return Err(e).context("writing to the host"),
            };
            pending.drain(..n.min(pending.len()));
        }
        let done_scans = limits.scans.is_some_and(|n| {
            emu.report().scans.len() as u32 >= n && emu.queued() == 0 && pending.is_empty()
        });
        let timed_out = limits.max_time.is_some_and(|t| start.elapsed() >= t);
        let stopped = limits
            .stop
            .as_ref()
            .is_some_and(|s| s.load(std::sync::atomic::Ordering::Relaxed));
        if done_scans || timed_out || stopped {
            break;
        }
        std::thread::sleep(Duration::from_micros(500));
    }
    Ok(())
}

/// True for an error that only means "not now" on a non-blocking descriptor.
fn busy(e: &std::io::Error) -> bool {
    e.kind() == ErrorKind::WouldBlock || e.kind() == ErrorKind::Interrupted
}

/// Writes what `w` takes of `bytes` now: 0 when it would block.
fn write_some(w: &mut impl Write, bytes: &[u8]) -> std::io::Result<usize> {
    match w.write(bytes) {
        Err(e) if busy(&e) => Ok(0),
        r => r,
    }
}

struct TcpWire {
    s: TcpStream,
}

impl Wire for TcpWire {
    fn read_host(&mut self, buf: &mut [u8]) -> std::io::Result<Option<usize>> {
        match self.s.read(buf) {
            Ok(0) => Ok(None),
            Ok(n) => Ok(Some(n)),
            Err(e) if busy(&e) => Ok(Some(0)),
            Err(e) => Err(e),
        }
    }
    fn write_device(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
        write_some(&mut self.s, bytes)
    }
    fn host_baud(&mut self) -> Option<u32> {
        None
    }
}

/// Accepts one TCP connection on `listener` (e.g. QEMU started with
/// `-serial tcp:127.0.0.1:PORT`) and emulates a device with `config`'s built-in source on it
/// until `limits` or the peer closes. Baud is not modelled (the host is always at the device's
/// rate); output is paced at the device baud and held back while the peer does not read.
pub fn serve_tcp(
    listener: TcpListener,
    config: EmulatorConfig,
    limits: RunLimits,
) -> Result<EmulatorReport> {
    serve_tcp_with(listener, Emulator::from_config(config), limits)
}

/// [`serve_tcp`] with a ready-made emulator (any [`RangeSource`](super::RangeSource)).
pub fn serve_tcp_with(
    listener: TcpListener,
    mut emu: Emulator,
    limits: RunLimits,
) -> Result<EmulatorReport> {
    let (s, _) = listener.accept().context("accepting the TCP connection")?;
    s.set_nonblocking(true)?;
    s.set_nodelay(true)?;
    let mut wire = TcpWire { s };
    run_realtime(&mut emu, &mut wire, &limits)?;
    Ok(emu.report().clone())
}

struct PtyWire {
    master: std::fs::File,
    slave: OwnedFd,
}

fn baud_of(b: BaudRate) -> Option<u32> {
    Some(match b {
        BaudRate::B9600 => 9600,
        BaudRate::B19200 => 19200,
        BaudRate::B38400 => 38400,
        BaudRate::B57600 => 57600,
        BaudRate::B115200 => 115_200,
        BaudRate::B230400 => 230_400,
        BaudRate::B460800 => 460_800,
        BaudRate::B500000 => 500_000,
        BaudRate::B4800 => 4800,
        _ => return None,
    })
}

impl Wire for PtyWire {
    fn read_host(&mut self, buf: &mut [u8]) -> std::io::Result<Option<usize>> {
        match self.master.read(buf) {
            Ok(n) => Ok(Some(n)),
            Err(e) if busy(&e) => Ok(Some(0)),
            // EIO: no process has the slave open (we keep one, so this is transient).
            Err(e) if e.raw_os_error() == Some(nix::libc::EIO) => Ok(Some(0)),
            Err(e) => Err(e),
        }
    }
    fn write_device(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
        write_some(&mut self.master, bytes)
    }
    fn host_baud(&mut self) -> Option<u32> {
        // The client's speed as set on the slave; an unknown one never matches the device.
        termios::tcgetattr(self.slave.as_fd())
            .ok()
            .map(|t| baud_of(termios::cfgetospeed(&t)).unwrap_or(1))
    }
}

/// A pseudo-terminal whose slave is reachable through a symlink at `link`.
pub struct Pty {
    wire: PtyWire,
    link: PathBuf,
    slave_path: PathBuf,
}

impl Pty {
    /// Opens a pty, sets its slave raw at 9600 baud and creates the symlink `link` to it.
    pub fn open(link: &Path) -> Result<Self> {
        let r = nix::pty::openpty(None, None).context("openpty")?;
        let slave_path = nix::unistd::ttyname(r.slave.as_fd()).context("ttyname")?;
        let mut t = termios::tcgetattr(r.slave.as_fd())?;
        termios::cfmakeraw(&mut t);
        termios::cfsetspeed(&mut t, BaudRate::B9600)?;
        termios::tcsetattr(r.slave.as_fd(), SetArg::TCSANOW, &t)?;
        let flags = OFlag::from_bits_truncate(fcntl(r.master.as_fd(), FcntlArg::F_GETFL)?);
        fcntl(
            r.master.as_fd(),
            FcntlArg::F_SETFL(flags | OFlag::O_NONBLOCK),
        )?;
        clear_stale_link(link)?;
        std::os::unix::fs::symlink(&slave_path, link)
            .with_context(|| format!("symlink {} -> {}", link.display(), slave_path.display()))?;
        Ok(Self {
            wire: PtyWire {
                master: std::fs::File::from(r.master),
                slave: r.slave,
            },
            link: link.to_path_buf(),
            slave_path,
        })
    }

    /// Path of the slave device (`/dev/pts/N`).
    pub fn slave_path(&self) -> &Path {
        &self.slave_path
    }
}

impl Drop for Pty {
    /// Removes the link, unless something else has replaced it since.
    fn drop(&mut self) {
        if std::fs::read_link(&self.link).is_ok_and(|t| t == self.slave_path) {
            let _ = std::fs::remove_file(&self.link);
        }
    }
}

/// Makes room for a pty link at `link`: nothing there is fine, a stale link of ours (a symlink
/// to a `/dev/pts/N` that no longer exists) is removed, anything else is refused (a user's
/// file, a directory, a link to a live pty that another emulator may be serving).
pub fn clear_stale_link(link: &Path) -> Result<()> {
    let Ok(meta) = link.symlink_metadata() else {
        return Ok(());
    };
    let target = meta
        .file_type()
        .is_symlink()
        .then(|| std::fs::read_link(link).ok())
        .flatten();
    match target {
        Some(t) if t.starts_with("/dev/pts/") && t.symlink_metadata().is_err() => {
            std::fs::remove_file(link)
                .with_context(|| format!("removing the stale link {}", link.display()))
        }
        Some(t) if t.starts_with("/dev/pts/") => anyhow::bail!(
            "{} links to {}, a pty that exists (another emulator?); not replacing it",
            link.display(),
            t.display()
        ),
        _ => anyhow::bail!(
            "{} exists and is not a stale pty link; not replacing it (remove it or pick \
             another path)",
            link.display()
        ),
    }
}

/// Emulates `emu` on a fresh pty linked at `link` until `limits`; baud is modelled from the
/// client's termios speed (bytes at another speed are garbled, as on a real line).
pub fn serve_pty(link: &Path, mut emu: Emulator, limits: RunLimits) -> Result<EmulatorReport> {
    let mut pty = Pty::open(link)?;
    run_realtime(&mut emu, &mut pty.wire, &limits)?;
    Ok(emu.report().clone())
}

/// Runs an emulator on an already opened [`Pty`].
pub fn serve_on(pty: &mut Pty, mut emu: Emulator, limits: RunLimits) -> Result<EmulatorReport> {
    run_realtime(&mut emu, &mut pty.wire, &limits)?;
    Ok(emu.report().clone())
}
