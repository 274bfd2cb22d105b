//! The QEMU soak: the real firmware (`pfe-qemu`, mps2-an386) against the emulated LMS200 on a
//! pseudo-terminal (QEMU's tty backend passes the UART's baud divisor on, so baud switches and
//! the power-on 9600 after a device reset are modelled), with the same ~1 % damage mix as the other soaks (`super::faults`), one device
//! reset and one silence long enough to force a re-initialisation.
//!
//! Every frame the firmware sends must decode with a valid CRC; each scan frame is matched, in
//! order, to the B0 telegram whose features pfe-core on the host computes bit-identically; the
//! counters in the frames must agree with what the emulator sent and damaged; and the stack
//! high-water mark of the full run may exceed that of a short run (warm-up) by at most
//! [`STACK_SLACK`]: with no heap and no recursion the stack cannot grow with the number of
//! scans, but a rare path (a re-initialisation interrupted by damage, an unusual scan) can be
//! taken first after the warm-up and go a frame or two deeper; a leak would not stop there.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use firmware::app::ConfigChoice;
use lms200_emulator::serve::{serve_on, Pty};
use lms200_emulator::{Emulator, EmulatorConfig, EmulatorReport, RunLimits};
use pfe_core::Feature;
use pfe_eval::scene::{Scenario, SceneKind};
use pfe_frame::{Counters, Frame, Header, Report};

use crate::qemu;

/// Scans in the warm-up run whose stack high-water mark the full run must stay close to.
pub const WARMUP_SCANS: u32 = 200;
/// How far, bytes, the full run's stack high-water mark may exceed the warm-up's.
pub const STACK_SLACK: u32 = 1024;
/// The emulator resets itself after this many B0 telegrams (in both runs).
const RESET_AFTER: u32 = 60;
/// The emulator falls silent (longer than the driver's 1 s silence timeout) after this many.
const SILENCE_AFTER: u32 = 120;
/// Length of the silence, ms.
const SILENCE_MS: u32 = 3000;
/// How far ahead of the last matched telegram a frame's telegram is searched.
const WINDOW: usize = 64;

/// One firmware run under QEMU.
struct QemuRun {
    code: Option<i32>,
    frames: Vec<Frame>,
    bad_frames: usize,
    emulator: EmulatorReport,
    elapsed: Duration,
}

/// Builds `pfe-qemu` the way `cargo xtask size`/`demo` ship it (opt-level "s").
fn build() -> Result<PathBuf> {
    let dir = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| qemu::root().join("target"))
        .join("soak-firmware");
    qemu::build_firmware(
        "pfe-qemu",
        &[],
        &[("CARGO_PROFILE_RELEASE_OPT_LEVEL", qemu::FIRMWARE_OPT_LEVEL)],
        &dir,
    )
}

/// Runs `elf` for `scans` scans against the damaging emulator serving `ranges` in order.
fn run_once(elf: &Path, scans: u32, ranges: Vec<Vec<f32>>, a: &super::Args) -> Result<QemuRun> {
    let t0 = Instant::now();
    let mut faults = super::faults(a.damage);
    faults.reset_after_scans = Some(RESET_AFTER);
    faults.silence_after_scans = Some(SILENCE_AFTER);
    faults.silence_ms = SILENCE_MS;
    let cfg = EmulatorConfig {
        faults,
        seed: a.seed,
        ..Default::default()
    };
    let timeout = Duration::from_secs(60 + u64::from(scans) / 10);
    let link = std::env::temp_dir().join(format!("pfe-soak-qemu-{}", std::process::id()));
    let mut pty = Pty::open(&link)?;
    let slave = pty.slave_path().display().to_string();
    let (l1, p1) = qemu::listener()?;
    let stop = Arc::new(AtomicBool::new(false));
    let limits = RunLimits {
        stop: Some(stop.clone()),
        max_time: Some(timeout),
        ..RunLimits::default()
    };
    let emu = Emulator::new(cfg, Box::new(qemu::SimSource::new(ranges)));
    let server = std::thread::spawn(move || serve_on(&mut pty, emu, limits));
    let n = scans.to_string();
    let cmd = qemu::qemu_command(
        elf,
        &slave,
        &format!("tcp:127.0.0.1:{p1}"),
        // As the board runs: the extraction without the pose step, which costs far more than a
        // scan period on the M4F (docs/POSE.md) and would overrun the receive ring.
        &[&n, "default-nopose", "500000"],
        false,
    );
    let run = qemu::run_collect(cmd, l1, timeout)?;
    stop.store(true, Ordering::Relaxed);
    let emulator = server
        .join()
        .map_err(|_| anyhow::anyhow!("the emulator thread panicked"))??;
    let log = elf.with_extension(format!("{scans}-scans.defmt"));
    let saved = std::fs::write(&log, &run.stdout).is_ok();
    if run.code != Some(0) {
        eprintln!("qemu stderr:\n{}", run.stderr);
        if saved {
            eprintln!(
                "the firmware's defmt log is in {} (defmt-print -e {} < it)",
                log.display(),
                elf.display()
            );
        }
    }
    let (frames, bad) = qemu::decode_frames(&run.output);
    Ok(QemuRun {
        code: run.code,
        frames,
        bad_frames: bad.len(),
        emulator,
        elapsed: t0.elapsed(),
    })
}

/// The stack report of a run: `(used, size)`.
fn stack_of(r: &QemuRun) -> Option<(u32, u32)> {
    r.frames.iter().find_map(|f| match f.header {
        Header::Report(Report::Stack { used, size }) => Some((used, size)),
        _ => None,
    })
}

/// The account of the full run.
#[derive(Default, Debug)]
struct Account {
    sent: usize,
    sent_damaged: usize,
    scan_frames: usize,
    matched_intact: usize,
    flagged_exact: usize,
    unmatched_frames: usize,
    features: usize,
    dropped_damaged: usize,
    missing_intact: usize,
    lost_in_reinit: usize,
    tail: usize,
    seq_errors: usize,
    /// Counter checks.
    ok_delta_errors: usize,
    phantom_drops: usize,
    unnoticed_damage: usize,
    crc_dropped_quiet: u32,
    damaged_dropped_quiet: usize,
    last: Counters,
}

fn same_features(a: &[Feature], b: &[Feature]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(x, y)| qemu::ulps_apart(x, y).is_none())
}

/// Matches each scan frame, in order, to the telegram the host's pfe-core agrees with
/// bit-for-bit, and checks the counters interval by interval.
fn account(r: &QemuRun) -> Result<Account> {
    let sent = &r.emulator.scans;
    let mut a = Account {
        sent: sent.len(),
        sent_damaged: sent.iter().filter(|s| s.damaged).count(),
        ..Default::default()
    };
    let mut cache: Vec<Option<Vec<Feature>>> = vec![None; sent.len()];
    let mut host = |j: usize| -> Result<Vec<Feature>> {
        if let Some(Some(f)) = cache.get(j) {
            return Ok(f.clone());
        }
        let words = &sent.get(j).context("no such telegram")?.words;
        let f = qemu::host_features(words, ConfigChoice::Default)?;
        if let Some(c) = cache.get_mut(j) {
            *c = Some(f.clone());
        }
        Ok(f)
    };
    let mut next = 0usize;
    let mut prev = Counters::default();
    for (k, f) in r
        .frames
        .iter()
        .filter_map(|f| f.scan().map(|h| (h, f)))
        .enumerate()
    {
        let (h, frame) = f;
        a.scan_frames += 1;
        a.features += frame.features.len();
        if h.seq != k as u32 {
            a.seq_errors += 1;
        }
        let mut found = None;
        for j in next..(next + WINDOW).min(sent.len()) {
            if same_features(&host(j)?, &frame.features) {
                found = Some(j);
                break;
            }
        }
        let Some(j) = found else {
            a.unmatched_frames += 1;
            continue;
        };
        let c = h.counters;
        // The first frame's counters also hold the initialisation's replies.
        let reinit = k == 0 || c.reinits != prev.reinits;
        let gap = sent.get(next..j).unwrap_or(&[]);
        let gap_damaged = gap.iter().filter(|s| s.damaged).count();
        let gap_intact = gap.len() - gap_damaged;
        a.dropped_damaged += gap_damaged;
        if reinit {
            // Telegrams streaming in while the driver re-initialises are lost legitimately.
            a.lost_in_reinit += gap_intact;
        } else {
            a.missing_intact += gap_intact;
            // One good-CRC telegram per scan between re-initialisations.
            if c.telegrams_ok.wrapping_sub(prev.telegrams_ok) != 1 {
                a.ok_delta_errors += 1;
            }
            let dropped = c.crc_dropped.wrapping_sub(prev.crc_dropped);
            let skipped = c.bytes_skipped.wrapping_sub(prev.bytes_skipped);
            a.crc_dropped_quiet += dropped;
            a.damaged_dropped_quiet += gap_damaged;
            if gap_damaged == 0 && dropped != 0 {
                a.phantom_drops += 1;
            }
            if gap_damaged > 0 && dropped == 0 && skipped == 0 {
                a.unnoticed_damage += 1;
            }
        }
        if sent.get(j).is_some_and(|s| s.damaged) {
            a.flagged_exact += 1;
        } else {
            a.matched_intact += 1;
        }
        prev = c;
        next = j + 1;
    }
    a.tail = sent.len().saturating_sub(next);
    a.last = prev;
    Ok(a)
}

/// Runs the QEMU soak for `scans` scans (and the warm-up run); `Ok(true)` when it balances.
pub fn run(a: &super::Args) -> Result<bool> {
    if !qemu::have("qemu-system-arm") || !qemu::have_target() {
        pfe_testkit::skip::skip(
            "soak (QEMU)",
            "needs qemu-system-arm and the thumbv7em-none-eabihf target",
            pfe_testkit::skip::Need::InCi,
        );
        return Ok(true);
    }
    let scans = u32::try_from(a.scans).context("--scans")?;
    let elf = build()?;
    // Distinct simulated rooms, so that every frame names its telegram by its features.
    let n = scans as usize + 200;
    let ranges: Vec<Vec<f32>> = (0..n as u64)
        .map(|s| {
            Scenario::new(SceneKind::Mixed, a.seed * 1_000_003 + s)
                .simulate()
                .ranges_mm
        })
        .collect();
    let warm = run_once(&elf, WARMUP_SCANS.min(scans), ranges.clone(), a)?;
    let full = run_once(&elf, scans, ranges, a)?;
    let acc = account(&full)?;
    let (w_stack, f_stack) = (stack_of(&warm), stack_of(&full));
    let done = full
        .frames
        .iter()
        .any(|f| f.header == Header::Report(Report::Done { scans }));
    let em = &full.emulator;
    let silences = u32::from(em.scans.len() > SILENCE_AFTER as usize);
    // Every device reset must lead to a re-initialisation. The silence (3 s, three times
    // the driver's timeout) usually does too, but not always: when QEMU reads the pty more
    // slowly than the emulator writes (a loaded host), the backlog still in the pty covers
    // the silence. A re-init whose probe falls into the device's deaf time after a reset
    // fails and is retried, so a few more are allowed; damage alone never causes one.
    let reinits_ok = acc.last.reinits >= em.resets
        && acc.last.reinits <= em.resets + silences + 2 + scans / 1000;

    println!(
        "\nsoak (QEMU pfe-qemu, mps2-an386, LMS200 on a pty): {:.1} s",
        full.elapsed.as_secs_f64()
    );
    println!(
        "  firmware exit code (warm-up / full)   {:?} / {:?}",
        warm.code, full.code
    );
    println!(
        "  frames decoded / rejected (CRC)       {:>9} / {}",
        full.frames.len(),
        full.bad_frames
    );
    println!("  telegrams (B0) sent by the emulator   {:>9}", acc.sent);
    println!(
        "    damaged on the way                  {:>9}",
        acc.sent_damaged
    );
    println!(
        "    intact                              {:>9}",
        acc.sent - acc.sent_damaged
    );
    println!(
        "  scan frames from the firmware         {:>9}  (Done report: {done})",
        acc.scan_frames
    );
    println!(
        "    = host pfe-core, bit-identical      {:>9}  ({} features)",
        acc.matched_intact + acc.flagged_exact,
        acc.features
    );
    println!(
        "    flagged damaged, own bytes intact   {:>9}",
        acc.flagged_exact
    );
    println!(
        "    matching no telegram                {:>9}",
        acc.unmatched_frames
    );
    println!(
        "    sequence-number errors              {:>9}",
        acc.seq_errors
    );
    println!(
        "  damaged telegrams dropped             {:>9}",
        acc.dropped_damaged
    );
    println!(
        "  intact telegrams missing              {:>9}",
        acc.missing_intact
    );
    println!(
        "  intact lost during re-init            {:>9}",
        acc.lost_in_reinit
    );
    println!("  sent after the last frame (tail)      {:>9}", acc.tail);
    println!("  firmware counters (last frame)        {:?}", acc.last);
    println!(
        "    reinits vs emulator resets+silences {:>9} / {} + {}  ({})",
        acc.last.reinits,
        em.resets,
        silences,
        if reinits_ok {
            "ok: one per reset, extra ones rare"
        } else {
            "NOT OK"
        }
    );
    println!(
        "    CRC-dropped vs damaged (no re-init) {:>9} / {}",
        acc.crc_dropped_quiet, acc.damaged_dropped_quiet
    );
    println!(
        "    intervals with telegrams_ok Δ ≠ 1   {:>9}",
        acc.ok_delta_errors
    );
    println!(
        "    drops without damage (phantom)      {:>9}",
        acc.phantom_drops
    );
    println!(
        "    damage not seen in counters         {:>9}",
        acc.unnoticed_damage
    );
    println!(
        "  stack high-water mark after {} / {} scans: {:?} / {:?}  (used, size bytes)",
        WARMUP_SCANS.min(scans),
        scans,
        w_stack.map(|s| s.0),
        f_stack
    );

    let ok = warm.code == Some(0)
        && full.code == Some(0)
        && warm.bad_frames == 0
        && full.bad_frames == 0
        && done
        && acc.scan_frames == scans as usize
        && acc.unmatched_frames == 0
        && acc.seq_errors == 0
        && acc.missing_intact == 0
        && acc.ok_delta_errors == 0
        && acc.phantom_drops == 0
        && acc.unnoticed_damage == 0
        && reinits_ok
        && acc.sent_damaged > 0
        && matches!((w_stack, f_stack), (Some((w, _)), Some((f, size))) if f <= w + STACK_SLACK && f < size);
    println!(
        "  account: {}",
        if ok {
            "BALANCED — firmware exit 0, every frame decodes, every scan bit-identical to host pfe-core, counters agree, stack bounded"
        } else {
            "NOT BALANCED"
        }
    );
    Ok(ok)
}
