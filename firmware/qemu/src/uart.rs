//! CMSDK APB UART (ARM's simple UART on the MPS2 boards): polled, or with the receive
//! interrupt ([`crate::scanner_uart`] drains it into the receive ring).
//!
//! Registers: DATA +0x0, STATE +0x4 (bit 0 TX full, bit 1 RX full, bits 2/3 TX/RX overrun,
//! write 1 to clear), CTRL +0x8 (bit 0 TX enable, bit 1 RX enable, bit 3 RX interrupt
//! enable), INTSTATUS +0xC (bit 1 RX, write 1 to clear), BAUDDIV +0x10. Under QEMU the
//! receiver holds one byte and stops reading the host socket until the firmware takes it, so
//! polled reception loses nothing (back-pressure); with the interrupt the handler takes each
//! byte at once and the host's bytes arrive as fast as it sends them.

use core::convert::Infallible;

/// UART0 (the scanner link: `-serial` #1).
pub const UART0: usize = 0x4000_4000;
/// UART1 (feature output: `-serial` #2).
pub const UART1: usize = 0x4000_5000;

/// Register offsets.
#[derive(Clone, Copy)]
#[repr(usize)]
enum Reg {
    Data = 0x0,
    State = 0x4,
    Ctrl = 0x8,
    IntStatus = 0xC,
    BaudDiv = 0x10,
}
/// APB clock of the UARTs on mps2-an386, Hz.
const APB_HZ: u64 = 25_000_000;
const TX_FULL: u32 = 1;
const RX_FULL: u32 = 2;
const RX_OVERRUN: u32 = 8;
/// CTRL: transmitter and receiver enabled.
const CTRL_TX_RX: u32 = 0b11;
/// CTRL: receive interrupt enabled.
const CTRL_RX_INT: u32 = 1 << 3;
/// INTSTATUS: receive interrupt.
const INT_RX: u32 = 2;

/// One CMSDK UART.
pub struct Uart {
    base: usize,
    overruns: u32,
}

impl Uart {
    /// Enables the UART at `base` (`UART0` or `UART1`) for transmit and receive.
    ///
    /// The caller hands over the UART: only one `Uart` per base address may exist.
    pub fn new(base: usize) -> Self {
        let u = Self { base, overruns: 0 };
        // BAUDDIV must be ≥ 16 on the CMSDK UART; the rate itself is not emulated.
        u.write_reg(Reg::BaudDiv, 16);
        u.write_reg(Reg::Ctrl, CTRL_TX_RX);
        u
    }

    /// Another handle on the UART at `base`, already enabled by [`Uart::new`] (writes no
    /// register): to split a UART between an interrupt handler (the receive side) and the
    /// main loop (the transmit side).
    pub fn handle(base: usize) -> Self {
        Self { base, overruns: 0 }
    }

    /// Receive overruns seen (bytes lost by the UART itself; none under QEMU).
    pub fn overruns(&self) -> u32 {
        self.overruns
    }

    /// Raises the receive interrupt (INTSTATUS RX) for every byte received from now on.
    pub fn listen_rx(&mut self) {
        self.write_reg(Reg::Ctrl, CTRL_TX_RX | CTRL_RX_INT);
    }

    /// Acknowledges the receive interrupt. Do it before draining DATA: a byte that arrives
    /// during the drain raises it again instead of being left behind.
    pub fn clear_rx_interrupt(&mut self) {
        self.write_reg(Reg::IntStatus, INT_RX);
    }

    #[allow(unsafe_code)]
    fn read_reg(&self, reg: Reg) -> u32 {
        // SAFETY: `base` is one of the two CMSDK UART blocks of the MPS2 memory map; the
        // registers are 32-bit, aligned, and reads have no side effect except DATA (which
        // takes the received byte, as intended).
        unsafe { core::ptr::read_volatile((self.base + reg as usize) as *const u32) }
    }

    #[allow(unsafe_code)]
    fn write_reg(&self, reg: Reg, v: u32) {
        // SAFETY: as in `read_reg`.
        unsafe { core::ptr::write_volatile((self.base + reg as usize) as *mut u32, v) }
    }

    /// The next received byte, if one is waiting.
    pub fn try_read_byte(&mut self) -> Option<u8> {
        let st = self.read_reg(Reg::State);
        if st & RX_OVERRUN != 0 {
            self.overruns = self.overruns.saturating_add(1);
            self.write_reg(Reg::State, RX_OVERRUN);
        }
        (st & RX_FULL != 0).then(|| self.read_reg(Reg::Data) as u8)
    }

    /// Sends one byte, waiting while the transmitter is full.
    pub fn write_byte(&mut self, b: u8) {
        while self.read_reg(Reg::State) & TX_FULL != 0 {}
        self.write_reg(Reg::Data, u32::from(b));
    }
}

impl embedded_io::ErrorType for Uart {
    type Error = Infallible;
}

impl embedded_io::Read for Uart {
    /// Blocks until at least one byte is there, then takes what is waiting.
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Infallible> {
        if buf.is_empty() {
            return Ok(0);
        }
        let mut n = 0;
        for slot in buf.iter_mut() {
            let b = loop {
                match self.try_read_byte() {
                    Some(b) => break Some(b),
                    None if n > 0 => break None,
                    None => {}
                }
            };
            match b {
                Some(b) => {
                    *slot = b;
                    n += 1;
                }
                None => break,
            }
        }
        Ok(n)
    }
}

impl embedded_io::ReadReady for Uart {
    fn read_ready(&mut self) -> Result<bool, Infallible> {
        Ok(self.read_reg(Reg::State) & RX_FULL != 0)
    }
}

impl embedded_io::Write for Uart {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Infallible> {
        for &b in buf {
            self.write_byte(b);
        }
        Ok(buf.len())
    }

    fn flush(&mut self) -> Result<(), Infallible> {
        while self.read_reg(Reg::State) & TX_FULL != 0 {}
        Ok(())
    }
}

/// QEMU passes BAUDDIV on to a tty backend (`-serial /dev/pts/N`), so the emulated LMS200
/// on a pty sees the rate the firmware chose; on a TCP backend it has no effect.
impl lms2xx::driver::SetBaud for Uart {
    fn set_baud(&mut self, baud: u32) -> Result<(), Infallible> {
        self.write_reg(Reg::BaudDiv, bauddiv(baud));
        Ok(())
    }
}

/// BAUDDIV for `bps` at the 25 MHz APB clock, as QEMU's tty backend reads it: it takes
/// `clock / BAUDDIV`, scales it by 10/11 and rounds up to the next standard rate, so this is
/// the smallest divisor whose scaled rate does not exceed `bps` (≥ 16, the hardware minimum).
pub const fn bauddiv(bps: u32) -> u32 {
    let bps = if bps == 0 { 1 } else { bps as u64 };
    let d = (APB_HZ * 10).div_ceil(11 * bps);
    if d < 16 {
        16
    } else if d > u32::MAX as u64 {
        u32::MAX
    } else {
        d as u32
    }
}
