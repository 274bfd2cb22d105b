//! The pfe firmware on QEMU `mps2-an386`: LMS200 on UART0 (received through the UART's
//! interrupt into the firmware's receive ring, as on the board; initialised and streamed by
//! the driver), pfe-core on every scan, one feature frame per scan on UART1
//! (`pfe_frame`), defmt logs on semihosting stdout.
//!
//! Semihosting arguments: `pfe <scans> [paper|default] [baud] [slow_ms] [slow_every] [field
//! resolution]` (`0` or none: run forever; baud 9600/19200/38400/500000, default 38400; the
//! LMS200 variant as field of view in degrees and resolution in 1/100 degree, `100 25` for
//! 100° at 0.25°, default 180° at 0.5°; `paper-nopose` and `default-nopose`: the pose step off,
//! frames without a pose block, as fast as the extraction alone). `slow_ms` makes the
//! extraction artificially slow: a busy-wait of that many ms after every `slow_every`-th
//! scan (default every scan), to test the receive ring (`host-tests/tests/rx_slow_qemu.rs`).
//! At the end it sends `Report::Stack` (painted-stack high-water mark) and `Report::Done`,
//! writes the receive path's account to semihosting stderr (`rx: ring_full=… overruns=…
//! line_errors=… peak=… capacity=… scan_errors=…`), then exits QEMU with 0; 3 = scanner link
//! failed, 4 = output failed, 101 = panic, 102 = fault.
#![cfg_attr(target_os = "none", no_std, no_main)]
#![deny(clippy::indexing_slicing)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("pfe-qemu runs on thumbv7em-none-eabihf under QEMU: cargo xtask demo");
}

#[cfg(target_os = "none")]
mod fw {
    use cortex_m_rt::entry;
    use defmt_semihosting as _;
    use embedded_hal::delay::DelayNs;
    use firmware::app::{AppError, ConfigChoice};
    use firmware_qemu::rt;
    use firmware_qemu::scanner_uart::ScannerUart;
    use firmware_qemu::sys;
    use firmware_qemu::time::{Clock, Delay};
    use firmware_qemu::uart::{Uart, UART1};
    use lms2xx::codec::types::{Baud, Variant};
    use lms2xx::driver::{Config, Driver};

    /// Consecutive failed scans before giving up.
    const MAX_FAILURES: u32 = 5;

    #[entry]
    fn main() -> ! {
        rt::start_clock();
        let scans = sys::arg_u32(0).unwrap_or(0);
        let choice = if sys::arg_is(1, "paper") || sys::arg_is(1, "paper-nopose") {
            ConfigChoice::Paper
        } else {
            ConfigChoice::Default
        };
        let pose = !(sys::arg_is(1, "paper-nopose") || sys::arg_is(1, "default-nopose"));
        let slow_ms = sys::arg_u32(3).unwrap_or(0);
        let slow_every = sys::arg_u32(4).unwrap_or(1).max(1);
        // Room for every LMS200 variant (up to 401 values) and 48 features.
        let Some(app) = rt::take_app() else {
            sys::exit(sys::EXIT_USAGE)
        };
        app.set_choice(choice);
        app.set_pose_step(pose);
        defmt::info!(
            "pfe-qemu: {} scans (0 = forever), config {}, slow {} ms every {} scans",
            scans,
            choice,
            slow_ms,
            slow_every
        );
        let mut out = Uart::new(UART1);
        let baud = sys::arg_u32(2)
            .and_then(Baud::from_bps)
            .unwrap_or(Config::default().baud);
        let Some(scanner) = ScannerUart::new() else {
            sys::exit(sys::EXIT_USAGE)
        };
        let variant = match (sys::arg_u32(5), sys::arg_u32(6)) {
            (Some(field), Some(res)) => match (u16::try_from(field), u16::try_from(res)) {
                (Ok(f), Ok(r)) => Variant::new(f, r),
                _ => sys::exit(sys::EXIT_USAGE),
            },
            _ => Config::default().variant,
        };
        let config = Config::default().with_baud(baud).with_variant(variant);
        let mut lms = Driver::new(scanner, Delay, Clock, config);
        let (mut failures, mut scan_errors) = (0u32, 0u32);
        while scans == 0 || app.seq() < scans {
            match app.step(&mut lms, &mut out) {
                Ok(h) => {
                    failures = 0;
                    defmt::info!(
                        "scan {}: {} valid, {} features, status {}",
                        h.seq,
                        h.valid,
                        h.n_features,
                        h.status
                    );
                    if slow_ms > 0 && h.seq % slow_every == 0 {
                        Delay.delay_ms(slow_ms);
                    }
                }
                Err(AppError::Source(e)) => {
                    failures += 1;
                    scan_errors += 1;
                    defmt::warn!("scanner: {} ({} in a row)", e, failures);
                    if failures >= MAX_FAILURES {
                        sys::exit(sys::EXIT_LINK);
                    }
                }
                Err(_) => sys::exit(sys::EXIT_OUTPUT),
            }
        }
        let _ = lms.stop();
        rt::finish(&mut out, app.seq(), scan_errors)
    }
}
