//! Runtime glue every binary shares: the SysTick, HardFault and panic handlers, and the
//! statics the pipeline runs in (no heap).

use core::sync::atomic::{AtomicBool, Ordering};

use cortex_m_rt::{exception, ExceptionFrame};
use firmware::app::{ConfigChoice, LmsApp, LmsExtractor};

use crate::{sys, time};

#[exception]
fn SysTick() {
    time::on_systick();
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
