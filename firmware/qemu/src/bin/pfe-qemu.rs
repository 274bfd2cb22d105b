//! The pfe firmware on QEMU `mps2-an386`: LMS200 on UART0 (initialised and streamed by the
//! driver), pfe-core on every scan, one feature frame per scan on UART1
//! (`firmware::output`), defmt logs on semihosting stdout.
//!
//! Semihosting arguments: `pfe <scans> [paper|default] [baud]` (`0` or none: run forever;
//! baud 9600/19200/38400/500000, default 38400). At the
//! end it sends `Report::Stack` (painted-stack high-water mark) and `Report::Done`, then
//! exits QEMU with 0; 3 = scanner link failed, 4 = output failed, 101 = panic, 102 = fault.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("pfe-qemu runs on thumbv7em-none-eabihf under QEMU: cargo xtask demo");
}

#[cfg(target_os = "none")]
mod fw {
    use cortex_m_rt::entry;
    use defmt_semihosting as _;
    use firmware::app::{AppError, ConfigChoice};
    use firmware::lms::types::Baud;
    use firmware::lms::{Config, Driver};
    use firmware::output::{self, Report};
    use firmware_qemu::time::{self, Clock, Delay};
    use firmware_qemu::uart::{Uart, UART0, UART1};
    use firmware_qemu::{rt, sys};

    /// Consecutive failed scans before giving up.
    const MAX_FAILURES: u32 = 5;

    fn report(out: &mut Uart, r: Report) {
        if output::write_report(out, &r).is_err() {
            sys::exit(sys::EXIT_OUTPUT);
        }
    }

    #[entry]
    fn main() -> ! {
        let Some(cp) = cortex_m::Peripherals::take() else {
            sys::exit(sys::EXIT_USAGE)
        };
        time::start(cp.SYST);
        let scans = sys::arg_u32(0).unwrap_or(0);
        let choice = if sys::arg_is(1, "paper") {
            ConfigChoice::Paper
        } else {
            ConfigChoice::Default
        };
        // Room for every LMS200 variant (up to 401 values) and 48 features.
        let Some(app) = rt::take_app() else {
            sys::exit(sys::EXIT_USAGE)
        };
        app.set_choice(choice);
        defmt::info!("pfe-qemu: {} scans (0 = forever), config {}", scans, choice);
        let mut out = Uart::new(UART1);
        let baud = sys::arg_u32(2)
            .and_then(Baud::from_bps)
            .unwrap_or(Config::default().baud);
        let mut lms = Driver::new(
            Uart::new(UART0),
            Delay,
            Clock,
            Config::default().with_baud(baud),
        );
        let mut failures = 0u32;
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
                }
                Err(AppError::Source(e)) => {
                    failures += 1;
                    defmt::warn!("scanner: {} ({} in a row)", e, failures);
                    if failures >= MAX_FAILURES {
                        sys::exit(sys::EXIT_LINK);
                    }
                }
                Err(_) => sys::exit(sys::EXIT_OUTPUT),
            }
        }
        let _ = lms.stop();
        let (used, size) = sys::stack_usage();
        defmt::info!("done: stack high-water mark {} of {} bytes", used, size);
        report(&mut out, Report::Stack { used, size });
        report(&mut out, Report::Done { scans: app.seq() });
        sys::exit(sys::EXIT_OK)
    }
}
