//! The QEMU firmware between two serial lines: its LMS200 UART (UART0) on an existing tty or
//! pty, its feature UART (UART1) on another or on a new pty behind a link path. What
//! `cargo xtask run-qemu` runs, and the end-to-end test with it.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Stdio};
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};

use crate::qemu::qemu_command;

/// A running QEMU firmware with its serial lines in place.
pub struct RunQemu {
    child: Child,
    /// The device QEMU's UART1 is on.
    pub output_device: PathBuf,
    /// The link this run created (removed on drop).
    link: Option<PathBuf>,
}

/// True when `path` opens as a terminal (a tty or pty).
fn is_tty(path: &Path) -> bool {
    use std::io::IsTerminal;
    std::fs::File::open(path).is_ok_and(|f| f.is_terminal())
}

/// The tty device behind `path` (a symlink such as `pfe emulate --pty`'s is followed).
fn tty_device(path: &Path, what: &str) -> Result<PathBuf> {
    let dev = path
        .canonicalize()
        .with_context(|| format!("{what} {}: no such device", path.display()))?;
    if !is_tty(&dev) {
        bail!("{what} {} is not a tty or pty", path.display());
    }
    Ok(dev)
}

impl RunQemu {
    /// Starts `elf` (pfe-qemu) with its scanner UART on the tty `scanner` and its output on
    /// `output`: an existing tty, or a new pty linked at `output` (a stale link of a finished
    /// run is replaced; anything else at the path is refused). `scans` 0 = run forever;
    /// `config` "paper" or "default". QEMU's stderr is echoed with a `qemu:` prefix.
    pub fn start(
        elf: &Path,
        scanner: &Path,
        output: &Path,
        config: &str,
        scans: u32,
    ) -> Result<Self> {
        Self::start_with(elf, scanner, output, scans, &[config])
    }

    /// [`RunQemu::start`] with pfe-qemu's semihosting arguments after `scans` (`args`: config,
    /// baud, slow_ms, slow_every, field, resolution; see pfe-qemu).
    pub fn start_with(
        elf: &Path,
        scanner: &Path,
        output: &Path,
        scans: u32,
        args: &[&str],
    ) -> Result<Self> {
        let scanner_dev = tty_device(scanner, "--scanner")?;
        let existing = match std::fs::symlink_metadata(output) {
            Err(_) => None,
            Ok(m) if m.file_type().is_symlink() && !output.exists() => {
                // A link to a pty that is gone: ours from an earlier run.
                std::fs::remove_file(output)
                    .with_context(|| format!("removing stale link {}", output.display()))?;
                None
            }
            Ok(_) => Some(tty_device(output, "--output")?),
        };
        let serial1 = existing
            .as_ref()
            .map_or_else(|| "pty".to_string(), |d| d.display().to_string());
        let n = scans.to_string();
        let all: Vec<&str> = std::iter::once(n.as_str())
            .chain(args.iter().copied())
            .collect();
        let mut cmd = qemu_command(
            elf,
            &scanner_dev.display().to_string(),
            &serial1,
            &all,
            false,
        );
        cmd.stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        let mut child = cmd.spawn().context("cannot run qemu-system-arm")?;
        let (tx, rx) = std::sync::mpsc::channel();
        let stdout: Box<dyn std::io::Read + Send> =
            Box::new(child.stdout.take().context("no stdout")?);
        let stderr: Box<dyn std::io::Read + Send> =
            Box::new(child.stderr.take().context("no stderr")?);
        for pipe in [stdout, stderr] {
            let tx = tx.clone();
            std::thread::spawn(move || {
                for line in BufReader::new(pipe).lines().map_while(Result::ok) {
                    // QEMU's "char device redirected to /dev/pts/N (label serial1)"
                    if let Some(rest) = line.split("redirected to ").nth(1) {
                        let dev = rest.split_whitespace().next().unwrap_or("");
                        let _ = tx.send(PathBuf::from(dev));
                    } else if !line.contains("has no peer") {
                        eprintln!("qemu: {line}");
                    }
                }
            });
        }
        let (output_device, link) = match existing {
            Some(d) => (d, None),
            None => {
                let dev = match rx.recv_timeout(Duration::from_secs(10)) {
                    Ok(d) => d,
                    Err(_) => {
                        let _ = child.kill();
                        bail!("QEMU did not report its output pty");
                    }
                };
                std::os::unix::fs::symlink(&dev, output).with_context(|| {
                    format!("linking {} to {}", output.display(), dev.display())
                })?;
                (dev, Some(output.to_path_buf()))
            }
        };
        Ok(Self {
            child,
            output_device,
            link,
        })
    }

    /// Waits for the firmware to exit, at most `timeout`; its exit code (`None`: still
    /// running, or killed by a signal).
    pub fn wait(&mut self, timeout: Duration) -> Result<Option<i32>> {
        let t0 = Instant::now();
        loop {
            if let Some(s) = self.child.try_wait()? {
                return Ok(s.code());
            }
            if t0.elapsed() >= timeout {
                return Ok(None);
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// Stops QEMU.
    pub fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for RunQemu {
    fn drop(&mut self) {
        self.kill();
        if let Some(l) = self.link.take() {
            let _ = std::fs::remove_file(l);
        }
    }
}
