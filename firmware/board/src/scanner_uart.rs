//! USART1 to the LMS200 with interrupt-driven, loss-free reception.
//!
//! The LMS200 streams telegrams continuously (up to 500 kBd, 20 µs a byte) while the main
//! loop runs the extractor (~4 ms a scan) and blocks writing feature frames on USART2, so
//! polling the one-byte data register would lose most of a telegram. Instead the USART1 RXNE
//! interrupt drains the data register into the firmware library's receive ring
//! ([`firmware::rx_ring`]: lock-free SPSC, 2047 bytes, 2.8 full telegrams of 732 bytes,
//! 41 ms at 500 kBd; host-tested in `firmware/tests/rx_ring.rs`) and [`ScannerUart`], the
//! driver's side, takes the bytes from it. Sending (the driver's short commands) stays polled.
//!
//! The handler counts what it loses in the ring's counters; reads report new counts once the
//! bytes before them are read: a receive overrun (the handler came too late) as
//! [`UartError::Overrun`] and a full ring (the main loop fell behind) as
//! [`UartError::RingFull`], so the driver returns them and the application logs them;
//! framing, noise and parity errors as a warning only (expected while the driver probes the
//! baud rate; the damaged byte is dropped, so the telegram fails its CRC as it should).
//!
//! Ownership: the handler owns the receiver ([`Rx`]) and the ring's producer end in
//! [`RX_SIDE`]; [`ScannerUart`] owns the transmitter and the consumer end. A baud switch masks
//! USART1 in the NVIC, takes the receiver back, re-creates the serial at the new rate, empties
//! the ring and hands the new receiver to the handler again.

use core::cell::RefCell;

use cortex_m::interrupt::{self as irq, Mutex};
use cortex_m::peripheral::NVIC;
use stm32f4xx_hal::{
    pac::{interrupt, Interrupt, USART1},
    prelude::*,
    rcc::Rcc,
    serial::{self, config::Config as SerialConfig, Rx, Serial, Tx},
};

use firmware::rx_ring::{RxConsumer, RxCounters, RxLoss, RxProducer, RxQueue};
use lms2xx::driver::SetBaud;

/// The handler's half: the receiver and the ring's producer end.
struct RxSide {
    rx: Rx<USART1>,
    ring: RxProducer<'static>,
}

/// Set by [`ScannerUart::new`]; taken back (with USART1 masked) during a baud switch.
static RX_SIDE: Mutex<RefCell<Option<RxSide>>> = Mutex::new(RefCell::new(None));

/// What the receive path lost.
static RX_COUNTERS: RxCounters = RxCounters::new();

/// Runs `f` on [`RX_SIDE`] in a critical section (never panics: nothing else can hold the
/// borrow inside the critical section, and if something did, `f` is not run).
fn with_rx_side<R>(f: impl FnOnce(&mut Option<RxSide>) -> R) -> Option<R> {
    irq::free(|cs| {
        let mut side = RX_SIDE.borrow(cs).try_borrow_mut().ok()?;
        Some(f(&mut side))
    })
}

/// Drains the USART1 data register into the ring (RXNE; with RXNEIE set an overrun raises
/// the interrupt too). Reading the data register clears RXNE and the error flags.
#[interrupt]
fn USART1() {
    use embedded_hal_nb::serial::Read;
    with_rx_side(|side| {
        let Some(RxSide { rx, ring }) = side.as_mut() else {
            return;
        };
        loop {
            match rx.read() {
                Ok(b) => {
                    ring.push(b);
                }
                Err(nb::Error::WouldBlock) => break,
                // The HAL drops the byte still in the data register along with it.
                Err(nb::Error::Other(serial::Error::Overrun)) => ring.overrun(),
                Err(nb::Error::Other(_)) => ring.line_error(),
            }
        }
    });
}

/// Errors of the scanner UART.
#[derive(Debug, defmt::Format)]
pub enum UartError {
    /// Receive overrun: bytes were lost before the interrupt handler read them.
    Overrun,
    /// The receive ring was full: bytes were dropped (the main loop fell behind).
    RingFull,
    /// Framing error (wrong baud rate?).
    Framing,
    /// Parity error.
    Parity,
    /// Line noise.
    Noise,
    /// Another HAL error.
    Other,
    /// The requested baud rate cannot be configured (or an earlier switch failed).
    Baud,
}

impl From<serial::Error> for UartError {
    fn from(e: serial::Error) -> Self {
        match e {
            serial::Error::Overrun => UartError::Overrun,
            serial::Error::FrameFormat => UartError::Framing,
            serial::Error::Parity => UartError::Parity,
            serial::Error::Noise => UartError::Noise,
            _ => UartError::Other,
        }
    }
}

impl From<RxLoss> for UartError {
    fn from(e: RxLoss) -> Self {
        match e {
            RxLoss::Overrun => UartError::Overrun,
            RxLoss::RingFull => UartError::RingFull,
        }
    }
}

impl embedded_io::Error for UartError {
    fn kind(&self) -> embedded_io::ErrorKind {
        embedded_io::ErrorKind::Other
    }
}

/// USART1 as the driver wants it: embedded-io Read/ReadReady/Write and a baud switch.
pub struct ScannerUart {
    /// `None` after a failed baud switch.
    tx: Option<Tx<USART1>>,
    ring: RxConsumer<'static>,
    rcc: Rcc,
}

impl ScannerUart {
    /// Starts interrupt-driven reception on `serial` (USART1). `None` if called twice.
    pub fn new(serial: Serial<USART1>, rcc: Rcc) -> Option<Self> {
        let queue = cortex_m::singleton!(: RxQueue = RxQueue::new())?;
        let (producer, consumer) = queue.split();
        let mut uart = Self {
            tx: None,
            ring: RxConsumer::new(consumer, &RX_COUNTERS),
            rcc,
        };
        uart.start(serial, RxProducer::new(producer, &RX_COUNTERS));
        Some(uart)
    }

    /// Hands the receiver and `producer` to the handler and unmasks USART1.
    fn start(&mut self, serial: Serial<USART1>, producer: RxProducer<'static>) {
        let (tx, mut rx) = serial.split();
        rx.listen();
        self.tx = Some(tx);
        with_rx_side(|side| {
            *side = Some(RxSide { rx, ring: producer });
        });
        // SAFETY: unmasking may end a critical section that relies on USART1 being masked;
        // none does (`RX_SIDE` is only used inside `interrupt::free`, which masks everything).
        #[allow(unsafe_code)]
        unsafe {
            NVIC::unmask(Interrupt::USART1)
        };
    }
}

impl embedded_io::ErrorType for ScannerUart {
    type Error = UartError;
}

impl embedded_io::Read for ScannerUart {
    /// Blocks until a byte is in the ring, then takes what is there (up to `buf.len()`).
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, UartError> {
        if self.tx.is_none() {
            return Err(UartError::Baud);
        }
        if buf.is_empty() {
            return Ok(0);
        }
        // Spin rather than WFI: in sleep the STM32F4 stops HCLK to the debug port unless
        // DBGMCU says otherwise, which stalls defmt over RTT. The driver reads only after
        // `read_ready`, so this hardly ever spins.
        loop {
            match self.ring.read(buf)? {
                0 => core::hint::spin_loop(),
                n => return Ok(n),
            }
        }
    }
}

impl embedded_io::ReadReady for ScannerUart {
    fn read_ready(&mut self) -> Result<bool, UartError> {
        Ok(self.tx.is_some() && self.ring.ready())
    }
}

impl embedded_io::Write for ScannerUart {
    fn write(&mut self, buf: &[u8]) -> Result<usize, UartError> {
        let tx = self.tx.as_mut().ok_or(UartError::Baud)?;
        // The HAL writes what fits in the data register; wait until all is queued.
        let mut rest = buf;
        while !rest.is_empty() {
            let n = embedded_io::Write::write(tx, rest).map_err(UartError::from)?;
            rest = rest.get(n..).unwrap_or(&[]);
        }
        Ok(buf.len())
    }

    fn flush(&mut self) -> Result<(), UartError> {
        let tx = self.tx.as_mut().ok_or(UartError::Baud)?;
        embedded_io::Write::flush(tx).map_err(UartError::from)
    }
}

impl SetBaud for ScannerUart {
    /// Re-creates the serial at `baud`; bytes received at the old rate are discarded.
    fn set_baud(&mut self, baud: u32) -> Result<(), UartError> {
        // Mask first: with RXNEIE still set and the receiver taken away, the handler would
        // be entered again and again.
        NVIC::mask(Interrupt::USART1);
        let side = with_rx_side(Option::take).flatten();
        let (Some(tx), Some(RxSide { rx, ring: producer })) = (self.tx.take(), side) else {
            return Err(UartError::Baud);
        };
        let (usart, (tx_pin, rx_pin)) = tx.join(rx).release();
        let (Some(tx_pin), Some(rx_pin)) = (tx_pin, rx_pin) else {
            return Err(UartError::Baud);
        };
        let cfg = SerialConfig::default().baudrate(baud.bps());
        let serial = Serial::new(usart, (tx_pin, rx_pin), cfg, &mut self.rcc)
            .map_err(|_| UartError::Baud)?;
        // Bytes at the old rate are stale; with the handler masked the consumer may empty
        // the ring.
        self.ring.clear();
        self.start(serial, producer);
        Ok(())
    }
}
