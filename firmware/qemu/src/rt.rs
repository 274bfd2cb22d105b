//! Runtime glue every binary shares: the SysTick, HardFault, device interrupt and panic
//! handlers, and the statics the pipeline runs in (no heap).

use core::sync::atomic::{AtomicBool, Ordering};

use cortex_m_rt::{exception, ExceptionFrame};
use firmware::app::{ConfigChoice, LmsApp, LmsExtractor};
use pfe_frame::Report;

use crate::uart::Uart;
use crate::{scanner_uart, sys, time};
use firmware::rx_ring::RING_SLOTS;

/// Takes the core peripherals and starts the SysTick time base ([`time::start`]); exits with
/// [`sys::EXIT_USAGE`] when called twice.
pub fn start_clock() {
    let Some(cp) = cortex_m::Peripherals::take() else {
        sys::exit(sys::EXIT_USAGE)
    };
    time::start(cp.SYST);
}

/// Sends `r` as a report frame on `out`; exits with [`sys::EXIT_OUTPUT`] when that fails.
pub fn report(out: &mut Uart, r: Report) {
    if pfe_frame::write_report(out, &r).is_err() {
        sys::exit(sys::EXIT_OUTPUT);
    }
}

/// The end of a run of the pfe firmware: sends `Report::Stack` (painted-stack high-water
/// mark) and `Report::Done { scans }` on `out`, writes the receive path's account to
/// semihosting stderr (`rx: ring_full=… overruns=… line_errors=… peak=… capacity=…
/// scan_errors=…`), then exits QEMU with [`sys::EXIT_OK`].
pub fn finish(out: &mut Uart, scans: u32, scan_errors: u32) -> ! {
    let (used, size) = sys::stack_usage();
    defmt::info!("done: stack high-water mark {} of {} bytes", used, size);
    report(out, Report::Stack { used, size });
    report(out, Report::Done { scans });
    let rx = scanner_uart::rx_counters();
    sys::eprint_stats(
        "rx:",
        &[
            ("ring_full", rx.ring_full()),
            ("overruns", rx.overruns()),
            ("line_errors", rx.line_errors()),
            ("peak", rx.peak()),
            ("capacity", RING_SLOTS as u32 - 1),
            ("scan_errors", scan_errors),
        ],
    );
    sys::exit(sys::EXIT_OK)
}

#[exception]
fn SysTick() {
    time::on_systick();
}

/// Device interrupts (cortex-m-rt's vector table sends them all here with their number):
/// UART0's receive interrupt and, with feature `async`, timer 0's; no other is unmasked.
#[exception]
#[allow(unsafe_code)]
unsafe fn DefaultHandler(irqn: i16) {
    if irqn == scanner_uart::UART0_RX_IRQ as i16 {
        scanner_uart::on_rx_interrupt();
        #[cfg(feature = "async")]
        crate::asynch::on_rx_interrupt();
    }
    #[cfg(feature = "async")]
    if irqn == crate::asynch::TIMER0_IRQ as i16 {
        crate::asynch::on_timer_interrupt();
    }
}

#[exception]
#[allow(unsafe_code)]
unsafe fn HardFault(_ef: &ExceptionFrame) -> ! {
    sys::exit(sys::EXIT_FAULT)
}

#[panic_handler]
fn panic(_info: &core::panic::PanicInfo) -> ! {
    sys::exit(sys::EXIT_PANIC)
}

/// The application in a `static` (its default state is all zero bytes: `.bss`, no copy on
/// the stack); `None` after the first call.
pub fn take_app() -> Option<&'static mut LmsApp> {
    static TAKEN: AtomicBool = AtomicBool::new(false);
    static mut APP: LmsApp = LmsApp::new(ConfigChoice::Default);
    if TAKEN.swap(true, Ordering::Relaxed) {
        return None;
    }
    #[allow(unsafe_code)]
    // SAFETY: TAKEN lets only the first call through: this is the only reference to APP.
    unsafe {
        Some(&mut *core::ptr::addr_of_mut!(APP))
    }
}

/// A bare extractor in a `static` (as [`take_app`]); `None` after the first call.
pub fn take_extractor() -> Option<&'static mut LmsExtractor> {
    static TAKEN: AtomicBool = AtomicBool::new(false);
    static mut EX: LmsExtractor = LmsExtractor::new();
    if TAKEN.swap(true, Ordering::Relaxed) {
        return None;
    }
    #[allow(unsafe_code)]
    // SAFETY: as in `take_app`.
    unsafe {
        Some(&mut *core::ptr::addr_of_mut!(EX))
    }
}
