//! Instruction counts of the pose step and of the whole pipeline with it, on `mps2-an386`
//! under QEMU `-icount shift=10` (`cargo xtask bench-mcu` builds and runs it).
//!
//! The scans are built in (`PFE_BENCH_SCANS`: back-to-back B0 telegrams of consecutive scans
//! of a moving robot); `PFE_BENCH_RESET_AT` (optional, comma-separated scan indices) restarts
//! the odometry before those scans (where a new recording starts). Each scan goes through the
//! firmware's `App` (in its `static`) one step at a time, timed with SysTick: decode the
//! telegram, extract, the pose step (registration against the local map and its update),
//! encode the frame. It sends `Report::Timing` frames for the pose step (`Stage::Pose`) and
//! for everything (`Stage::PipelinePose`), then `Report::Stack` and `Report::Done`.
//! Instructions = ticks × 10 / 256 (instruction counts, not cycles).
#![cfg_attr(target_os = "none", no_std, no_main)]
#![deny(clippy::indexing_slicing)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("pfe-bench-pose runs on thumbv7em-none-eabihf under QEMU: cargo xtask bench-mcu");
}

#[cfg(target_os = "none")]
mod fw {
    use cortex_m_rt::entry;
    use defmt_semihosting as _;
    use firmware::app::{RawScan, LMS_READINGS};
    use firmware_qemu::rt::{self, report};
    use firmware_qemu::{
        sys, time,
        uart::{Uart, UART1},
    };
    use lms2xx::codec::frame::{Decoder, Event};
    use lms2xx::codec::reply::{MeasuredValues, ReplyOptions};
    use lms2xx::codec::types::MeasuringMode;
    use pfe_core::ScanGeometry;
    use pfe_frame::{Counters, Report, Stage};

    static SCANS: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/bench_scans.bin"));
    /// Scans before which the odometry restarts (a new recording), comma-separated.
    const RESET_AT: Option<&str> = option_env!("PFE_BENCH_RESET_AT");
    const N: usize = LMS_READINGS;

    /// Discards what it is given (the frame encoder's cost without UART polling).
    struct Sink;
    impl embedded_io::ErrorType for Sink {
        type Error = core::convert::Infallible;
    }
    impl embedded_io::Write for Sink {
        fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
            Ok(core::hint::black_box(buf).len())
        }
        fn flush(&mut self) -> Result<(), Self::Error> {
            Ok(())
        }
    }

    /// Decodes the telegram at the front of `bytes` into `codes`; returns (bytes used, count).
    fn decode(dec: &mut Decoder<812>, bytes: &[u8], codes: &mut [u16; N]) -> (usize, usize) {
        let mut used = 0;
        while let Some(rest) = bytes.get(used..) {
            if rest.is_empty() {
                break;
            }
            let (n, ev) = dec.feed(rest);
            used += n;
            if let Some(Event::Telegram(t)) = ev {
                if let Ok(v) = MeasuredValues::parse(t.payload(), ReplyOptions::default()) {
                    return (used, v.range_codes(MeasuringMode(0), codes));
                }
            }
            if n == 0 {
                break;
            }
        }
        (used, 0)
    }

    fn reset_before(seq: u32) -> bool {
        RESET_AT.is_some_and(|s| s.split(',').any(|v| v.trim().parse() == Ok(seq)))
    }

    #[entry]
    fn main() -> ! {
        rt::start_clock();
        let mut out = Uart::new(UART1);
        if SCANS.is_empty() {
            defmt::error!(
                "no built-in scans: build with PFE_BENCH_SCANS=<file> (cargo xtask bench-mcu)"
            );
            sys::exit(sys::EXIT_USAGE);
        }
        // The firmware's application, as it runs on the board (pose step on).
        let Some(app) = rt::take_app() else {
            sys::exit(sys::EXIT_USAGE)
        };
        let mut dec = Decoder::<812>::new();
        let mut codes = [0u16; N];
        let g = ScanGeometry::LMS200_180_050;
        let mut pos = 0usize;
        let mut seq = 0u32;
        while let Some(rest) = SCANS.get(pos..).filter(|r| !r.is_empty()) {
            if reset_before(seq) {
                app.set_pose_step(false);
                app.set_pose_step(true);
            }
            let t0 = time::ticks();
            let (used, n) = decode(&mut dec, rest, &mut codes);
            if n == 0 {
                break;
            }
            let raw = RawScan::lms_8m(g, codes.get(..n).unwrap_or(&[]), 1.0);
            let header = app.extract(&raw, Counters::default());
            let t1 = time::ticks();
            let pose = core::hint::black_box(app.update_pose());
            let t2 = time::ticks();
            if app.write_frame(&mut Sink, &header, pose.as_ref()).is_err() {
                sys::exit(sys::EXIT_OUTPUT);
            }
            let t3 = time::ticks();
            let points = n as u16;
            for (stage, t) in [(Stage::Pose, t2 - t1), (Stage::PipelinePose, t3 - t0)] {
                let ticks = u32::try_from(t).unwrap_or(u32::MAX);
                report(
                    &mut out,
                    Report::Timing {
                        seq,
                        stage,
                        ticks,
                        points,
                    },
                );
            }
            pos += used;
            seq += 1;
        }
        let (used, size) = sys::stack_usage();
        report(&mut out, Report::Stack { used, size });
        report(&mut out, Report::Done { scans: seq });
        defmt::info!(
            "bench-pose: {} scans, stack {} of {} bytes",
            seq,
            used,
            size
        );
        sys::exit(sys::EXIT_OK)
    }
}
