//! Running the pfe firmware under QEMU (mps2-an386) from the host, and reading its output:
//! shared by xtask (`bench-mcu`, `size`), host-tests' `examples/demo_host` (`cargo xtask demo`),
//! the soak and the end-to-end tests (whose sessions against the emulator are
//! `host_tests::qemu`).

use std::io::Read;
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use lms2xx::codec::frame::{encode_telegram, DEVICE_ADDRESS};
use pfe_frame::{DecodeError, Feed, Frame, FrameDecoder};

/// The Cortex-M target.
pub const TARGET: &str = "thumbv7em-none-eabihf";

/// The workspace root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .ancestors()
        .nth(2)
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."))
}

/// True when `program` runs.
pub fn have(program: &str) -> bool {
    Command::new(program)
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .map(|s| s.success())
        .unwrap_or(false)
}

/// True when the thumbv7em target's standard library is installed.
pub fn have_target() -> bool {
    let Ok(out) = Command::new("rustc").args(["--print", "sysroot"]).output() else {
        return false;
    };
    let sysroot = String::from_utf8_lossy(&out.stdout).trim().to_string();
    Path::new(&sysroot)
        .join("lib/rustlib")
        .join(TARGET)
        .join("lib")
        .is_dir()
}

/// Builds a firmware-qemu binary in release for the target; returns the ELF path.
/// `target_dir` should differ from the calling cargo's (its lock is held during `cargo test`).
pub fn build_firmware<V: AsRef<std::ffi::OsStr>>(
    bin: &str,
    features: &[&str],
    env: &[(&str, V)],
    target_dir: &Path,
) -> Result<PathBuf> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut cmd = Command::new(cargo);
    cmd.current_dir(root())
        .args([
            "build",
            "--release",
            "-p",
            "firmware-qemu",
            "--bin",
            bin,
            "--target",
            TARGET,
        ])
        .env("CARGO_TARGET_DIR", target_dir)
        .env_remove("RUSTFLAGS");
    if !features.is_empty() {
        cmd.args(["--features", &features.join(",")]);
    }
    for (k, v) in env {
        cmd.env(k, v);
    }
    let status = cmd.status().context("cannot run cargo")?;
    if !status.success() {
        bail!("building {bin} failed: {status}");
    }
    Ok(target_dir.join(TARGET).join("release").join(bin))
}

/// For a QEMU test named `test`: `bin` of firmware-qemu built as shipped (opt-level "s") in
/// `$CARGO_TARGET_DIR/<dir>` (not the outer cargo's target dir: its lock is held while tests
/// run); `None` after a [`skip`](crate::skip::skip) when `PFE_SKIP_QEMU` is set
/// (`cargo xtask test --quick`), or when qemu-system-arm or the target is missing (a failure
/// under `CI=true`). Panics when the firmware does not build: the test fails.
pub fn test_firmware(test: &str, bin: &str, dir: &str) -> Option<PathBuf> {
    test_firmware_with(test, bin, &[], dir)
}

/// [`test_firmware`] with firmware-qemu's cargo `features` (`pfe-qemu-async` needs `async`).
/// `PFE_E2E_FIRMWARE` names a pfe-qemu ELF built elsewhere to run instead of `pfe-qemu` (to
/// check a test against another build, such as an older firmware).
#[allow(
    clippy::panic,
    reason = "a test helper: its panic is the calling test's failure"
)]
pub fn test_firmware_with(test: &str, bin: &str, features: &[&str], dir: &str) -> Option<PathBuf> {
    use crate::skip::{skip, Need};
    if let (Some(elf), "pfe-qemu") = (std::env::var_os("PFE_E2E_FIRMWARE"), bin) {
        return Some(PathBuf::from(elf));
    }
    if std::env::var_os("PFE_SKIP_QEMU").is_some() {
        skip(
            test,
            "PFE_SKIP_QEMU is set (cargo xtask test --quick)",
            Need::Optional,
        );
        return None;
    }
    if !have("qemu-system-arm") {
        skip(
            test,
            "qemu-system-arm is not installed (apt-get install qemu-system-arm)",
            Need::InCi,
        );
        return None;
    }
    if !have_target() {
        skip(
            test,
            "the thumbv7em-none-eabihf target is missing (rustup target add thumbv7em-none-eabihf)",
            Need::InCi,
        );
        return None;
    }
    let dir = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join("target"))
        .join(dir);
    match build_firmware(
        bin,
        features,
        &[("CARGO_PROFILE_RELEASE_OPT_LEVEL", FIRMWARE_OPT_LEVEL)],
        &dir,
    ) {
        Ok(elf) => Some(elf),
        Err(e) => panic!("{test}: {e:#}"),
    }
}

/// A QEMU command line for `elf` with UART0 and UART1 connected to `serial0`/`serial1` (QEMU
/// `-serial` specs), semihosting arguments `args` and, optionally, `-icount shift=10`.
pub fn qemu_command(
    elf: &Path,
    serial0: &str,
    serial1: &str,
    args: &[&str],
    icount: bool,
) -> Command {
    let mut cmd = Command::new("qemu-system-arm");
    let mut semi = String::from("enable=on,target=native,arg=pfe");
    for a in args {
        semi.push_str(",arg=");
        semi.push_str(a);
    }
    cmd.args([
        "-machine",
        "mps2-an386",
        "-cpu",
        "cortex-m4",
        "-display",
        "none",
    ])
    .args(["-monitor", "none", "-nodefaults"])
    .args(["-semihosting-config", &semi])
    .args(["-serial", serial0, "-serial", serial1])
    .arg("-kernel")
    .arg(elf);
    if icount {
        cmd.args(["-icount", "shift=10"]);
    }
    cmd
}

/// What a QEMU run produced.
pub struct Run {
    /// Exit code (semihosting), `None` if killed.
    pub code: Option<i32>,
    /// Bytes the firmware wrote to UART1.
    pub output: Vec<u8>,
    /// Semihosting stdout (defmt frames).
    pub stdout: Vec<u8>,
    /// QEMU's stderr.
    pub stderr: String,
}

/// A listener on a free local port (the firmware's UART1 connects to it as a client).
pub fn listener() -> Result<(TcpListener, u16)> {
    let l = TcpListener::bind("127.0.0.1:0").context("bind")?;
    let port = l.local_addr()?.port();
    Ok((l, port))
}

/// Runs QEMU (`cmd` from [`qemu_command`] with UART1 = `tcp:127.0.0.1:PORT` of `out`) to its
/// end, collecting UART1 from `out`; kills it after `timeout`.
pub fn run_collect(mut cmd: Command, out: TcpListener, timeout: Duration) -> Result<Run> {
    let mut child: Child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .context("cannot start qemu-system-arm")?;
    let stdout = child.stdout.take();
    let stderr = child.stderr.take();
    let so = std::thread::spawn(move || {
        let mut v = Vec::new();
        if let Some(mut s) = stdout {
            let _ = s.read_to_end(&mut v);
        }
        v
    });
    let se = std::thread::spawn(move || {
        let mut v = Vec::new();
        if let Some(mut s) = stderr {
            let _ = s.read_to_end(&mut v);
        }
        String::from_utf8_lossy(&v).into_owned()
    });
    out.set_nonblocking(true)?;
    let start = Instant::now();
    let mut output = Vec::new();
    let mut conn = None;
    let mut code = None;
    loop {
        if conn.is_none() {
            if let Ok((s, _)) = out.accept() {
                s.set_nonblocking(false)?;
                s.set_read_timeout(Some(Duration::from_millis(20)))?;
                conn = Some(s);
            }
        }
        if let Some(s) = conn.as_mut() {
            let mut buf = [0u8; 4096];
            match s.read(&mut buf) {
                Ok(0) => {}
                Ok(n) => output.extend_from_slice(buf.get(..n).unwrap_or(&[])),
                Err(_) => {}
            }
        } else {
            std::thread::sleep(Duration::from_millis(5));
        }
        if let Some(st) = child.try_wait()? {
            code = st.code();
            break;
        }
        if start.elapsed() > timeout {
            let _ = child.kill();
            let _ = child.wait();
            break;
        }
    }
    // Drain what is left in the socket.
    if let Some(mut s) = conn {
        let _ = s.set_read_timeout(Some(Duration::from_millis(200)));
        let mut rest = Vec::new();
        let _ = s.read_to_end(&mut rest);
        output.extend_from_slice(&rest);
    }
    Ok(Run {
        code,
        output,
        stdout: so.join().unwrap_or_default(),
        stderr: se.join().unwrap_or_default(),
    })
}

/// Decodes every frame in `bytes`; returns the frames and the rejected ones.
pub fn decode_frames(bytes: &[u8]) -> (Vec<Frame>, Vec<DecodeError>) {
    let mut dec = Box::new(FrameDecoder::<16384>::new());
    let (mut frames, mut errors) = (Vec::new(), Vec::new());
    let mut rest = bytes;
    loop {
        match dec.feed(rest) {
            Feed::Consumed => break,
            Feed::Frame { frame, remaining } => {
                frames.push(frame);
                rest = remaining;
            }
            Feed::Error { error, remaining } => {
                errors.push(error);
                rest = remaining;
            }
        }
    }
    (frames, errors)
}

/// A B0 telegram (device → host) with `values` (mm unit bits set when `mm`), status 0x10.
pub fn b0_telegram(values: &[u16], mm: bool) -> Result<Vec<u8>> {
    let n = u16::try_from(values.len()).context("too many values")?;
    let count = n | if mm { 1 << 14 } else { 0 };
    let mut payload = vec![0xB0];
    payload.extend_from_slice(&count.to_le_bytes());
    for v in values {
        payload.extend_from_slice(&v.to_le_bytes());
    }
    payload.push(0x10);
    let mut out = vec![0u8; payload.len() + 6];
    let n = encode_telegram(DEVICE_ADDRESS, &payload, &mut out)
        .map_err(|e| anyhow::anyhow!("encode: {e:?}"))?;
    out.truncate(n);
    Ok(out)
}

/// The build profile the firmware ships with and the flash budget is measured on
/// (`cargo xtask size`, `bench-mcu`): `opt-level = "s"` on top of the workspace's release
/// profile (LTO, one codegen unit; pfe-core at 3, see the workspace Cargo.toml).
pub const FIRMWARE_OPT_LEVEL: &str = "s";

/// The receive path's account pfe-qemu writes to semihosting stderr at its end
/// (`rx: ring_full=… overruns=… line_errors=… peak=… capacity=… scan_errors=…`), by key.
pub fn rx_stats(stderr: &str) -> Option<std::collections::BTreeMap<String, u32>> {
    let line = stderr.lines().rev().find_map(|l| l.strip_prefix("rx:"))?;
    line.split_whitespace()
        .map(|kv| {
            let (k, v) = kv.split_once('=')?;
            Some((k.to_string(), v.parse().ok()?))
        })
        .collect()
}

/// What `pfe extract --format lms200` (`--config paper` for [`ConfigChoice::Paper`]) gives on
/// a capture of one B0 telegram of `words` in mm: the features the firmware should have sent.
/// The CLI's way, not the firmware's: the telegram decoded by pfe-formats' LMS200 reader into
/// ranges in mm, the configuration of `pfe extract` for the format (`Format::sigma_r`,
/// `Format::sigma_sys`), the scan told its sweeps (`sweeps_of`) and grid (`range_quantum`), and
/// pfe-core on the host with the host's capacities.
///
/// [`ConfigChoice::Paper`]: firmware::app::ConfigChoice::Paper
pub fn host_features(
    words: &[u16],
    choice: firmware::app::ConfigChoice,
) -> Result<Vec<pfe_core::Feature>> {
    host_features_unit(words, true, choice)
}

/// [`host_features`] of a telegram in mm (`mm`) or cm.
pub fn host_features_unit(
    words: &[u16],
    mm: bool,
    choice: firmware::app::ConfigChoice,
) -> Result<Vec<pfe_core::Feature>> {
    use firmware::app::ConfigChoice;
    use pfe_core::{Config, Extractor, Scan};
    use pfe_formats::{lms200, range_quantum, sweeps_of, Format, MAX_BEAMS, MAX_FEATURES};
    let bytes = b0_telegram(words, mm)?;
    let mut reader = lms200::Reader::new(Box::new(std::io::Cursor::new(bytes)));
    let telegram = reader.next().context("no telegram decoded")??;
    let record = telegram
        .record()
        .context("a value count no LMS200 variant sends")?;
    let format = Format::Lms200;
    let config = match choice {
        ConfigChoice::Paper => Config::paper(),
        ConfigChoice::Default => Config::default(),
    }
    .with_sigma_r(format.sigma_r())
    .with_sigma_sys(format.sigma_sys());
    let g = record.geometry;
    let scan = Scan::from_mm(g, &record.ranges_mm)
        .with_sweeps(sweeps_of(format, &g))
        .with_quantum(range_quantum(&record.ranges_mm, g.r_max));
    let mut ex = Box::new(Extractor::<MAX_BEAMS, MAX_FEATURES>::new());
    // As `pfe extract`: a refused scan has no features (its status says why).
    let _ = ex.extract(&scan, &config);
    Ok(ex.features().to_vec())
}

/// The firmware's `App` on the host over consecutive scans (the value words the emulator
/// sent, in order): the frames the firmware should have sent, decoded (features and pose).
pub fn host_frames(
    scans: &[&[u16]],
    choice: firmware::app::ConfigChoice,
) -> Result<Vec<pfe_frame::Frame>> {
    use firmware::app::{App, RawScan};
    use lms2xx::codec::types::Variant;
    let v = Variant::A180_R050;
    let mut g = pfe_core::ScanGeometry::lms200(f32::from(v.angle_deg), v.resolution_deg());
    g.r_max = f32::from(pfe_core::LMS_MAX_VALID_8M);
    let mut app = Box::new(App::<361, 48>::new(choice));
    let mut out = Vec::new();
    for words in scans {
        let codes: Vec<u16> = words.iter().map(|w| w & 0x1FFF).collect();
        let mut w = VecWriter(Vec::new());
        app.process(
            &RawScan::lms_8m(g, &codes, 1.0),
            pfe_frame::Counters::default(),
            &mut w,
        )
        .map_err(|e| anyhow::anyhow!("{e}"))?;
        let (frames, errors) = decode_frames(&w.0);
        if !errors.is_empty() {
            bail!("host frame did not decode: {errors:?}");
        }
        out.extend(frames);
    }
    Ok(out)
}

/// `embedded_io::Write` into a `Vec`.
pub struct VecWriter(pub Vec<u8>);

impl embedded_io::ErrorType for VecWriter {
    type Error = core::convert::Infallible;
}

impl embedded_io::Write for VecWriter {
    fn write(&mut self, buf: &[u8]) -> std::result::Result<usize, Self::Error> {
        self.0.extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::result::Result<(), Self::Error> {
        Ok(())
    }
}

/// Bit-level comparison of two features: `None` when identical, else the largest difference
/// in units in the last place over all f32 fields (and `u32::MAX` for a different kind/range).
pub fn ulps_apart(a: &pfe_core::Feature, b: &pfe_core::Feature) -> Option<u32> {
    use pfe_core::Feature;
    let fields = |f: &Feature| -> (u8, [u16; 3], Vec<f32>) {
        match f {
            Feature::Line(l) => (0, [l.first, l.last, l.points], l.values().to_vec()),
            Feature::Circle(c) => (1, [c.first, c.last, c.points], c.values().to_vec()),
            Feature::Object(o) => (2, [o.first, o.last, o.points], o.values().to_vec()),
            _ => (u8::MAX, [0; 3], Vec::new()),
        }
    };
    let (ka, ia, va) = fields(a);
    let (kb, ib, vb) = fields(b);
    if ka != kb || ia != ib {
        return Some(u32::MAX);
    }
    let key = |x: f32| -> i64 {
        let b = x.to_bits() as i32;
        i64::from(if b < 0 { i32::MIN - b } else { b })
    };
    let worst = va
        .iter()
        .zip(&vb)
        .map(|(x, y)| (key(*x) - key(*y)).unsigned_abs())
        .max()
        .unwrap_or(0);
    (worst != 0).then(|| u32::try_from(worst).unwrap_or(u32::MAX))
}
