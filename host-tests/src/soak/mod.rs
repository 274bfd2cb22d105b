//! Soak test: tagged scans → emulated LMS200 with ~1 % damage (bit flips, dropped and
//! duplicated bytes, truncation, garbage, device resets, silences) → the firmware driver →
//! pfe-core (paper and default) → output frames → frame decoder, then an account proving that
//! no intact scan is missing or duplicated and no damaged one was accepted.
//!
//! ```text
//! cargo run --release -p host-tests --example soak -- [--scans N] [--seed S] [--damage P]
//!     [--transport inproc|pty|qemu]
//! ```
//! `inproc` (default) runs the in-process virtual-time link; `pty` runs the emulator in real
//! time on a pseudo-terminal and the driver over the tty (500 000 baud; keep N small); `qemu`
//! runs the real firmware (`pfe-qemu`) under `qemu-system-arm -M mps2-an386` against the
//! emulator on a pseudo-terminal (see [`qemu`]).
//! Every scan is unique: [`TaggedSource`] encodes its sequence number in the first two ranges,
//! and each delivered scan is compared word for word (and by checksum) with what was sent.
//! Exits non-zero when the account does not balance; a panic anywhere aborts it.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use firmware::app::{App, ConfigChoice, ScanDataExt};
use lms2xx::codec::types::Baud;
use lms2xx::driver::{Clock, Config, Driver, ScanData, SetBaud};
use pfe_frame::{self as output, Feed, FrameDecoder};
pub mod qemu;

use lms200_emulator::{
    Emulator, EmulatorConfig, Faults, Link, RunLimits, SentScan, SourceKind, TaggedSource,
};

/// FNV-1a over the value words: the per-scan checksum kept for what was sent and received.
fn checksum(words: &[u16]) -> u64 {
    words.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, w| {
        let h = (h ^ u64::from(w & 0xFF)).wrapping_mul(0x100_0000_01b3);
        (h ^ u64::from(w >> 8)).wrapping_mul(0x100_0000_01b3)
    })
}

/// Command-line settings.
pub struct Args {
    pub scans: usize,
    pub seed: u64,
    pub damage: f64,
    pub pty: bool,
    pub qemu: bool,
}

pub fn args() -> Result<Args> {
    let mut a = Args {
        scans: 100_000,
        seed: 1,
        damage: 0.01,
        pty: false,
        qemu: false,
    };
    let v: Vec<String> = std::env::args().skip(1).collect();
    let mut it = v.iter();
    while let Some(k) = it.next() {
        let mut val = || it.next().context("missing value");
        match k.as_str() {
            "--scans" => a.scans = val()?.parse()?,
            "--seed" => a.seed = val()?.parse()?,
            "--damage" => a.damage = val()?.parse()?,
            "--transport" => match val()?.as_str() {
                "inproc" => {}
                "pty" => a.pty = true,
                "qemu" => a.qemu = true,
                other => bail!("unknown transport {other} (inproc, pty, qemu)"),
            },
            other => bail!("unknown argument {other}"),
        }
    }
    Ok(a)
}

/// The damage mix: `p` per telegram in total for the damaging faults, plus garbage bytes
/// between telegrams with probability `p`.
pub fn faults(p: f64) -> Faults {
    Faults {
        bit_flip: 0.4 * p,
        drop_byte: 0.25 * p,
        duplicate_byte: 0.15 * p,
        truncate: 0.2 * p,
        garbage: p,
        ..Default::default()
    }
}

/// What came out of the driver for one scan.
struct Delivered {
    tag: u32,
    checksum: u64,
    words: Vec<u16>,
}

/// The pipeline after the driver: both configurations through the firmware's `App`, each
/// frame decoded again and checked.
struct Pipeline {
    paper: Box<App<401, 64>>,
    default: Box<App<401, 64>>,
    frames: Box<FrameDecoder<8192>>,
    buf: Vec<u8>,
    features: [u64; 2],
    frames_ok: u64,
}

impl Pipeline {
    fn new() -> Self {
        Self {
            paper: Box::new(App::new(ConfigChoice::Paper)),
            default: Box::new(App::new(ConfigChoice::Default)),
            frames: Box::new(FrameDecoder::new()),
            buf: Vec::with_capacity(8192),
            features: [0; 2],
            frames_ok: 0,
        }
    }

    fn run(&mut self, s: &ScanData, counters: output::Counters) -> Result<()> {
        let raw = s.raw();
        for (k, app) in [&mut self.paper, &mut self.default].into_iter().enumerate() {
            self.buf.clear();
            let header = app
                .process(&raw, counters, &mut self.buf)
                .map_err(|e| anyhow::anyhow!("encoding a frame: {e:?}"))?;
            for f in app.extractor().features() {
                if !f.is_well_formed() || f.last() >= s.len() {
                    bail!("ill-formed feature {f:?}");
                }
            }
            self.features[k] += u64::from(header.n_features);
            match self.frames.feed(&self.buf) {
                Feed::Frame {
                    frame,
                    remaining: [],
                } => {
                    if frame.scan() != Some(&header) {
                        bail!("frame header {:?} ≠ sent {header:?}", frame.header);
                    }
                    self.frames_ok += 1;
                }
                other => bail!("own frame did not decode: {other:?}"),
            }
        }
        Ok(())
    }
}

/// The account of one run.
#[derive(Default)]
struct Account {
    sent: usize,
    sent_damaged: usize,
    delivered: usize,
    duplicates: usize,
    damaged_accepted: usize,
    flagged_exact: usize,
    mismatched: usize,
    missing_intact: Vec<u32>,
    in_flight: usize,
    driver_errors: BTreeMap<String, u32>,
    resets: u32,
}

fn account(sent: &[SentScan], delivered: &[Delivered], errors: BTreeMap<String, u32>) -> Account {
    let mut a = Account {
        sent: sent.len(),
        sent_damaged: sent.iter().filter(|s| s.damaged).count(),
        delivered: delivered.len(),
        driver_errors: errors,
        ..Default::default()
    };
    let mut times = vec![0u32; sent.len()];
    for d in delivered {
        match sent.get(d.tag as usize) {
            Some(s) => {
                times[d.tag as usize] += 1;
                let exact = checksum(&s.words) == d.checksum && s.words == d.words;
                if !exact {
                    a.mismatched += 1;
                }
                if s.damaged {
                    // Accepting damaged bytes is a failure; a telegram the emulator flagged
                    // whose own bytes arrived intact (a duplicated byte after its CRC) is not.
                    if exact {
                        a.flagged_exact += 1;
                    } else {
                        a.damaged_accepted += 1;
                    }
                }
            }
            None => a.mismatched += 1,
        }
    }
    a.duplicates = times.iter().map(|&t| t.saturating_sub(1) as usize).sum();
    let last = delivered.iter().map(|d| d.tag).max().unwrap_or(0);
    for s in sent {
        if s.seq > last {
            a.in_flight += 1;
        } else if !s.damaged && times[s.seq as usize] == 0 {
            a.missing_intact.push(s.seq);
        }
    }
    a
}

fn report(name: &str, a: &Account, p: &Pipeline, counters: &str, elapsed: Duration) -> bool {
    println!("\nsoak ({name}): {:.1} s", elapsed.as_secs_f64());
    println!("  telegrams (B0) sent by the emulator   {:>9}", a.sent);
    println!(
        "    damaged on the way                  {:>9}",
        a.sent_damaged
    );
    println!(
        "    intact                              {:>9}",
        a.sent - a.sent_damaged
    );
    println!("  scans delivered by the driver         {:>9}", a.delivered);
    println!(
        "    bit-exact and checksum-equal        {:>9}",
        a.delivered - a.mismatched
    );
    println!(
        "    damaged telegrams accepted          {:>9}",
        a.damaged_accepted
    );
    println!(
        "    flagged damaged, own bytes intact   {:>9}  (fault after its CRC: a duplicated last byte)",
        a.flagged_exact
    );
    println!(
        "    duplicates                          {:>9}",
        a.duplicates
    );
    println!(
        "  intact scans missing                  {:>9}",
        a.missing_intact.len()
    );
    println!("  sent after the last delivered (tail)  {:>9}", a.in_flight);
    println!(
        "  device resets / driver errors         {:>9} / {:?}",
        a.resets, a.driver_errors
    );
    println!("  driver counters                       {counters}");
    println!(
        "  pfe-core features paper / default     {} / {}  (frames encoded and decoded: {})",
        p.features[0], p.features[1], p.frames_ok
    );
    let ok = a.mismatched == 0
        && a.damaged_accepted == 0
        && a.duplicates == 0
        && a.missing_intact.is_empty()
        && a.delivered > 0
        && p.frames_ok == 2 * a.delivered as u64;
    if !a.missing_intact.is_empty() {
        let show: Vec<_> = a.missing_intact.iter().take(20).collect();
        println!("  MISSING intact scans (first 20): {show:?}");
    }
    println!(
        "  account: {}",
        if ok {
            "BALANCED — every intact scan delivered exactly once, no damaged scan accepted, zero panics"
        } else {
            "NOT BALANCED"
        }
    );
    ok
}

fn tag_and_copy(s: &ScanData) -> Result<Delivered> {
    let tag = TaggedSource::tag_of(s.codes()).context("delivered scan carries no tag")?;
    Ok(Delivered {
        tag,
        checksum: checksum(s.words()),
        words: s.words().to_vec(),
    })
}

fn counters_of(c: &lms2xx::driver::Counters) -> output::Counters {
    output::Counters {
        telegrams_ok: c.telegrams_ok,
        crc_dropped: c.crc_errors,
        bytes_skipped: c.bytes_skipped,
        reinits: c.reinits,
    }
}

/// Takes the driver's next scan through `pipe` into `delivered` (`Ok(true)`), or counts its
/// error in `errors` (`Ok(false)`).
fn next_scan<U, D, C>(
    lms: &mut Driver<U, D, C>,
    pipe: &mut Pipeline,
    delivered: &mut Vec<Delivered>,
    errors: &mut BTreeMap<String, u32>,
) -> Result<bool>
where
    U: embedded_io::Read + embedded_io::Write + embedded_io::ReadReady + SetBaud,
    U::Error: std::fmt::Debug,
    D: embedded_hal::delay::DelayNs,
    C: Clock,
{
    match lms.next_scan() {
        Ok(s) => {
            let d = tag_and_copy(s)?;
            let c = counters_of(&lms.counters());
            pipe.run(lms.last_scan(), c)?;
            delivered.push(d);
            Ok(true)
        }
        Err(e) => {
            *errors.entry(format!("{e:?}")).or_default() += 1;
            Ok(false)
        }
    }
}

/// The in-process run; `Ok(true)` when the account balances.
pub fn inproc(a: &Args) -> Result<bool> {
    let cfg = EmulatorConfig {
        source: SourceKind::Tagged,
        faults: faults(a.damage),
        seed: a.seed,
        ..Default::default()
    };
    let link = Link::new(Emulator::from_config(cfg), Some(9600));
    let mut lms = Driver::new(
        link.host_port(),
        link.delay(),
        link.clock(),
        Config::default(),
    );
    let mut pipe = Pipeline::new();
    let mut delivered = Vec::with_capacity(a.scans);
    let mut errors: BTreeMap<String, u32> = BTreeMap::new();
    // A device reset every ~5/p scans (500 at 1 %) and a silence every ~20/p scans.
    let reset_every = ((5.0 / a.damage.max(1e-9)) as usize).max(50);
    let silence_every = ((20.0 / a.damage.max(1e-9)) as usize).max(200);
    let t0 = Instant::now();
    let mut next_print = 0;
    while delivered.len() < a.scans {
        let n = delivered.len();
        if n > 0 && n % reset_every == 0 {
            link.with_emulator(|e| {
                let sent = e.report().scans.len() as u32;
                if e.faults_mut().reset_after_scans.is_none() {
                    e.faults_mut().reset_after_scans = Some(sent + 1);
                }
            })?;
        }
        if n > 0 && n % silence_every == reset_every / 2 {
            link.with_emulator(|e| {
                let sent = e.report().scans.len() as u32;
                e.faults_mut().silence_ms = 1500;
                if e.faults_mut().silence_after_scans.is_none() {
                    e.faults_mut().silence_after_scans = Some(sent + 1);
                }
            })?;
        }
        if !next_scan(&mut lms, &mut pipe, &mut delivered, &mut errors)?
            && errors.values().sum::<u32>() as usize > 20 + a.scans / 100
        {
            bail!("the driver keeps failing: {errors:?}");
        }
        if delivered.len() >= next_print {
            eprint!("\r  {} / {} scans", delivered.len(), a.scans);
            next_print += 5000;
        }
    }
    eprintln!();
    let (sent, resets) = link.with_emulator(|e| (e.report().scans.clone(), e.report().resets))?;
    let mut acc = account(&sent, &delivered, errors);
    acc.resets = resets;
    Ok(report(
        "in-process link, virtual time",
        &acc,
        &pipe,
        &format!("{:?}", lms.counters()),
        t0.elapsed(),
    ))
}

mod tty {
    //! The driver's view of a serial port on the host: a tty with termios baud rates.
    use std::fs::File;
    use std::io::{ErrorKind, Read as _, Write as _};
    use std::os::fd::AsFd;
    use std::os::unix::fs::OpenOptionsExt;
    use std::path::Path;
    use std::time::{Duration, Instant};

    use lms2xx::driver::{Clock, SetBaud};
    use nix::poll::{poll, PollFd, PollFlags, PollTimeout};
    use nix::sys::termios::{self, BaudRate, SetArg};

    /// A tty opened non-blocking, raw.
    pub struct Tty(pub File);

    impl Tty {
        pub fn open(path: &Path) -> std::io::Result<Self> {
            let f = std::fs::OpenOptions::new()
                .read(true)
                .write(true)
                .custom_flags(nix::libc::O_NONBLOCK | nix::libc::O_NOCTTY)
                .open(path)?;
            let mut t = termios::tcgetattr(f.as_fd())?;
            termios::cfmakeraw(&mut t);
            termios::tcsetattr(f.as_fd(), SetArg::TCSANOW, &t)?;
            Ok(Self(f))
        }
    }

    impl embedded_io::ErrorType for Tty {
        type Error = std::io::Error;
    }

    impl embedded_io::ReadReady for Tty {
        fn read_ready(&mut self) -> Result<bool, Self::Error> {
            let mut fds = [PollFd::new(self.0.as_fd(), PollFlags::POLLIN)];
            Ok(poll(&mut fds, PollTimeout::ZERO)? > 0)
        }
    }

    impl embedded_io::Read for Tty {
        fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error> {
            loop {
                match self.0.read(buf) {
                    Err(e) if e.kind() == ErrorKind::WouldBlock => {
                        std::thread::sleep(Duration::from_micros(200))
                    }
                    r => return r,
                }
            }
        }
    }

    impl embedded_io::Write for Tty {
        fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
            loop {
                match self.0.write(buf) {
                    Err(e) if e.kind() == ErrorKind::WouldBlock => {
                        std::thread::sleep(Duration::from_micros(200))
                    }
                    r => return r,
                }
            }
        }
        fn flush(&mut self) -> Result<(), Self::Error> {
            Ok(())
        }
    }

    impl SetBaud for Tty {
        fn set_baud(&mut self, baud: u32) -> Result<(), Self::Error> {
            let rate = match baud {
                9600 => BaudRate::B9600,
                19200 => BaudRate::B19200,
                38400 => BaudRate::B38400,
                500_000 => BaudRate::B500000,
                _ => return Err(std::io::Error::other(format!("no termios rate {baud}"))),
            };
            let mut t = termios::tcgetattr(self.0.as_fd())?;
            termios::cfsetspeed(&mut t, rate)?;
            termios::tcsetattr(self.0.as_fd(), SetArg::TCSADRAIN, &t)?;
            Ok(())
        }
    }

    /// Wall-clock milliseconds.
    pub struct Wall(pub Instant);
    impl Clock for Wall {
        fn now_ms(&mut self) -> u32 {
            self.0.elapsed().as_millis() as u32
        }
    }

    /// `thread::sleep`.
    pub struct Sleep;
    impl embedded_hal::delay::DelayNs for Sleep {
        fn delay_ns(&mut self, ns: u32) {
            std::thread::sleep(Duration::from_nanos(u64::from(ns)));
        }
    }
}

/// The pseudo-terminal run; `Ok(true)` when the account balances.
pub fn pty(a: &Args) -> Result<bool> {
    use lms200_emulator::serve::{serve_on, Pty};
    let cfg = EmulatorConfig {
        source: SourceKind::Tagged,
        faults: faults(a.damage),
        seed: a.seed,
        ..Default::default()
    };
    let link = std::env::temp_dir().join(format!("pfe-soak-{}", std::process::id()));
    let mut p = Pty::open(&link)?;
    let slave: PathBuf = p.slave_path().to_path_buf();
    let stop = Arc::new(AtomicBool::new(false));
    let limits = RunLimits {
        max_time: Some(Duration::from_secs(600)),
        stop: Some(stop.clone()),
        ..Default::default()
    };
    let emu = Emulator::from_config(cfg);
    let server = std::thread::spawn(move || serve_on(&mut p, emu, limits));
    let t0 = Instant::now();
    let port = tty::Tty::open(&slave).with_context(|| format!("opening {}", slave.display()))?;
    let mut lms = Driver::new(
        port,
        tty::Sleep,
        tty::Wall(Instant::now()),
        Config::default().with_baud(Baud::B500000),
    );
    let mut pipe = Pipeline::new();
    let mut delivered = Vec::new();
    let mut errors: BTreeMap<String, u32> = BTreeMap::new();
    while delivered.len() < a.scans {
        if !next_scan(&mut lms, &mut pipe, &mut delivered, &mut errors)?
            && errors.values().sum::<u32>() > 20
        {
            stop.store(true, Ordering::SeqCst);
            bail!("the driver keeps failing on the pty: {errors:?}");
        }
    }
    let counters = format!("{:?}", lms.counters());
    drop(lms);
    stop.store(true, Ordering::SeqCst);
    let rep = server
        .join()
        .map_err(|_| anyhow::anyhow!("the emulator thread panicked"))??;
    let mut acc = account(&rep.scans, &delivered, errors);
    acc.resets = rep.resets;
    let _ = std::fs::remove_file(&link);
    Ok(report(
        "pseudo-terminal, real time, 500000 baud",
        &acc,
        &pipe,
        &counters,
        t0.elapsed(),
    ))
}
