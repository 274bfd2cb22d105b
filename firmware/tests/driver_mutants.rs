//! Driver behaviour against a scripted LMS200 written from the protocol notes
//! (common/lms.rs): what the driver sends, what it delivers, when it re-initialises. Each test
//! kills cargo-mutants survivors (docs/TESTING.md, mutation section).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

mod common;

use common::lms::{crc16, Lms};
use common::Time;
use firmware::lms::driver::{Config, Driver};
use firmware::lms::{Baud, Error, MeasuringMode};

type Lms200 = Driver<Lms, Time, Time>;

fn driver(dev_bps: u32, config: Config) -> Lms200 {
    let t = Time::default();
    Driver::new(Lms::new(t.clone(), dev_bps), t.clone(), t, config)
}

/// The mock's CRC is the protocol's: it reproduces published vectors.
#[test]
fn mock_crc_reproduces_the_vectors() {
    assert_eq!(crc16(&[0x02, 0x00, 0x02, 0x00, 0x20, 0x24]), 0x0834);
    assert_eq!(crc16(&[0x02, 0x80, 0x03, 0x00, 0xA0, 0x00, 0x10]), 0x0A16);
}

/// Streaming starts with init and ends with stop; a scan carries the telegram's values and
/// count word (361 values, mm: bits 14–15 = 01).
#[test]
fn init_streams_and_a_scan_carries_the_telegram() {
    let mut d = driver(38400, Config::default());
    assert!(!d.is_streaming(), "streaming before init");
    d.init().unwrap();
    assert!(d.is_streaming());
    let s = d.next_scan().unwrap();
    assert_eq!(s.len(), 361);
    assert_eq!(s.count_word(), (1 << 14) | 361);
    assert_eq!(s.codes()[0], 1000);
    assert_eq!(s.codes()[360], 1360);
    assert_eq!(s.range_mm(360), Some(1360.0));
    d.stop().unwrap();
    assert!(!d.is_streaming(), "streaming after stop");
    let (uart, _, _) = d.release();
    // The last command is `20 25`.
    assert_eq!(uart.commands.last().unwrap(), &vec![0x20, 0x25]);
}

/// The driver polls every `min(poll_interval_us, half a character time)`: 500 µs at 9600
/// (half a character 520 µs), 130 µs at 38 400 (5 000 000 / 38 400 = 130.2).
#[test]
fn poll_interval_is_the_configured_one_capped_at_half_a_character() {
    // Device at 9600: the probe tries 38 400 (configured) first, waits 1 s there, then 9600.
    let mut d = driver(9600, Config::default());
    d.init().unwrap();
    let (uart, _, _) = d.release();
    for (bps, want) in [(38400, 130u64), (9600, 500)] {
        let times: Vec<u64> = uart
            .idle_polls
            .iter()
            .filter(|p| p.1 == bps)
            .map(|p| p.0)
            .collect();
        let mut gaps: Vec<u64> = times.windows(2).map(|w| w[1] - w[0]).collect();
        assert!(gaps.len() > 20, "{bps}: {} polls", gaps.len());
        gaps.sort_unstable();
        assert_eq!(gaps[gaps.len() / 2], want, "median poll gap at {bps} Bd");
    }
}

/// `3B` is sent when the status did not name the variant, and not when it named the one
/// configured.
#[test]
fn variant_is_set_only_when_not_known_to_be_right() {
    let mut d = driver(38400, Config::default());
    d.init().unwrap();
    let (uart, _, _) = d.release();
    assert!(
        uart.sent(0x3B).is_empty(),
        "3B sent though B1 named 180/0.5"
    );

    let t = Time::default();
    let mut lms = Lms::new(t.clone(), 38400);
    lms.answer_status = false;
    let mut d = Driver::new(lms, t.clone(), t, Config::default());
    d.init().unwrap();
    let (uart, _, _) = d.release();
    assert_eq!(
        uart.sent(0x3B),
        vec![&vec![0x3B, 0xB4, 0x00, 0x32, 0x00]],
        "the variant must be set when the status is refused"
    );
}

/// The configuration `77` is written only when unit or measuring mode differ, with the
/// device's block changed in those bytes only.
#[test]
fn configuration_is_written_only_when_it_differs() {
    // Device in mm, mode 0; configured mm, device's mode: nothing to write.
    let mut d = driver(38400, Config::default());
    d.init().unwrap();
    let (uart, _, _) = d.release();
    assert!(uart.sent(0x77).is_empty(), "77 sent though nothing differs");

    // Same unit, another measuring mode: written, mode byte 5 = 6.
    let mut d = driver(
        38400,
        Config::default().with_measuring_mode(MeasuringMode::M32_FIELD_A),
    );
    d.init().unwrap();
    assert_eq!(d.device().measuring_mode, MeasuringMode::M32_FIELD_A);
    let (uart, _, _) = d.release();
    let w = uart.sent(0x77);
    assert_eq!(w.len(), 1, "one 77 for a new measuring mode");
    let mut want = vec![0x77, 0x46, 0, 0, 0, 0, 6, 1];
    want.resize(35, 0);
    assert_eq!(w[0], &want);
    assert_eq!(uart.config[5], 6);
}

/// A power-on message (`90`) in answer to a command means the device restarted: the command
/// fails with `DeviceReset` at once, not after its tries time out.
#[test]
fn a_power_on_message_while_waiting_is_a_device_reset() {
    let t = Time::default();
    let lms = Lms::new(t.clone(), 38400);
    let mut d = Driver::new(lms, t.clone(), t.clone(), Config::default());
    d.init().unwrap();
    let (uart, delay, clock) = d.release();
    let mut uart = uart;
    uart.power_on_next = true;
    let mut d = Driver::new(uart, delay, clock, Config::default());
    let t0 = t.0.get();
    assert_eq!(d.stop(), Err(Error::DeviceReset));
    assert!(t.0.get() - t0 < 500_000, "waited {} µs", t.0.get() - t0);
    assert_eq!(d.counters().device_resets, 1);
    assert_eq!(d.counters().timeouts, 0);
}

/// At 9600 Bd one 361-value telegram takes 732 × 10 / 9600 s = 762.5 ms; the silence limit is
/// two of them (1525 ms), above the configured 1000 ms. A device sending a scan every 1.4 s
/// is not silent; one that stops is re-initialised.
#[test]
fn silence_limit_is_two_telegram_times_at_9600() {
    let t = Time::default();
    let mut lms = Lms::new(t.clone(), 9600);
    lms.scan_period_us = 1_400_000;
    let cfg = Config::default().with_baud(Baud::B9600);
    let mut d = Driver::new(lms, t.clone(), t, cfg);
    for _ in 0..6 {
        d.next_scan().unwrap();
    }
    assert_eq!(
        d.counters().reinits,
        0,
        "re-initialised a device that kept sending"
    );
}

/// A scan with the restart bit re-initialises; after normal scans, the next one does again
/// (a restart that stays set is accepted only until a normal scan is seen).
#[test]
fn restart_bit_reinitialises_again_after_normal_scans() {
    let t = Time::default();
    let mut lms = Lms::new(t.clone(), 38400);
    lms.restart_scans = vec![3, 8];
    let mut d = Driver::new(lms, t.clone(), t, Config::default());
    for _ in 0..10 {
        let s = d.next_scan().unwrap();
        assert!(!s.status.restart(), "a restart scan was delivered");
    }
    assert_eq!(d.counters().reinits, 2);
    assert_eq!(d.counters().device_resets, 2);
}

/// The driver's counters carry the decoder's: one good telegram per answered command, and a
/// NAK, a bad CRC, a zero LEN or line noise in place of one reply each counted once (the
/// decoder skips every byte of a rejected candidate, its STX included, and the noise).
#[test]
fn counters_carry_the_decoders_counts() {
    let bad_crc = {
        let mut t = common::lms::device_telegram(&[0xA0, 0x00, 0x10]);
        t[8] ^= 1;
        t
    };
    // (replacement of the reply to `3A`, naks, crc errors, bad length, bytes skipped)
    let cases: [(Vec<u8>, u32, u32, u32, u32); 4] = [
        (vec![0x15], 1, 0, 0, 0),
        (bad_crc, 0, 1, 0, 9),
        (vec![0x02, 0x80, 0x00, 0x00], 0, 0, 1, 4),
        (vec![0x55, 0x55, 0x55], 0, 0, 0, 3),
    ];
    for (bytes, naks, crc, len, skipped) in cases {
        let t = Time::default();
        let mut lms = Lms::new(t.clone(), 38400);
        lms.replace_reply = Some((1, bytes.clone()));
        let mut d = Driver::new(lms, t.clone(), t, Config::default());
        d.init().unwrap();
        let c = d.counters();
        let commands = d.release().0.commands.len() as u32;
        assert_eq!(c.telegrams_ok, commands - 1, "{bytes:02x?}");
        assert_eq!(c.naks, naks, "{bytes:02x?}");
        assert_eq!(c.crc_errors, crc, "{bytes:02x?}");
        assert_eq!(c.bad_length, len, "{bytes:02x?}");
        assert_eq!(c.bytes_skipped, skipped, "{bytes:02x?}");
        assert_eq!(c.retries, 1, "{bytes:02x?}");
    }
}

/// A device that keeps sending scans in another unit than configured (cm here) after the
/// re-initialisation is used with the unit its scans carry (§7: count bits 14–15).
#[test]
fn scans_in_another_unit_are_used_with_their_unit() {
    let t = Time::default();
    let mut lms = Lms::new(t.clone(), 38400);
    lms.scan_unit_bits = Some(0);
    let mut d = Driver::new(lms, t.clone(), t, Config::default());
    for _ in 0..3 {
        let s = d.next_scan().unwrap();
        assert_eq!(s.unit(), firmware::lms::Unit::Cm);
        assert_eq!(s.range_mm(0), Some(10_000.0));
    }
    assert_eq!(d.device().unit, Some(firmware::lms::Unit::Cm));
    assert_eq!(d.counters().reinits, 1);
}

/// An unrequested power-on message (`90`, §4) while streaming means the device restarted: the
/// driver re-initialises at once, not after the silence timeout, and delivers scans again.
#[test]
fn a_power_on_message_while_streaming_reinitialises_at_once() {
    let t = Time::default();
    let mut lms = Lms::new(t.clone(), 38400);
    lms.power_on_scans = vec![3];
    let mut d = Driver::new(lms, t.clone(), t.clone(), Config::default());
    assert!(d.last_scan().is_empty(), "a scan before the first");
    let mut times = Vec::new();
    for _ in 0..4 {
        let s = d.next_scan().unwrap();
        assert!(!s.is_empty());
        times.push(s.time_ms);
    }
    assert_eq!(d.counters().device_resets, 1);
    assert_eq!(d.counters().reinits, 1);
    // Scan 2 → (power-on) → re-init → next scan: well under the 1 s silence timeout.
    let gap = times[2] - times[1];
    assert!(gap < 900, "{gap} ms between the scans around the restart");
}
