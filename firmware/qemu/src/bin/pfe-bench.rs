//! Instruction counts of the pipeline on `mps2-an386` under QEMU `-icount shift=10`
//! (`cargo xtask bench-mcu` builds and runs it).
//!
//! The scans are built in (`PFE_BENCH_SCANS`: back-to-back B0 telegrams from the simulator).
//! For every scan it measures, with SysTick, decoding the telegram, pfe-core `paper`, pfe-core
//! `default`, and the whole pipeline (telegram bytes → features → encoded frame), and sends
//! one `Report::Timing` frame per measurement on UART1, then `Report::Stack` and
//! `Report::Done`. Instructions = ticks × 10 / 256 (instruction counts, not cycles).
#![cfg_attr(target_os = "none", no_std, no_main)]
#![deny(clippy::indexing_slicing)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("pfe-bench runs on thumbv7em-none-eabihf under QEMU: cargo xtask bench-mcu");
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
    use pfe_core::{Config, ExtractError, ScanGeometry};
    use pfe_frame::{Counters, Report, Stage};

    static SCANS: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/bench_scans.bin"));
    /// Values a telegram may hold (the bench's scans have 361).
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
        // The firmware's extractor and application (the scans have 361 values).
        let (Some(ex), Some(app)) = (rt::take_extractor(), rt::take_app()) else {
            sys::exit(sys::EXIT_USAGE)
        };
        // The pipeline without the pose step (pfe-bench-pose measures it with).
        app.set_pose_step(false);
        let mut dec = Decoder::<812>::new();
        let mut codes = [0u16; N];
        let g = ScanGeometry::LMS200_180_050;
        let (paper, default) = (Config::paper(), Config::default_config());
        let mut pos = 0usize;
        let mut seq = 0u32;
        while let Some(rest) = SCANS.get(pos..).filter(|r| !r.is_empty()) {
            // Decode.
            let t0 = time::ticks();
            let (used, n) = decode(&mut dec, rest, &mut codes);
            let t_dec = time::ticks() - t0;
            if n == 0 {
                break;
            }
            let values = codes.get(..n).unwrap_or(&[]);
            let scan = RawScan::lms_8m(g, values, 1.0).to_pfe();
            let t0 = time::ticks();
            let r_paper = core::hint::black_box(ex.extract(&scan, &paper));
            let t_paper = time::ticks() - t0;
            let t0 = time::ticks();
            let r_default = core::hint::black_box(ex.extract(&scan, &default));
            let t_default = time::ticks() - t0;
            // An extraction refused outright measures nothing (a full feature buffer is fine).
            for r in [r_paper, r_default] {
                if let Err(
                    ExtractError::InvalidConfig
                    | ExtractError::InvalidGeometry
                    | ExtractError::TooManyReadings { .. },
                ) = r
                {
                    defmt::error!("bench: an extraction was refused");
                    sys::exit(sys::EXIT_USAGE);
                }
            }
            // Whole pipeline: bytes → codes → features → frame.
            let t0 = time::ticks();
            let (_, n2) = decode(&mut dec, rest, &mut codes);
            let raw = RawScan::lms_8m(g, codes.get(..n2).unwrap_or(&[]), 1.0);
            let r = app.process(&raw, Counters::default(), &mut Sink);
            let t_pipe = time::ticks() - t0;
            if r.is_err() {
                sys::exit(sys::EXIT_OUTPUT);
            }
            let points = n as u16;
            for (stage, t) in [
                (Stage::Decode, t_dec),
                (Stage::ExtractPaper, t_paper),
                (Stage::ExtractDefault, t_default),
                (Stage::Pipeline, t_pipe),
            ] {
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
        defmt::info!("bench: {} scans, stack {} of {} bytes", seq, used, size);
        sys::exit(sys::EXIT_OK)
    }
}
