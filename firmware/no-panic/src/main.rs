//! The scan path and the LMS driver with a panic handler that cannot link.
//!
//! Two paths, chosen at run time by an opaque register read so neither is optimised away.
//! The scan path: bytes arrive from UART0 (read with volatile loads, so the optimiser knows nothing about
//! them) → [`Decoder`] → [`parse_reply`] → range codes → [`App::process`] with
//! `Config::paper()` and with `Config::default()` (pfe-core extraction, then the output frame
//! streamed to UART1). The driver path ([`driver_path`]): [`lms2xx::driver::Driver`] over
//! the same UART with a delay and a clock read from registers and a [`lms2xx::driver::Config`]
//! made of register bits, through `init` (baud probe, baud switch, configuration), `next_scan`
//! (re-initialisation on silence or reset), `poll`, `stop` and `reset_device`. The
//! `#[panic_handler]` calls `__pfe_panic_path_survived`, a symbol
//! defined nowhere: if any panic (bounds check, `unwrap`, overflow check, division by zero,
//! `copy_from_slice` length mismatch, …) is still reachable after optimisation, the link fails
//! with "undefined symbol: __pfe_panic_path_survived". `cargo xtask no-panic` builds it and,
//! on failure, rebuilds with `--features probe` and lists where the surviving panics are.
//!
//! The release profile here is the shipped firmware's plus `overflow-checks = true` when
//! xtask asks for it (`--overflow-checks`), which proves arithmetic cannot overflow either.
#![cfg_attr(target_os = "none", no_std, no_main)]
#![deny(unsafe_code)]

#[cfg(target_os = "none")]
mod driver_path;

#[cfg(target_os = "none")]
mod board {
    use core::convert::Infallible;

    use firmware::app::{App, ConfigChoice, RawScan};
    use lms2xx::codec::frame::MAX_TELEGRAM;
    use lms2xx::codec::frame::{Decoder, Event};
    use lms2xx::codec::reply::{parse_reply, Reply, ReplyOptions};
    use lms2xx::codec::types::MeasuringMode;
    use pfe_core::ScanGeometry;
    use pfe_frame::Counters;

    /// Most values in one B0 telegram (100° at 0.25°).
    const VALUES: usize = 401;
    /// Features per scan.
    const FEATURES: usize = 48;

    pub(crate) const UART0: usize = 0x4000_4000;
    pub(crate) const UART1: usize = 0x4000_5000;
    pub(crate) const DATA: usize = 0x0;
    pub(crate) const STATE: usize = 0x4;
    const CTRL: usize = 0x8;
    pub(crate) const STATE_TX_FULL: u32 = 1;
    pub(crate) const STATE_RX_FULL: u32 = 2;

    /// A CMSDK APB UART (QEMU mps2-an386), polled.
    pub(crate) struct Uart(pub(crate) usize);

    impl Uart {
        #[allow(unsafe_code)]
        pub(crate) fn reg(&self, off: usize) -> u32 {
            // SAFETY: a device register of the CMSDK UART at a fixed address.
            unsafe { core::ptr::read_volatile((self.0 + off) as *const u32) }
        }

        #[allow(unsafe_code)]
        pub(crate) fn set(&mut self, off: usize, v: u32) {
            // SAFETY: as above.
            unsafe { core::ptr::write_volatile((self.0 + off) as *mut u32, v) }
        }

        pub(crate) fn enable(base: usize) -> Self {
            let mut u = Uart(base);
            u.set(CTRL, 0b11);
            u
        }

        /// Reads what has arrived, at least one byte, into `buf`.
        fn read_some(&mut self, buf: &mut [u8]) -> usize {
            let mut n = 0;
            for slot in buf.iter_mut() {
                while n == 0 && self.reg(STATE) & STATE_RX_FULL == 0 {}
                if self.reg(STATE) & STATE_RX_FULL == 0 {
                    break;
                }
                *slot = self.reg(DATA) as u8;
                n += 1;
            }
            n
        }
    }

    impl embedded_io::ErrorType for Uart {
        type Error = Infallible;
    }

    impl embedded_io::Write for Uart {
        fn write(&mut self, buf: &[u8]) -> Result<usize, Infallible> {
            for &b in buf {
                while self.reg(STATE) & STATE_TX_FULL != 0 {}
                self.set(DATA, u32::from(b));
            }
            Ok(buf.len())
        }

        fn flush(&mut self) -> Result<(), Infallible> {
            Ok(())
        }
    }

    /// The LMS200 variants, by the number of values in a full scan.
    fn geometry(n: usize) -> Option<ScanGeometry> {
        let (field, res) = match n {
            181 => (180.0, 1.0),
            361 => (180.0, 0.5),
            101 => (100.0, 1.0),
            201 => (100.0, 0.5),
            401 => (100.0, 0.25),
            _ => return None,
        };
        Some(ScanGeometry::lms200(field, res))
    }

    #[cortex_m_rt::entry]
    fn main() -> ! {
        static mut DECODER: Decoder<MAX_TELEGRAM> = Decoder::new();
        static mut PAPER: App<VALUES, FEATURES> = App::new(ConfigChoice::Paper);
        static mut DEFAULT: App<VALUES, FEATURES> = App::new(ConfigChoice::Default);
        static mut PAYLOAD: [u8; MAX_TELEGRAM] = [0; MAX_TELEGRAM];
        static mut CODES: [u16; VALUES] = [0; VALUES];

        // An opaque choice (a register's bit), so both paths stay in the binary.
        if Uart(UART0).reg(CTRL) & 0x100 != 0 {
            crate::driver_path::run();
        }
        // The scan path: UART bytes → decoder → reply → pfe-core (both configurations) →
        // output frames.

        let mut rx = Uart::enable(UART0);
        let mut tx = Uart::enable(UART1);
        let mut chunk = [0u8; 64];
        let mut reinits = 0u32;
        loop {
            let n = rx.read_some(&mut chunk);
            let mut rest = chunk.get(..n).unwrap_or(&[]);
            loop {
                let (used, event) = DECODER.feed(rest);
                rest = rest.get(used..).unwrap_or(&[]);
                // Copy the payload out so the decoder's counters can be read below.
                let len = match event {
                    None => break,
                    Some(Event::Telegram(t)) => {
                        let p = t.payload();
                        match PAYLOAD.get_mut(..p.len()) {
                            Some(dst) => {
                                dst.copy_from_slice(p);
                                p.len()
                            }
                            None => 0,
                        }
                    }
                    Some(Event::Nak) => {
                        reinits = reinits.wrapping_add(1);
                        0
                    }
                    Some(Event::Ack) => 0,
                };
                let stats = DECODER.stats();
                let counters = Counters {
                    telegrams_ok: stats.telegrams,
                    crc_dropped: stats.crc_errors,
                    bytes_skipped: stats.bytes_skipped,
                    reinits,
                };
                let payload = PAYLOAD.get(..len).unwrap_or(&[]);
                let Ok(reply) = parse_reply(payload, ReplyOptions::default()) else {
                    continue;
                };
                let Reply::Values(values) = reply.reply else {
                    continue;
                };
                let Some(unit) = values.unit() else { continue };
                let k = values.range_codes(MeasuringMode::M8_FIELDS_AB_DAZZLE, CODES);
                let Some(geometry) = geometry(k) else {
                    continue;
                };
                let codes = CODES.get(..k).unwrap_or(&[]);
                let scan = RawScan::lms_8m(geometry, codes, unit.mm_per_unit());
                // Errors of an infallible writer cannot happen; extraction errors are in the frame.
                let _ = PAPER.process(&scan, counters, &mut tx);
                let _ = DEFAULT.process(&scan, counters, &mut tx);
            }
        }
    }

    #[cfg(not(feature = "probe"))]
    #[panic_handler]
    fn panic(_: &core::panic::PanicInfo<'_>) -> ! {
        extern "C" {
            /// Defined nowhere: referencing it makes the link fail.
            fn __pfe_panic_path_survived() -> !;
        }
        #[allow(unsafe_code)]
        // SAFETY: never executed; the link fails while this call is reachable.
        unsafe {
            __pfe_panic_path_survived()
        }
    }

    #[cfg(feature = "probe")]
    #[panic_handler]
    fn panic(_: &core::panic::PanicInfo<'_>) -> ! {
        loop {
            core::hint::spin_loop();
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("pfe-no-panic is a thumbv7em-none-eabihf firmware: run `cargo xtask no-panic`");
}
