//! Criterion benches of the firmware's per-scan work on the host, so that regressions in its hot
//! functions show without QEMU: the LMS checksum of a 361-value B0 telegram, decoding that
//! telegram (resyncing decoder, checksum, values), and writing one scan frame (postcard, COBS,
//! CRC-32). Instruction counts on the Cortex-M4F model are `cargo xtask bench-mcu`'s job.
//!
//! Run with `cargo bench -p host-tests --bench firmware`.

use criterion::{criterion_group, criterion_main, Criterion};
use lms2xx::codec::crc::crc16;
use lms2xx::codec::frame::Event;
use lms2xx::codec::frame::{encode_telegram, Decoder, DEVICE_ADDRESS};
use lms2xx::codec::reply::{MeasuredValues, ReplyOptions};
use lms2xx::codec::types::MeasuringMode;
use pfe_core::{Config, Extractor, Scan};
use pfe_eval::bench::simulated_scans;
use pfe_frame::{write_scan, Counters, ScanHeader, ScanStatus};
use std::hint::black_box;

/// Discards what it is given (the encoder's cost alone).
struct Sink;
impl embedded_io::ErrorType for Sink {
    type Error = core::convert::Infallible;
}
impl embedded_io::Write for Sink {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        Ok(black_box(buf).len())
    }
    fn flush(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
}

fn benches(c: &mut Criterion) {
    let scan = simulated_scans(1, 7).remove(0);
    let codes: Vec<u16> = scan
        .ranges_mm
        .iter()
        .map(|r| {
            if r.is_finite() {
                r.round().clamp(1.0, 8000.0) as u16
            } else {
                8183
            }
        })
        .collect();
    // B0 payload: command, count (mm mode), values, status.
    let mut payload = vec![0xB0];
    payload.extend_from_slice(&(codes.len() as u16 | 1 << 14).to_le_bytes());
    codes
        .iter()
        .for_each(|v| payload.extend_from_slice(&v.to_le_bytes()));
    payload.push(0x10);
    let mut telegram = vec![0u8; payload.len() + 6];
    let n = encode_telegram(DEVICE_ADDRESS, &payload, &mut telegram).unwrap_or(0);
    telegram.truncate(n);
    let body = &telegram[..telegram.len().saturating_sub(2)];

    c.bench_function("lms_crc16_b0_361", |b| b.iter(|| crc16(black_box(body))));

    let mut dec = Decoder::<812>::new();
    let mut out = [0u16; 361];
    let mut decode = |bytes: &[u8]| -> usize {
        match dec.feed(bytes).1 {
            Some(Event::Telegram(t)) => MeasuredValues::parse(t.payload(), ReplyOptions::default())
                .map(|v| v.range_codes(MeasuringMode(0), &mut out))
                .unwrap_or(0),
            _ => 0,
        }
    };
    // Every pass decodes the whole telegram (a bench of nothing would be no bench).
    assert_eq!(decode(&telegram), codes.len());
    assert_eq!(decode(&telegram), codes.len());
    c.bench_function("lms_decode_b0_361", |b| {
        b.iter(|| decode(black_box(&telegram)))
    });

    let mut ex = Box::new(Extractor::<361, 64>::new());
    let _ = ex.extract(
        &Scan::from_mm(scan.geometry, &scan.ranges_mm),
        &Config::default(),
    );
    let header = ScanHeader {
        seq: 1,
        time_ms: 0,
        counters: Counters::default(),
        valid: 350,
        segments: 12,
        dropped: 0,
        n_features: 0,
        status: ScanStatus::Ok,
    };
    let name = format!("output_write_scan_{}_features", ex.features().len());
    c.bench_function(&name, |b| {
        b.iter(|| write_scan(&mut Sink, black_box(&header), black_box(ex.features())))
    });
}

criterion_group!(firmware_benches, benches);
criterion_main!(firmware_benches);
