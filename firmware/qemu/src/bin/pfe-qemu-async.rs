//! The pfe firmware's async path on QEMU `mps2-an386` (feature `async`): lms2xx's
//! [`AsyncDriver`](lms2xx::driver::AsyncDriver) on UART0 (awaiting the receive ring the UART's
//! interrupt fills, as `pfe-qemu` reads it), its delays on timer 0's interrupt, run by
//! [`block_on`](firmware_qemu::asynch::block_on) (one future, `WFI` between polls);
//! pfe-core on every scan through the same `App::process` and frame encoder, one feature frame
//! per scan on UART1, defmt logs on semihosting stdout.
//!
//! Semihosting arguments, reports, stderr account and exit codes as `pfe-qemu`'s:
//! `pfe <scans> [paper|default|paper-nopose|default-nopose] [baud] [slow_ms] [slow_every]`
//! (`slow_ms`: an awaited delay after every `slow_every`-th scan; `*-nopose`: the pose step off,
//! as the embassy firmware runs); the end sends `Report::Stack` and `Report::Done`, writes
//! `rx: …` to stderr and exits 0; 3 = scanner link failed, 4 = output failed, 101 = panic,
//! 102 = fault. `host-tests/tests/e2e_qemu_async.rs` checks its frames against `pfe-qemu`'s.
#![cfg_attr(target_os = "none", no_std, no_main)]
#![deny(clippy::indexing_slicing)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!(
        "pfe-qemu-async runs on thumbv7em-none-eabihf under QEMU (host-tests' e2e_qemu_async)"
    );
}

#[cfg(target_os = "none")]
mod fw {
    use cortex_m_rt::entry;
    use defmt_semihosting as _;
    use embedded_hal_async::delay::DelayNs;
    use firmware::app::{link_counters, ConfigChoice, LmsApp, ScanDataExt};
    use firmware_qemu::asynch::{self, AsyncDelay, AsyncScanner};
    use firmware_qemu::time::Clock;
    use firmware_qemu::uart::{Uart, UART1};
    use firmware_qemu::{rt, sys};
    use lms2xx::codec::types::Baud;
    use lms2xx::driver::{AsyncDriver, Config};

    /// Consecutive failed scans before giving up.
    const MAX_FAILURES: u32 = 5;

    /// What `main` read from the semihosting arguments.
    struct Args {
        scans: u32,
        slow_ms: u32,
        slow_every: u32,
    }

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
        let args = Args {
            scans,
            slow_ms: sys::arg_u32(3).unwrap_or(0),
            slow_every: sys::arg_u32(4).unwrap_or(1).max(1),
        };
        let Some(app) = rt::take_app() else {
            sys::exit(sys::EXIT_USAGE)
        };
        app.set_choice(choice);
        app.set_pose_step(pose);
        defmt::info!(
            "pfe-qemu-async: {} scans (0 = forever), config {}, slow {} ms every {} scans",
            args.scans,
            choice,
            args.slow_ms,
            args.slow_every
        );
        let out = Uart::new(UART1);
        let baud = sys::arg_u32(2)
            .and_then(Baud::from_bps)
            .unwrap_or(Config::default().baud);
        let Some(scanner) = AsyncScanner::new() else {
            sys::exit(sys::EXIT_USAGE)
        };
        asynch::start_alarm();
        // In this frame, the future holding a reference: an async fn keeps a by-value
        // argument twice (the argument and its binding), which took 6 KiB of stack here.
        let mut lms = AsyncDriver::new(
            scanner,
            AsyncDelay,
            Clock,
            Config::default().with_baud(baud),
        );
        asynch::block_on(run(app, &mut lms, out, args))
    }

    /// `pfe-qemu`'s loop, awaiting the scans.
    async fn run(
        app: &'static mut LmsApp,
        lms: &mut AsyncDriver<AsyncScanner, AsyncDelay, Clock>,
        mut out: Uart,
        args: Args,
    ) -> ! {
        let (mut failures, mut scan_errors) = (0u32, 0u32);
        while args.scans == 0 || app.seq() < args.scans {
            if let Err(e) = lms.next_scan().await {
                failures += 1;
                scan_errors += 1;
                defmt::warn!("scanner: {} ({} in a row)", e, failures);
                if failures >= MAX_FAILURES {
                    sys::exit(sys::EXIT_LINK);
                }
                continue;
            }
            failures = 0;
            let counters = link_counters(&lms.counters());
            let Ok(h) = app.process(&lms.last_scan().raw(), counters, &mut out) else {
                sys::exit(sys::EXIT_OUTPUT)
            };
            defmt::info!(
                "scan {}: {} valid, {} features, status {}",
                h.seq,
                h.valid,
                h.n_features,
                h.status
            );
            if args.slow_ms > 0 && h.seq % args.slow_every == 0 {
                AsyncDelay.delay_ms(args.slow_ms).await;
            }
        }
        let _ = lms.stop().await;
        rt::finish(&mut out, app.seq(), scan_errors)
    }
}
