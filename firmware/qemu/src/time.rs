//! SysTick as a free-running 64-bit tick counter (24-bit hardware counter plus a wrap count
//! kept by the SysTick exception, every 2^24 ticks), with microsecond time and a busy-wait
//! delay built on it.
//!
//! On `mps2-an386` SysTick counts the 25 MHz system clock. Under QEMU with
//! `-icount shift=10` every instruction takes 1024 ns of virtual time, i.e. 25.6 ticks, so
//! `instructions = ticks × 10 / 256` exactly; without `-icount` ticks follow host time.

use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::peripheral::{syst::SystClkSource, SCB, SYST};

/// SysTick frequency on mps2-an386, Hz.
pub const TICK_HZ: u64 = 25_000_000;
const RELOAD: u32 = 0x00FF_FFFF;

static WRAPS: AtomicU32 = AtomicU32::new(0);

/// Called from the SysTick exception handler of the binary.
pub fn on_systick() {
    WRAPS.fetch_add(1, Ordering::Relaxed);
}

/// Starts SysTick (core clock, maximum reload, exception on wrap).
pub fn start(mut syst: SYST) {
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(RELOAD);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
}

/// Ticks since [`start`]; monotonic.
///
/// The counter can wrap before its exception has been taken (QEMU delivers it at the end of
/// a translation block; on hardware it waits while a higher priority runs), so a wrap still
/// pending counts too: the value read before the pending bit is from before any wrap when
/// the bit is clear, the one read after it from after the wrap when it is set. Counting the
/// wrap count alone made time jump back by 2^24 ticks (0.67 s) now and then.
pub fn ticks() -> u64 {
    loop {
        let w0 = WRAPS.load(Ordering::Relaxed);
        let before = SYST::get_current();
        let pending = SCB::is_pendst_pending();
        let after = SYST::get_current();
        let w1 = WRAPS.load(Ordering::Relaxed);
        if w0 == w1 {
            let (wraps, cvr) = if pending {
                (u64::from(w0) + 1, after)
            } else {
                (u64::from(w0), before)
            };
            return (wraps << 24) + u64::from(RELOAD - cvr);
        }
    }
}

/// Microseconds since [`start`].
pub fn micros() -> u64 {
    ticks() * 1_000_000 / TICK_HZ
}

/// Busy-wait delay on [`ticks`] (`embedded_hal::delay::DelayNs`).
#[derive(Clone, Copy, Debug, Default)]
pub struct Delay;

impl embedded_hal::delay::DelayNs for Delay {
    fn delay_ns(&mut self, ns: u32) {
        let until = ticks() + (u64::from(ns) * TICK_HZ).div_ceil(1_000_000_000);
        while ticks() < until {}
    }
}

/// Milliseconds from [`ticks`] for the LMS driver.
#[derive(Clone, Copy, Debug, Default)]
pub struct Clock;

impl lms2xx::driver::Clock for Clock {
    fn now_ms(&mut self) -> u32 {
        (ticks() / (TICK_HZ / 1000)) as u32
    }
}
