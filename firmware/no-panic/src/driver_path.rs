//! The LMS driver path: [`Driver`] over the polled CMSDK UART, with a delay and a clock that
//! read registers and a [`Config`] made of register bits, so the optimiser can assume nothing
//! about the device's replies, the timing or the settings.

use core::convert::Infallible;

use embedded_hal::delay::DelayNs;
use lms2xx::codec::types::{Baud, MeasuringMode, Unit, Variant};
use lms2xx::driver::{Clock, Config, Driver, SetBaud};

use crate::board::{Uart, DATA, STATE, STATE_RX_FULL, STATE_TX_FULL, UART0, UART1};

/// UART0's baud divider register: an opaque source of settings.
const BAUDDIV: usize = 0x10;
/// SysTick's current value register: an opaque clock.
const SYST_CVR: usize = 0xE000_E018;

/// The device UART (UART0) as the driver sees it.
struct Port(Uart);

impl embedded_io::ErrorType for Port {
    type Error = Infallible;
}

impl embedded_io::Read for Port {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Infallible> {
        let mut n = 0;
        for slot in buf.iter_mut() {
            if self.0.reg(STATE) & STATE_RX_FULL == 0 {
                break;
            }
            *slot = self.0.reg(DATA) as u8;
            n += 1;
        }
        Ok(n)
    }
}

impl embedded_io::ReadReady for Port {
    fn read_ready(&mut self) -> Result<bool, Infallible> {
        Ok(self.0.reg(STATE) & STATE_RX_FULL != 0)
    }
}

impl embedded_io::Write for Port {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Infallible> {
        // An opaque short write (0 included), as a HAL may return.
        let n = (self.0.reg(STATE) >> 8) as usize;
        let n = n.min(buf.len());
        for &b in buf.iter().take(n) {
            while self.0.reg(STATE) & STATE_TX_FULL != 0 {}
            self.0.set(DATA, u32::from(b));
        }
        Ok(n)
    }

    fn flush(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
}

impl SetBaud for Port {
    fn set_baud(&mut self, baud: u32) -> Result<(), Infallible> {
        // 25 MHz APB clock, as the mps2-an386 UART expects.
        self.0.set(BAUDDIV, 25_000_000 / baud.max(1));
        Ok(())
    }
}

/// A delay that spins on register reads.
struct Spin;

impl DelayNs for Spin {
    fn delay_ns(&mut self, ns: u32) {
        for _ in 0..ns / 64 {
            let _ = Uart(SYST_CVR).reg(0);
        }
    }
}

/// A millisecond clock read from a register.
struct Ticks;

impl Clock for Ticks {
    fn now_ms(&mut self) -> u32 {
        Uart(SYST_CVR).reg(0)
    }
}

/// A configuration made of the bits of `w`: every field the driver reads is opaque.
fn config(w: u32, v: u32) -> Config {
    let baud = match w & 3 {
        0 => Baud::B9600,
        1 => Baud::B19200,
        2 => Baud::B38400,
        _ => Baud::B500000,
    };
    let variant = Variant {
        angle_deg: (v & 0xFFFF) as u16,
        resolution_cdeg: (v >> 16) as u16,
    };
    let unit = match (w >> 2) & 3 {
        0 => Unit::Cm,
        1 => Unit::Mm,
        _ => Unit::Dm,
    };
    let mut c = Config::default()
        .with_baud(baud)
        .with_variant(variant)
        .with_unit(unit)
        .with_silence_timeout_ms(w >> 4);
    if w & 0x10 != 0 {
        c = c.with_measuring_mode(MeasuringMode((w >> 8) as u8));
    }
    c.reply_timeout_ms = w.rotate_left(7);
    c.config_timeout_ms = w.rotate_left(13);
    c.tries = (w >> 20) as u8;
    c.baud_switch_wait_ms = w.rotate_left(3);
    c.max_reinits_per_call = (w >> 24) as u8;
    c.poll_interval_us = w.rotate_left(17);
    c
}

/// Sends `word` on UART1 (keeps results alive).
fn emit(word: u32) {
    let mut out = Uart(UART1);
    for b in word.to_le_bytes() {
        while out.reg(STATE) & STATE_TX_FULL != 0 {}
        out.set(DATA, u32::from(b));
    }
}

/// Runs the driver's public calls in an order the registers choose, forever.
pub fn run() -> ! {
    let rx = Uart::enable(UART0);
    let w = rx.reg(BAUDDIV);
    let v = Uart(SYST_CVR).reg(0);
    let mut lms = Driver::new(Port(rx), Spin, Ticks, config(w, v));
    loop {
        let op = Uart(UART0).reg(STATE) >> 4;
        let code = match op & 7 {
            0 => lms.init().is_ok() as u32,
            1 => match lms.next_scan() {
                Ok(scan) => {
                    let mut sum = scan.len() as u32 ^ scan.seq;
                    for (i, &c) in scan.codes().iter().enumerate() {
                        sum = sum.wrapping_add(u32::from(c)).rotate_left(1);
                        if let Some(mm) = scan.range_mm(i) {
                            sum ^= mm.to_bits();
                        }
                    }
                    sum
                }
                Err(_) => 1,
            },
            2 => match lms.poll() {
                Ok(Some(scan)) => scan.len() as u32 ^ u32::from(scan.status.0),
                Ok(None) => 2,
                Err(_) => 3,
            },
            3 => lms.stop().is_ok() as u32,
            4 => lms.reset_device().is_ok() as u32,
            _ => {
                let c = lms.counters();
                c.scans ^ c.reinits ^ c.timeouts ^ u32::from(lms.is_streaming())
            }
        };
        emit(code);
    }
}
