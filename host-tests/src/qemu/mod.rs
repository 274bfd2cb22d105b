//! The QEMU runner of [`pfe_testkit::qemu`], and one session of the firmware under QEMU
//! against the emulated LMS200 serving simulated scenes (the end-to-end tests, the soak).

pub use pfe_testkit::qemu::*;

use std::path::Path;
use std::time::Duration;

use anyhow::Result;
use pfe_frame::{DecodeError, Frame};

/// Simulated scenes served by the emulator, in order (cycling).
pub struct SimSource {
    ranges: Vec<Vec<f32>>,
    next: usize,
}

impl SimSource {
    /// Serves `ranges` (mm, one vector per scan) in order, cycling.
    pub fn new(ranges: Vec<Vec<f32>>) -> Self {
        Self { ranges, next: 0 }
    }
}

impl lms200_emulator::RangeSource for SimSource {
    fn next_scan(&mut self, n: usize, _start_deg: f32, _step_deg: f32) -> Vec<f32> {
        let r = match self.ranges.get(self.next % self.ranges.len().max(1)) {
            Some(r) if r.len() == n => r.clone(),
            _ => vec![f32::NAN; n],
        };
        self.next += 1;
        r
    }
}

/// One QEMU session: the firmware against the emulated LMS200 serving simulated scans.
pub struct Session {
    /// The simulated scans (the emulator serves `sims[k % len]` as its k-th B0 telegram).
    pub sims: Vec<pfe_eval::scene::SimScan>,
    /// What the emulator did.
    pub emulator: lms200_emulator::EmulatorReport,
    /// QEMU's run.
    pub run: Run,
    /// Frames from UART1.
    pub frames: Vec<Frame>,
    /// Rejected frames.
    pub bad_frames: Vec<DecodeError>,
}

/// Runs `elf` (pfe-qemu) for `scans` scans with `config` ("paper" / "default") against the
/// emulator serving mixed simulated scenes from `seed`.
pub fn session(
    elf: &Path,
    scans: u32,
    config: &str,
    seed: u64,
    timeout: Duration,
) -> Result<Session> {
    session_with(elf, scans, &[config], scans, seed, timeout)
}

/// [`session`] with pfe-qemu's semihosting arguments after `scans` (`args`: config, baud,
/// slow_ms, slow_every) and `rooms` distinct simulated scenes (more than `scans` when
/// telegrams may be lost, so that every telegram stays identifiable by its features).
pub fn session_with(
    elf: &Path,
    scans: u32,
    args: &[&str],
    rooms: u32,
    seed: u64,
    timeout: Duration,
) -> Result<Session> {
    use pfe_eval::scene::{Scenario, SceneKind};
    let sims: Vec<_> = (seed..seed + u64::from(rooms.max(1)))
        .map(|s| Scenario::new(SceneKind::Mixed, s).simulate())
        .collect();
    session_sims(elf, scans, args, sims, seed, timeout)
}

/// [`session`] on consecutive scans of a robot driving around a room
/// ([`pfe_eval::scene::drive::room_drive`] from noise seed `seed`; the emulator's telegram `k`
/// is the drive's scan `k`, for `4 · scans` telegrams: room for telegrams the firmware misses
/// before the drive would start over): the firmware's pose step has a motion to find.
pub fn session_drive(
    elf: &Path,
    scans: u32,
    config: &str,
    seed: u64,
    timeout: Duration,
) -> Result<Session> {
    let sims = pfe_eval::scene::drive::room_drive(4 * scans.max(1) as usize, seed)
        .into_iter()
        .map(|d| d.scan)
        .collect();
    session_sims(elf, scans, &[config], sims, seed, timeout)
}

/// A session serving `sims` in order (cycling).
fn session_sims(
    elf: &Path,
    scans: u32,
    args: &[&str],
    sims: Vec<pfe_eval::scene::SimScan>,
    seed: u64,
    timeout: Duration,
) -> Result<Session> {
    use lms200_emulator::serve::{serve_on, Pty};
    use lms200_emulator::{Emulator, EmulatorConfig, RunLimits};
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;

    let source = SimSource {
        ranges: sims.iter().map(|s| s.ranges_mm.clone()).collect(),
        next: 0,
    };
    // The LMS200 on a pty: QEMU's tty backend passes the UART's baud divisor on, so the
    // emulator sees the firmware's baud switch (a TCP backend would not).
    let link = std::env::temp_dir().join(format!(
        "pfe-qemu-lms-{}-{seed}-{scans}",
        std::process::id()
    ));
    let mut pty = Pty::open(&link)?;
    let slave = pty.slave_path().display().to_string();
    let (l1, p1) = listener()?;
    let stop = Arc::new(AtomicBool::new(false));
    let limits = RunLimits {
        stop: Some(stop.clone()),
        max_time: Some(timeout),
        ..RunLimits::default()
    };
    let emu = Emulator::new(EmulatorConfig::default(), Box::new(source));
    let server = std::thread::spawn(move || serve_on(&mut pty, emu, limits));
    let n = scans.to_string();
    let all: Vec<&str> = std::iter::once(n.as_str())
        .chain(args.iter().copied())
        .collect();
    let cmd = qemu_command(elf, &slave, &format!("tcp:127.0.0.1:{p1}"), &all, false);
    let run = run_collect(cmd, l1, timeout)?;
    stop.store(true, Ordering::Relaxed);
    let emulator = server
        .join()
        .map_err(|_| anyhow::anyhow!("the emulator thread panicked"))??;
    let (frames, bad_frames) = decode_frames(&run.output);
    Ok(Session {
        sims,
        emulator,
        run,
        frames,
        bad_frames,
    })
}
