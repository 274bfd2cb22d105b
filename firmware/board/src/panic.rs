//! The panic handler: the panic's location and, when it has no arguments, its message over
//! defmt, then a `HardFault` (as panic-probe's, which probe-rs reports with a backtrace).
//! panic-probe's own printing formats the whole message with `core::fmt` (about 2 KB of
//! flash); a message with arguments (core's bounds checks) is named by its location here.

use core::panic::PanicInfo;
use core::sync::atomic::{AtomicBool, Ordering};

#[panic_handler]
fn panic(info: &PanicInfo) -> ! {
    static PANICKED: AtomicBool = AtomicBool::new(false);
    cortex_m::interrupt::disable();
    // Once: a panic while reporting one goes straight to the fault.
    if !PANICKED.load(Ordering::Relaxed) {
        PANICKED.store(true, Ordering::Relaxed);
        let message = info
            .message()
            .as_str()
            .unwrap_or("(a message with arguments)");
        match info.location() {
            Some(l) => defmt::error!(
                "panicked at {=str}:{=u32}:{=u32}: {=str}",
                l.file(),
                l.line(),
                l.column(),
                message
            ),
            None => defmt::error!("panicked: {=str}", message),
        }
    }
    hard_fault()
}

/// A `HardFault` by `udf` (UsageFault disabled first, or `udf` would raise that instead).
fn hard_fault() -> ! {
    const SHCSR: *mut u32 = 0xE000_ED24usize as _;
    const USGFAULTENA: u32 = 18;
    #[allow(unsafe_code)]
    // SAFETY: SHCSR is the Cortex-M4's System Handler Control and State Register (always
    // mapped); clearing its UsageFault enable bit with interrupts off only reroutes faults.
    unsafe {
        let shcsr = core::ptr::read_volatile(SHCSR);
        core::ptr::write_volatile(SHCSR, shcsr & !(1 << USGFAULTENA));
    }
    cortex_m::asm::udf()
}
