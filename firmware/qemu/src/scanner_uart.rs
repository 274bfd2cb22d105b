//! UART0 to the LMS200 with interrupt-driven reception: the board's receive path on QEMU.
//!
//! The CMSDK UART's receive interrupt drains the data register into the firmware library's
//! receive ring ([`firmware::rx_ring`], the ring type and loss counters the board's USART1
//! uses) and [`ScannerUart`], the driver's side, takes the bytes from it, so the QEMU soak
//! and demo run the code the board runs. Sending (the driver's short commands) stays polled.
//!
//! Under QEMU the handler empties the one-byte receiver at once, so the host's bytes arrive
//! as fast as it sends them and a main loop that falls behind by more than the ring fills it:
//! the bytes dropped are counted ([`rx_counters`]) and the driver's next read reports the loss
//! once ([`RxLoss`]); its decoder resyncs on the next telegram.
//!
//! Ownership: the handler owns the receive side of UART0 (its own [`Uart`] handle: DATA
//! reads, STATE overrun and INTSTATUS acknowledgement) and the ring's producer end in
//! `RX_SIDE`; [`ScannerUart`] owns the transmit side and BAUDDIV and the consumer end.

use core::cell::RefCell;

use cortex_m::interrupt::{self as irq, InterruptNumber, Mutex};
use cortex_m::peripheral::NVIC;
use firmware::rx_ring::{RxConsumer, RxCounters, RxLoss, RxProducer, RxQueue};
use lms2xx::driver::SetBaud;

use crate::uart::{Uart, UART0};

/// NVIC line of UART0's receive interrupt on `mps2-an386`: QEMU's `hw/arm/mps2.c` wires the
/// CMSDK UARTs' RX interrupts to IRQ 0, 2, 4, 18, 20 (TX to the next line up, the overrun
/// interrupts of UART0–2 together to IRQ 12).
pub const UART0_RX_IRQ: u16 = 0;

/// UART0's receive interrupt, for the NVIC.
#[derive(Clone, Copy, Debug)]
struct Uart0Rx;

// SAFETY: `number` is a device interrupt line of mps2-an386 (see `UART0_RX_IRQ`).
#[allow(unsafe_code)]
unsafe impl InterruptNumber for Uart0Rx {
    fn number(self) -> u16 {
        UART0_RX_IRQ
    }
}

/// The handler's half: UART0's receiver and the ring's producer end.
struct RxSide {
    uart: Uart,
    ring: RxProducer<'static>,
}

/// Set by [`ScannerUart::new`].
static RX_SIDE: Mutex<RefCell<Option<RxSide>>> = Mutex::new(RefCell::new(None));

/// What the receive path lost.
static RX_COUNTERS: RxCounters = RxCounters::new();

/// The receive path's loss counters and backlog high-water mark.
pub fn rx_counters() -> &'static RxCounters {
    &RX_COUNTERS
}

/// UART0's receive interrupt (called by the runtime's `DefaultHandler` for IRQ
/// [`UART0_RX_IRQ`]): acknowledges it, then moves every waiting byte into the ring.
pub fn on_rx_interrupt() {
    irq::free(|cs| {
        let Ok(mut side) = RX_SIDE.borrow(cs).try_borrow_mut() else {
            return;
        };
        let Some(RxSide { uart, ring }) = side.as_mut() else {
            return;
        };
        let overruns = uart.overruns();
        uart.clear_rx_interrupt();
        while let Some(b) = uart.try_read_byte() {
            ring.push(b);
        }
        for _ in overruns..uart.overruns() {
            ring.overrun();
        }
    });
}

/// UART0 as the driver wants it: embedded-io Read/ReadReady/Write over the receive ring, and
/// the baud switch.
pub struct ScannerUart {
    tx: Uart,
    ring: RxConsumer<'static>,
}

impl ScannerUart {
    /// Enables UART0, hands its receiver to the interrupt handler and unmasks the interrupt.
    /// `None` if called twice.
    pub fn new() -> Option<Self> {
        let queue = cortex_m::singleton!(: RxQueue = RxQueue::new())?;
        let (producer, consumer) = queue.split();
        let tx = Uart::new(UART0);
        let mut rx = Uart::handle(UART0);
        rx.listen_rx();
        irq::free(|cs| {
            *RX_SIDE.borrow(cs).borrow_mut() = Some(RxSide {
                uart: rx,
                ring: RxProducer::new(producer, &RX_COUNTERS),
            });
        });
        // SAFETY: no critical section relies on this line being masked (`RX_SIDE` is only
        // used inside `interrupt::free`).
        #[allow(unsafe_code)]
        unsafe {
            NVIC::unmask(Uart0Rx)
        };
        Some(Self {
            tx,
            ring: RxConsumer::new(consumer, &RX_COUNTERS),
        })
    }
}

impl embedded_io::ErrorType for ScannerUart {
    type Error = RxLoss;
}

impl embedded_io::Read for ScannerUart {
    /// Blocks until a byte is in the ring, then takes what is there (up to `buf.len()`).
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, RxLoss> {
        self.ring.read_blocking(buf)
    }
}

impl embedded_io::ReadReady for ScannerUart {
    fn read_ready(&mut self) -> Result<bool, RxLoss> {
        Ok(self.ring.ready())
    }
}

impl embedded_io::Write for ScannerUart {
    fn write(&mut self, buf: &[u8]) -> Result<usize, RxLoss> {
        for &b in buf {
            self.tx.write_byte(b);
        }
        Ok(buf.len())
    }

    fn flush(&mut self) -> Result<(), RxLoss> {
        let Ok(()) = embedded_io::Write::flush(&mut self.tx);
        Ok(())
    }
}

impl SetBaud for ScannerUart {
    /// Sets BAUDDIV (see [`crate::uart::bauddiv`]); bytes received at the old rate are
    /// discarded.
    fn set_baud(&mut self, baud: u32) -> Result<(), RxLoss> {
        NVIC::mask(Uart0Rx);
        let Ok(()) = self.tx.set_baud(baud);
        // With the handler masked the consumer may empty the ring.
        self.ring.clear();
        // SAFETY: as in `ScannerUart::new`.
        #[allow(unsafe_code)]
        unsafe {
            NVIC::unmask(Uart0Rx)
        };
        Ok(())
    }
}
