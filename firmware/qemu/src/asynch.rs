//! The async path on QEMU (feature `async`): what lms2xx's
//! [`AsyncDriver`](lms2xx::driver::AsyncDriver) needs, on the same UART0 receive interrupt and
//! ring as the blocking driver, and the smallest executor that runs it.
//!
//! - [`AsyncScanner`]: UART0 as `embedded_io_async::Read + Write` and
//!   [`AsyncSetBaud`]. A read takes what is in the receive ring or waits, woken by UART0's
//!   receive interrupt ([`on_rx_interrupt`]); it takes bytes only when it completes, so a read
//!   dropped unfinished loses none (cancel-safe, as the driver requires). Sending stays polled.
//! - [`AsyncDelay`]: `embedded_hal_async::delay::DelayNs` on the SysTick time base
//!   ([`crate::time::ticks`]), woken by a one-shot alarm on the CMSDK APB timer 0
//!   ([`on_timer_interrupt`]).
//! - [`block_on`]: runs one future to its end, sleeping with `WFI` while it waits; any waker
//!   call (from the two interrupts) makes it poll again.
//!
//! The interrupt handlers are called from the runtime's `DefaultHandler` ([`crate::rt`]).

use core::cell::RefCell;
use core::future::{poll_fn, Future};
use core::pin::pin;
use core::sync::atomic::{AtomicBool, Ordering};
use core::task::{Context, Poll, RawWaker, RawWakerVTable, Waker};

use cortex_m::interrupt::{self as irq, InterruptNumber, Mutex};
use cortex_m::peripheral::NVIC;
use firmware::rx_ring::RxLoss;
use lms2xx::driver::{AsyncSetBaud, SetBaud};

use crate::scanner_uart::ScannerUart;
use crate::time;

/// The waker of the one task waiting on an interrupt (set at each poll, taken by the handler).
struct WakerSlot(Mutex<RefCell<Option<Waker>>>);

impl WakerSlot {
    const fn new() -> Self {
        Self(Mutex::new(RefCell::new(None)))
    }

    /// Keeps `waker` for the next [`WakerSlot::wake`] (no clone when it is the one kept).
    fn register(&self, waker: &Waker) {
        irq::free(|cs| {
            let mut slot = self.0.borrow(cs).borrow_mut();
            match slot.as_ref() {
                Some(w) if w.will_wake(waker) => {}
                _ => *slot = Some(waker.clone()),
            }
        });
    }

    /// Wakes the waker kept, if any (from an interrupt handler).
    fn wake(&self) {
        if let Some(w) = irq::free(|cs| self.0.borrow(cs).borrow_mut().take()) {
            w.wake();
        }
    }
}

/// Woken by UART0's receive interrupt.
static RX_WAKER: WakerSlot = WakerSlot::new();
/// Woken by timer 0's interrupt.
static ALARM_WAKER: WakerSlot = WakerSlot::new();

/// Called by the runtime after UART0's receive handler moved the bytes into the ring.
pub fn on_rx_interrupt() {
    RX_WAKER.wake();
}

/// Loss on the receive path ([`RxLoss`]) as an `embedded-io-async` error (that crate's
/// `embedded-io` is not the one the firmware library's ring implements).
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub struct LinkError(pub RxLoss);

impl core::fmt::Display for LinkError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self.0 {
            RxLoss::Overrun => f.write_str("UART overrun"),
            RxLoss::RingFull => f.write_str("receive ring full"),
        }
    }
}

impl core::error::Error for LinkError {}

impl embedded_io_async::Error for LinkError {
    fn kind(&self) -> embedded_io_async::ErrorKind {
        embedded_io_async::ErrorKind::Other
    }
}

/// UART0 to the LMS200 for the async driver: [`ScannerUart`]'s ring, awaited.
pub struct AsyncScanner {
    uart: ScannerUart,
}

impl AsyncScanner {
    /// UART0 with its receive interrupt on (see [`ScannerUart::new`]); `None` if called twice.
    pub fn new() -> Option<Self> {
        ScannerUart::new().map(|uart| Self { uart })
    }
}

impl embedded_io_async::ErrorType for AsyncScanner {
    type Error = LinkError;
}

impl embedded_io_async::Read for AsyncScanner {
    /// Waits until a byte (or a loss not yet reported) is in the ring, then takes what is
    /// there, up to `buf.len()` bytes. Cancel-safe: nothing is taken before it completes.
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, LinkError> {
        if buf.is_empty() {
            return Ok(0);
        }
        poll_fn(|cx| {
            // Registered before looking, so a byte arriving after the look wakes us.
            RX_WAKER.register(cx.waker());
            match embedded_io::ReadReady::read_ready(&mut self.uart) {
                // Ready: the ring's read returns at once (bytes, or the loss).
                Ok(true) => Poll::Ready(embedded_io::Read::read(&mut self.uart, buf)),
                Ok(false) => Poll::Pending,
                Err(e) => Poll::Ready(Err(e)),
            }
            .map(|r| r.map_err(LinkError))
        })
        .await
    }
}

impl embedded_io_async::Write for AsyncScanner {
    /// Sends `buf` (polled: QEMU's transmitter is never full for long).
    async fn write(&mut self, buf: &[u8]) -> Result<usize, LinkError> {
        embedded_io::Write::write(&mut self.uart, buf).map_err(LinkError)
    }

    async fn flush(&mut self) -> Result<(), LinkError> {
        embedded_io::Write::flush(&mut self.uart).map_err(LinkError)
    }
}

impl AsyncSetBaud for AsyncScanner {
    /// As [`ScannerUart`]'s `set_baud`: BAUDDIV, and the bytes received at the old rate dropped.
    async fn set_baud(&mut self, baud: u32) -> Result<(), LinkError> {
        SetBaud::set_baud(&mut self.uart, baud).map_err(LinkError)
    }
}

/// CMSDK APB timer 0 on mps2-an386.
const TIMER0: usize = 0x4000_0000;
/// NVIC line of timer 0 on mps2-an386 (QEMU's `hw/arm/mps2.c`).
pub const TIMER0_IRQ: u16 = 8;
/// Timer registers: CTRL (bit 0 enable, bit 3 interrupt enable), VALUE, RELOAD, INTSTATUS
/// (bit 0, write 1 to clear). The timer counts PCLK (25 MHz, SysTick's rate) down from
/// RELOAD and raises its interrupt on the step from 1 to 0.
const CTRL: usize = 0x0;
const VALUE: usize = 0x4;
const RELOAD: usize = 0x8;
const INTSTATUS: usize = 0xC;
const CTRL_EN_IRQ: u32 = 0b1001;

/// Timer 0's interrupt, for the NVIC.
#[derive(Clone, Copy, Debug)]
struct Timer0;

// SAFETY: `number` is a device interrupt line of mps2-an386 (see `TIMER0_IRQ`).
#[allow(unsafe_code)]
unsafe impl InterruptNumber for Timer0 {
    fn number(self) -> u16 {
        TIMER0_IRQ
    }
}

#[allow(unsafe_code)]
fn timer_write(reg: usize, v: u32) {
    // SAFETY: TIMER0 is the CMSDK APB timer block of the MPS2 memory map; its registers are
    // 32-bit and aligned, and only this module uses the timer.
    unsafe { core::ptr::write_volatile((TIMER0 + reg) as *mut u32, v) }
}

/// Stops timer 0 and clears its interrupt (status and NVIC pending bit).
fn timer_stop() {
    timer_write(CTRL, 0);
    timer_write(INTSTATUS, 1);
    NVIC::unpend(Timer0);
}

/// Unmasks timer 0's interrupt (stopped until the first delay arms it). Call once, after
/// [`crate::rt::start_clock`] and before the first [`AsyncDelay`].
pub fn start_alarm() {
    irq::free(|_| timer_stop());
    // SAFETY: no critical section relies on this line being masked (the wakers are only
    // used inside `interrupt::free`).
    #[allow(unsafe_code)]
    unsafe {
        NVIC::unmask(Timer0)
    };
}

/// Interrupt in `ticks` SysTick ticks (at least 1); replaces the alarm set before, whose
/// interrupt, if pending, is dropped.
fn arm(ticks: u64) {
    let n = u32::try_from(ticks).unwrap_or(u32::MAX).max(1);
    irq::free(|_| {
        timer_stop();
        // Writing RELOAD sets VALUE too.
        timer_write(RELOAD, n);
        timer_write(VALUE, n);
        timer_write(CTRL, CTRL_EN_IRQ);
    });
}

/// Timer 0's interrupt (called by the runtime's `DefaultHandler` for IRQ [`TIMER0_IRQ`]):
/// stops the timer (one shot) and wakes the delay waiting.
pub fn on_timer_interrupt() {
    irq::free(|_| timer_stop());
    ALARM_WAKER.wake();
}

/// `embedded_hal_async::delay::DelayNs` on [`time::ticks`], sleeping until timer 0's alarm.
/// One delay at a time (one alarm): a new delay's poll takes the alarm over.
#[derive(Clone, Copy, Debug, Default)]
pub struct AsyncDelay;

impl embedded_hal_async::delay::DelayNs for AsyncDelay {
    async fn delay_ns(&mut self, ns: u32) {
        let until = time::ticks() + (u64::from(ns) * time::TICK_HZ).div_ceil(1_000_000_000);
        poll_fn(|cx| {
            let now = time::ticks();
            if now >= until {
                return Poll::Ready(());
            }
            ALARM_WAKER.register(cx.waker());
            arm(until - now);
            Poll::Pending
        })
        .await
    }
}

/// Set by every waker of [`block_on`]'s future.
static WOKEN: AtomicBool = AtomicBool::new(false);

fn waker_clone(_: *const ()) -> RawWaker {
    RawWaker::new(core::ptr::null(), &VTABLE)
}

fn waker_wake(_: *const ()) {
    WOKEN.store(true, Ordering::Release);
}

fn waker_drop(_: *const ()) {}

static VTABLE: RawWakerVTable =
    RawWakerVTable::new(waker_clone, waker_wake, waker_wake, waker_drop);

/// Runs `fut` to its end: polls it, and while it is pending and no waker was called since the
/// poll, sleeps with `WFI` (interrupts masked around the check, so a wake between the check
/// and the `WFI` still ends the sleep: a pending interrupt wakes `WFI` even when masked).
pub fn block_on<F: Future>(fut: F) -> F::Output {
    let mut fut = pin!(fut);
    // SAFETY: the vtable's functions ignore the data pointer (null) and only store to an
    // atomic, so the waker is valid from any context and for any lifetime.
    #[allow(unsafe_code)]
    let waker = unsafe { Waker::from_raw(waker_clone(core::ptr::null())) };
    let mut cx = Context::from_waker(&waker);
    loop {
        WOKEN.store(false, Ordering::Release);
        if let Poll::Ready(v) = fut.as_mut().poll(&mut cx) {
            return v;
        }
        irq::free(|_| {
            if !WOKEN.load(Ordering::Acquire) {
                cortex_m::asm::wfi();
            }
        });
    }
}
