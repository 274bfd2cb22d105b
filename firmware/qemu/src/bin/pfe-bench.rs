//! Instruction counts of the pipeline on `mps2-an386` under QEMU `-icount shift=10`
//! (`cargo xtask bench-mcu` builds and runs it).
//!
//! The scans are built in (`PFE_BENCH_SCANS`: back-to-back B0 telegrams). Each scan is
//! extracted as the firmware does (`RawScan::to_pfe`: the variant from the value count, the unit
//! from the telegram, the sweeps and grid from them; `ConfigChoice`'s configurations, everything
//! on). For every scan it measures, with SysTick, decoding the telegram, pfe-core `paper`,
//! building the scan from the codes (`RawScan::to_pfe`), pfe-core `default` step by step
//! (pfe-core's `probe`: load, scatter, mark, sweeps, check, segments, reach, sift), encoding
//! the frame, and the whole
//! pipeline (telegram bytes → features → encoded frame, without the probe), and sends one
//! `Report::Timing` frame per measurement on UART1, then `Report::Stack` and `Report::Done`.
//! Instructions = ticks × 10 / 256 (instruction counts, not cycles).
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
    use firmware::app::{ConfigChoice, RawScan, LMS_READINGS};
    use firmware_qemu::rt::{self, report};
    use firmware_qemu::{
        sys, time,
        uart::{Uart, UART1},
    };
    use lms2xx::codec::frame::{Decoder, Event};
    use lms2xx::codec::reply::{MeasuredValues, ReplyOptions};
    use lms2xx::codec::types::{MeasuringMode, Unit, Variant};
    use pfe_core::Stage as Step;
    use pfe_core::{ExtractError, ScanGeometry};
    use pfe_frame::{Counters, Report, ScanHeader, ScanStatus, Stage};

    static SCANS: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/bench_scans.bin"));
    /// Values a telegram may hold (every LMS200 variant).
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

    /// A decoded telegram: its value count and mm per code.
    struct Decoded {
        used: usize,
        n: usize,
        mm_per_unit: f32,
    }

    /// Decodes the telegram at the front of `bytes` into `codes`.
    fn decode(dec: &mut Decoder<812>, bytes: &[u8], codes: &mut [u16; N]) -> Decoded {
        let mut used = 0;
        while let Some(rest) = bytes.get(used..) {
            if rest.is_empty() {
                break;
            }
            let (n, ev) = dec.feed(rest);
            used += n;
            if let Some(Event::Telegram(t)) = ev {
                if let Ok(v) = MeasuredValues::parse(t.payload(), ReplyOptions::default()) {
                    let mm_per_unit = v.unit().unwrap_or(Unit::Mm).mm_per_unit();
                    let n = v.range_codes(MeasuringMode(0), codes);
                    return Decoded {
                        used,
                        n,
                        mm_per_unit,
                    };
                }
            }
            if n == 0 {
                break;
            }
        }
        Decoded {
            used,
            n: 0,
            mm_per_unit: 1.0,
        }
    }

    /// The geometry of a scan of `n` values in `mm_per_unit` (as the driver's `ScanData`
    /// gives it: the variant's field and resolution, the range of the measuring mode).
    fn geometry(n: usize, mm_per_unit: f32) -> ScanGeometry {
        let v = Variant::from_values(n).unwrap_or(Variant::A180_R050);
        let mut g = ScanGeometry::lms200(f32::from(v.angle_deg), v.resolution_deg());
        g.r_max = f32::from(MeasuringMode::M8_FIELDS_AB_DAZZLE.max_valid()) * mm_per_unit;
        g
    }

    /// The probe's steps in the order they report, as timing stages.
    /// pfe-core's stage observer as a closure.
    struct Ticks<F: FnMut(Step)>(F);

    impl<F: FnMut(Step)> pfe_core::StageObserver for Ticks<F> {
        fn ended(&mut self, stage: Step) {
            (self.0)(stage)
        }
    }

    const STEPS: [(Step, Stage); 8] = [
        (Step::Load, Stage::Load),
        (Step::Scatter, Stage::Scatter),
        (Step::Mark, Stage::Mark),
        (Step::Sweeps, Stage::Sweeps),
        (Step::Check, Stage::Check),
        (Step::Segments, Stage::Segments),
        (Step::Reach, Stage::Reach),
        (Step::Sift, Stage::Sift),
    ];

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
        let (paper, default) = (ConfigChoice::Paper.config(), ConfigChoice::Default.config());
        let mut pos = 0usize;
        let mut seq = 0u32;
        while let Some(rest) = SCANS.get(pos..).filter(|r| !r.is_empty()) {
            // Decode.
            let t0 = time::ticks();
            let d = decode(&mut dec, rest, &mut codes);
            let t_dec = time::ticks() - t0;
            if d.n == 0 {
                break;
            }
            let g = geometry(d.n, d.mm_per_unit);
            let values = codes.get(..d.n).unwrap_or(&[]);
            let raw = RawScan::lms_8m(g, values, d.mm_per_unit);
            let t0 = time::ticks();
            let r_paper = core::hint::black_box(ex.extract(&raw.to_pfe(), &paper));
            let t_paper = time::ticks() - t0;
            // The default extraction step by step: each step's ticks since the one before.
            let mut steps = [0u64; STEPS.len()];
            let t0 = time::ticks();
            let scan = raw.to_pfe();
            let t_scan = time::ticks() - t0;
            let mut last = time::ticks();
            let mut observer = Ticks(|s: Step| {
                let now = time::ticks();
                if let Some(k) = STEPS.iter().position(|(step, _)| *step == s) {
                    if let Some(t) = steps.get_mut(k) {
                        *t = now - last;
                    }
                }
                last = now;
            });
            let r_default =
                core::hint::black_box(ex.extract_observed(&scan, &default, &mut observer));
            let t_default = time::ticks() - t0;
            // An extraction refused outright measures nothing (a full feature buffer is fine).
            for r in [&r_paper, &r_default] {
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
            // The output frame of these features.
            let stats = ex.stats();
            let sat = |v: usize| u16::try_from(v).unwrap_or(u16::MAX);
            let header = ScanHeader {
                seq,
                time_ms: 0,
                counters: Counters::default(),
                valid: sat(stats.valid),
                segments: sat(stats.segments),
                dropped: sat(stats.dropped),
                n_features: sat(ex.features().len()),
                status: match r_default {
                    Ok(_) => ScanStatus::Ok,
                    Err(_) => ScanStatus::FeatureCapacity,
                },
            };
            let t0 = time::ticks();
            let encoded = pfe_frame::write_scan(&mut Sink, &header, ex.features());
            let t_enc = time::ticks() - t0;
            if encoded.is_err() {
                sys::exit(sys::EXIT_OUTPUT);
            }
            // Whole pipeline: bytes → codes → features → frame, as the firmware runs it.
            let t0 = time::ticks();
            let d2 = decode(&mut dec, rest, &mut codes);
            let raw = RawScan::lms_8m(
                geometry(d2.n, d2.mm_per_unit),
                codes.get(..d2.n).unwrap_or(&[]),
                d2.mm_per_unit,
            );
            let r = app.process(&raw, Counters::default(), &mut Sink);
            let t_pipe = time::ticks() - t0;
            if r.is_err() {
                sys::exit(sys::EXIT_OUTPUT);
            }
            let points = u16::try_from(d.n).unwrap_or(u16::MAX);
            let mut send = |stage: Stage, t: u64| {
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
            };
            for (stage, t) in [
                (Stage::Decode, t_dec),
                (Stage::ExtractPaper, t_paper),
                (Stage::ExtractDefault, t_default),
                (Stage::Encode, t_enc),
                (Stage::Scan, t_scan),
                (Stage::Pipeline, t_pipe),
            ] {
                send(stage, t);
            }
            for ((_, stage), t) in STEPS.iter().zip(steps) {
                send(*stage, t);
            }
            pos += d.used;
            seq += 1;
        }
        let (used, size) = sys::stack_usage();
        report(&mut out, Report::Stack { used, size });
        report(&mut out, Report::Done { scans: seq });
        defmt::info!("bench: {} scans, stack {} of {} bytes", seq, used, size);
        sys::exit(sys::EXIT_OK)
    }
}
