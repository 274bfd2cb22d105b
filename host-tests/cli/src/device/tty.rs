//! std adapters that let the firmware's LMS200 driver run on a host: [`TtyPort`] (termios on
//! a tty, raw and non-blocking), [`StdDelay`], [`StdClock`].

use std::fs::{File, OpenOptions};
use std::io::{ErrorKind, Read, Write};
use std::os::fd::AsFd;
use std::os::unix::fs::OpenOptionsExt;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result};
use lms2xx::driver::{Clock, SetBaud};
use nix::sys::termios::{self, BaudRate, SetArg};

/// A tty opened raw and non-blocking, usable as an `embedded-io` UART by the firmware driver.
/// Every byte handed to the driver is also appended to an optional capture sink, until the
/// capture is switched off ([`TtyPort::capture_switch`]).
pub struct TtyPort {
    file: File,
    buf: Vec<u8>,
    capture: Option<Box<dyn Write + Send>>,
    capturing: Arc<AtomicBool>,
    captured: u64,
    stop: Option<Arc<AtomicBool>>,
}

/// The termios rate for `bps`.
pub fn baud_rate(bps: u32) -> Option<BaudRate> {
    Some(match bps {
        9600 => BaudRate::B9600,
        19200 => BaudRate::B19200,
        38400 => BaudRate::B38400,
        57600 => BaudRate::B57600,
        115_200 => BaudRate::B115200,
        230_400 => BaudRate::B230400,
        460_800 => BaudRate::B460800,
        500_000 => BaudRate::B500000,
        921_600 => BaudRate::B921600,
        _ => return None,
    })
}

impl TtyPort {
    /// Opens `path` raw, 8N1, at 9600 baud.
    pub fn open(path: &Path) -> Result<Self> {
        let file = OpenOptions::new()
            .read(true)
            .write(true)
            .custom_flags(nix::libc::O_NOCTTY | nix::libc::O_NONBLOCK)
            .open(path)
            .with_context(|| format!("opening {}", path.display()))?;
        let mut t = termios::tcgetattr(file.as_fd())
            .with_context(|| format!("{} is not a tty", path.display()))?;
        termios::cfmakeraw(&mut t);
        termios::cfsetspeed(&mut t, BaudRate::B9600)?;
        termios::tcsetattr(file.as_fd(), SetArg::TCSANOW, &t)?;
        Ok(Self {
            file,
            buf: Vec::new(),
            capture: None,
            capturing: Arc::new(AtomicBool::new(true)),
            captured: 0,
            stop: None,
        })
    }

    /// Copies every byte the driver reads into `sink`. While capturing, a read hands out one
    /// byte: the driver then holds no byte it has not decoded, so the capture ends exactly
    /// where the driver's last telegram ended when the capture is switched off.
    pub fn with_capture(mut self, sink: Box<dyn Write + Send>) -> Self {
        self.capture = Some(sink);
        self
    }

    /// Clearing this flag ends the capture: later bytes are not written to it.
    pub fn capture_switch(&self) -> Arc<AtomicBool> {
        self.capturing.clone()
    }

    /// Fails every read once `stop` is set (so a blocked driver returns, e.g. on Ctrl-C).
    pub fn with_stop(mut self, stop: Arc<AtomicBool>) -> Self {
        self.stop = Some(stop);
        self
    }

    /// Bytes captured so far.
    pub fn captured(&self) -> u64 {
        self.captured
    }

    fn fill(&mut self) -> std::io::Result<()> {
        if self
            .stop
            .as_ref()
            .is_some_and(|s| s.load(Ordering::Relaxed))
        {
            return Err(std::io::Error::other("interrupted"));
        }
        let mut tmp = [0u8; 1024];
        match self.file.read(&mut tmp) {
            Ok(n) => {
                self.buf.extend_from_slice(tmp.get(..n).unwrap_or(&[]));
                Ok(())
            }
            Err(e) if e.kind() == ErrorKind::WouldBlock || e.kind() == ErrorKind::Interrupted => {
                Ok(())
            }
            Err(e) => Err(e),
        }
    }

    /// Flushes the capture sink.
    pub fn finish(&mut self) -> std::io::Result<()> {
        match self.capture.as_mut() {
            Some(c) => c.flush(),
            None => Ok(()),
        }
    }
}

impl embedded_io::ErrorType for TtyPort {
    type Error = std::io::Error;
}

impl embedded_io::ReadReady for TtyPort {
    fn read_ready(&mut self) -> std::io::Result<bool> {
        if self.buf.is_empty() {
            self.fill()?;
        }
        Ok(!self.buf.is_empty())
    }
}

impl embedded_io::Read for TtyPort {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        if self.buf.is_empty() {
            self.fill()?;
        }
        let capturing = self.capture.is_some() && self.capturing.load(Ordering::Relaxed);
        let most = if capturing { 1 } else { out.len() };
        let n = out.len().min(self.buf.len()).min(most);
        for (d, s) in out.iter_mut().zip(self.buf.drain(..n)) {
            *d = s;
        }
        if let (true, Some(c)) = (capturing, self.capture.as_mut()) {
            c.write_all(out.get(..n).unwrap_or(&[]))?;
            self.captured += n as u64;
        }
        Ok(n)
    }
}

impl embedded_io::Write for TtyPort {
    fn write(&mut self, data: &[u8]) -> std::io::Result<usize> {
        loop {
            match self.file.write(data) {
                Err(e)
                    if e.kind() == ErrorKind::WouldBlock || e.kind() == ErrorKind::Interrupted =>
                {
                    std::thread::sleep(std::time::Duration::from_micros(200));
                }
                other => return other,
            }
        }
    }
    fn flush(&mut self) -> std::io::Result<()> {
        termios::tcdrain(self.file.as_fd()).map_err(std::io::Error::from)
    }
}

impl SetBaud for TtyPort {
    fn set_baud(&mut self, bps: u32) -> std::io::Result<()> {
        let b = baud_rate(bps)
            .ok_or_else(|| std::io::Error::new(ErrorKind::InvalidInput, format!("baud {bps}")))?;
        let mut t = termios::tcgetattr(self.file.as_fd())?;
        termios::cfsetspeed(&mut t, b)?;
        termios::tcsetattr(self.file.as_fd(), SetArg::TCSADRAIN, &t)?;
        self.buf.clear();
        Ok(())
    }
}

/// `embedded_hal::delay::DelayNs` by sleeping.
#[derive(Clone, Copy, Debug, Default)]
pub struct StdDelay;

impl embedded_hal::delay::DelayNs for StdDelay {
    fn delay_ns(&mut self, ns: u32) {
        std::thread::sleep(std::time::Duration::from_nanos(u64::from(ns)));
    }
}

/// Milliseconds since creation.
#[derive(Clone, Copy, Debug)]
pub struct StdClock(Instant);

impl Default for StdClock {
    fn default() -> Self {
        Self(Instant::now())
    }
}

impl Clock for StdClock {
    fn now_ms(&mut self) -> u32 {
        self.0.elapsed().as_millis() as u32
    }
}
