//! The pfe firmware on an STM32F411 board (WeAct "Black Pill" F411CE, 25 MHz crystal):
//! LMS200 on USART1 (PA9 TX, PA10 RX, through an RS-232/RS-422 transceiver) at the baud the
//! driver asks for, received by interrupt into a ring (`scanner_uart.rs`); one feature frame
//! per scan on USART2 (PA2 TX, PA3 RX) at 460800 baud, defmt logs over RTT, panics reported
//! over defmt (`panic.rs`). The independent watchdog (250 ms) is fed once per main-loop iteration and
//! by the driver's polling delay; the cause of the last reset is logged at start-up
//! (`watchdog.rs`).
//!
//! `cargo run --release` in this directory flashes it with probe-rs (see `.cargo/config.toml`).
#![cfg_attr(target_os = "none", no_std, no_main)]
#![deny(clippy::indexing_slicing)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("pfe-board runs on an STM32F411: cd firmware/board && cargo run --release");
}

#[cfg(target_os = "none")]
mod panic;
#[cfg(target_os = "none")]
mod scanner_uart;
#[cfg(target_os = "none")]
mod watchdog;

#[cfg(target_os = "none")]
mod fw {
    use core::sync::atomic::{AtomicU32, Ordering};

    use cortex_m::peripheral::syst::SystClkSource;
    use cortex_m_rt::{entry, exception};
    use defmt_rtt as _;
    use stm32f4xx_hal::{
        pac,
        prelude::*,
        rcc::Config as RccConfig,
        serial::{config::Config as SerialConfig, Serial},
    };

    use crate::scanner_uart::ScannerUart;
    use crate::watchdog;
    use firmware::app::{AppError, ConfigChoice, LmsApp};
    use lms2xx::driver::{Clock, Config, Driver};

    /// System clock, Hz.
    const SYSCLK_HZ: u32 = 96_000_000;
    /// Feature output baud rate.
    const OUTPUT_BAUD: u32 = 460_800;

    static MILLIS: AtomicU32 = AtomicU32::new(0);

    #[exception]
    fn SysTick() {
        MILLIS.fetch_add(1, Ordering::Relaxed);
    }

    /// Milliseconds from the 1 kHz SysTick.
    struct Millis;
    impl Clock for Millis {
        fn now_ms(&mut self) -> u32 {
            MILLIS.load(Ordering::Relaxed)
        }
    }

    /// Core cycles in `ns` nanoseconds: ⌊ns · 96 / 1000⌋ = ⌊ns · 12 / 125⌋, split at multiples of
    /// 125 ns so it stays in u32 (at most 4.1·10⁸, no overflow) with divisions by a constant (a
    /// multiply each), where the u64 product and division linked a 0.9 KB u64 division routine.
    const fn ns_to_cycles(ns: u32) -> u32 {
        const _: () = assert!(SYSCLK_HZ == 96_000_000);
        ns / 125 * 12 + ns % 125 * 12 / 125
    }

    /// Busy-wait delay counting core cycles; feeds the watchdog (the driver waits through it).
    struct Delay;
    impl embedded_hal::delay::DelayNs for Delay {
        fn delay_ns(&mut self, ns: u32) {
            watchdog::feed();
            cortex_m::asm::delay(ns_to_cycles(ns).max(1));
        }
    }

    #[entry]
    fn main() -> ! {
        let (Some(dp), Some(cp)) = (pac::Peripherals::take(), cortex_m::Peripherals::take()) else {
            defmt::panic!("peripherals taken twice");
        };
        let reset = watchdog::take_reset_cause(&dp.RCC);
        watchdog::start(dp.IWDG, &dp.DBGMCU);
        let mut rcc = dp
            .RCC
            .freeze(RccConfig::hse(25.MHz()).sysclk(SYSCLK_HZ.Hz()));
        let mut syst = cp.SYST;
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(SYSCLK_HZ / 1000 - 1);
        syst.clear_current();
        syst.enable_interrupt();
        syst.enable_counter();

        let gpioa = dp.GPIOA.split(&mut rcc);
        let Ok(mut out) = Serial::new(
            dp.USART2,
            (gpioa.pa2, gpioa.pa3),
            SerialConfig::default().baudrate(OUTPUT_BAUD.bps()),
            &mut rcc,
        ) else {
            defmt::panic!("USART2 configuration");
        };
        // The LMS200 powers up at 9600 baud; the driver probes and switches.
        let Ok(lms_serial) = Serial::new(
            dp.USART1,
            (gpioa.pa9, gpioa.pa10),
            SerialConfig::default().baudrate(9600.bps()),
            &mut rcc,
        ) else {
            defmt::panic!("USART1 configuration");
        };
        let Some(uart) = ScannerUart::new(lms_serial, rcc) else {
            defmt::panic!("scanner UART started twice");
        };
        // Room for every LMS200 variant (up to 401 values) and 48 features.
        let app: &'static mut LmsApp = {
            static mut APP: LmsApp = LmsApp::new(ConfigChoice::Default);
            #[allow(unsafe_code)]
            // SAFETY: the only reference to APP, taken once here.
            unsafe {
                &mut *core::ptr::addr_of_mut!(APP)
            }
        };
        let mut lms = Driver::new(uart, Delay, Millis, Config::default());
        defmt::info!(
            "pfe-board: LMS200 on USART1, features on USART2 at {} baud; last reset: {}",
            OUTPUT_BAUD,
            reset
        );
        loop {
            watchdog::feed();
            // Without the pose step: it costs far more than a scan period on the M4F for now
            // (docs/POSE.md, "On the board"); every scan's features first. The QEMU firmware
            // runs it.
            match app.step_features(&mut lms, &mut out) {
                Ok(h) => defmt::debug!("scan {}: {} features", h.seq, h.n_features),
                Err(AppError::Source(e)) => defmt::warn!("scanner: {}", e),
                Err(_) => defmt::warn!("feature output failed"),
            }
        }
    }
}
