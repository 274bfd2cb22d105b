//! The independent watchdog (IWDG, clocked by the 32 kHz LSI, so it runs whatever the main
//! clock does) and the cause of the last reset (RCC_CSR).
//!
//! The watchdog is fed once per main-loop iteration and by the driver's delay, which every
//! wait of the LMS driver calls while it polls (each such wait ends at its timeout, as the
//! `lms_driver` fuzz target checks). So initialisation, which may wait several seconds, does
//! not trip it, while a loop that stops polling or a stuck extraction or output does.

use core::cell::RefCell;

use cortex_m::interrupt::{self, Mutex};
use stm32f4xx_hal::{pac, prelude::*, watchdog::IndependentWatchdog};

/// Watchdog timeout, ms: several scan periods at 500 kBd (26.7 ms) and above one at 38 400 Bd
/// (190 ms); the LSI's spread (17–47 kHz) makes the real timeout 170–470 ms.
pub const TIMEOUT_MS: u32 = 250;

static WATCHDOG: Mutex<RefCell<Option<IndependentWatchdog>>> = Mutex::new(RefCell::new(None));

/// Starts the watchdog (it cannot be stopped again); it pauses while a debugger halts the core.
pub fn start(iwdg: pac::IWDG, dbgmcu: &pac::DBGMCU) {
    let mut wdg = IndependentWatchdog::new(iwdg);
    wdg.stop_on_debug(dbgmcu, true);
    wdg.start(TIMEOUT_MS.millis());
    interrupt::free(|cs| *WATCHDOG.borrow(cs).borrow_mut() = Some(wdg));
}

/// Reloads the watchdog's counter (nothing before [`start`]).
pub fn feed() {
    interrupt::free(|cs| {
        if let Some(w) = WATCHDOG.borrow(cs).borrow_mut().as_mut() {
            w.feed();
        }
    });
}

/// Why the MCU last reset, most specific first (an internal reset also sets the pin flag,
/// a power-on reset the brown-out flag).
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum ResetCause {
    /// Low-power management (entering Standby or Stop with the nRST_STDBY/STOP option).
    LowPower,
    /// Window watchdog.
    WindowWatchdog,
    /// Independent watchdog: the main loop stopped.
    IndependentWatchdog,
    /// Software (`SCB::sys_reset`, e.g. after a panic).
    Software,
    /// Power-on or brown-out.
    PowerOn,
    /// The NRST pin (reset button or debugger).
    Pin,
    /// No flag set.
    Unknown,
}

/// Reads the reset flags of RCC_CSR, then clears them (RMVF) so the next reset reports its own.
pub fn take_reset_cause(rcc: &pac::RCC) -> ResetCause {
    let csr = rcc.csr().read();
    let cause = if csr.lpwrrstf().bit_is_set() {
        ResetCause::LowPower
    } else if csr.wwdgrstf().bit_is_set() {
        ResetCause::WindowWatchdog
    } else if csr.wdgrstf().bit_is_set() {
        ResetCause::IndependentWatchdog
    } else if csr.sftrstf().bit_is_set() {
        ResetCause::Software
    } else if csr.porrstf().bit_is_set() || csr.borrstf().bit_is_set() {
        ResetCause::PowerOn
    } else if csr.padrstf().bit_is_set() {
        ResetCause::Pin
    } else {
        ResetCause::Unknown
    };
    rcc.csr().modify(|_, w| w.rmvf().set_bit());
    cause
}
