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
use lms2xx::codec::types::{Baud, MeasuringMode};
use lms2xx::driver::Error;
use lms2xx::driver::{Config, Driver};

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
        assert_eq!(s.unit(), lms2xx::codec::types::Unit::Cm);
        assert_eq!(s.range_mm(0), Some(10_000.0));
    }
    assert_eq!(d.device().unit, Some(lms2xx::codec::types::Unit::Cm));
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

/// Runs `scenario` on another thread; if it panics or has not returned within 5 s the whole
/// test binary exits with a failure at once, because a hung thread (this one, or another test
/// hung by the same fault) would otherwise keep the binary running until an outside timeout.
fn within_5_s(what: &str, scenario: impl FnOnce() + Send + 'static) {
    let (tx, rx) = std::sync::mpsc::channel();
    let worker = std::thread::spawn(move || {
        scenario();
        let _ = tx.send(());
    });
    match rx.recv_timeout(std::time::Duration::from_secs(5)) {
        Ok(()) => worker.join().unwrap(),
        // The panic message is already printed.
        Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
            eprintln!("{what} failed");
            std::process::exit(101);
        }
        Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
            eprintln!("{what} did not return within 5 s");
            std::process::exit(101);
        }
    }
}

/// The driver never hangs on a device that answers (§4 order, traces A–D): init, three scans
/// and stop come back within 5 s of real time (simulated time makes them take milliseconds).
/// Named to sort first, so it starts before any other test of this binary can hang.
#[test]
fn a_driver_on_a_working_device_always_returns() {
    within_5_s("init, three scans and stop", || {
        let mut d = driver(9600, Config::default());
        d.init().unwrap();
        for _ in 0..3 {
            assert_eq!(d.next_scan().unwrap().len(), 361);
        }
        d.stop().unwrap();
    });
}

/// `20 xx` baud codes (§4, traces A, C): a device found at 9600 is switched to the configured
/// rate with `20 40` (38 400) or `20 48` (500 000) and then runs there; a device already at the
/// configured rate gets no baud command.
#[test]
fn the_baud_is_switched_only_when_the_device_runs_at_another() {
    for (baud, code, bps) in [
        (Baud::B38400, 0x40u8, 38400u32),
        (Baud::B500000, 0x48, 500_000),
    ] {
        let mut d = driver(9600, Config::default().with_baud(baud));
        d.init().unwrap();
        assert_eq!(d.device().baud, Some(baud));
        let (uart, _, _) = d.release();
        let switches: Vec<_> = uart
            .sent(0x20)
            .into_iter()
            .filter(|c| c[1] & 0xF0 == 0x40)
            .collect();
        assert_eq!(switches, vec![&vec![0x20, code]], "{bps}");
        assert_eq!(uart.dev_bps, bps);
        assert_eq!(uart.host_bauds.last(), Some(&bps));
    }
    let mut d = driver(38400, Config::default());
    d.init().unwrap();
    let (uart, _, _) = d.release();
    let modes: Vec<u8> = uart.sent(0x20).iter().map(|c| c[1]).collect();
    assert_eq!(
        modes,
        vec![0x25, 0x24],
        "only request mode, then continuous"
    );
}

/// `10` is the reset (§4): answered `91`, after which the device runs at 9600. The driver sends
/// it, stops streaming and knows the device is at 9600; the next scan re-initialises there.
#[test]
fn reset_sends_10_and_the_device_is_then_at_9600() {
    let mut d = driver(38400, Config::default());
    d.init().unwrap();
    d.reset_device().unwrap();
    assert!(!d.is_streaming());
    assert_eq!(d.device().baud, Some(Baud::B9600));
    assert_eq!(d.next_scan().unwrap().len(), 361);
    assert_eq!(d.device().baud, Some(Baud::B38400));
    let (uart, _, _) = d.release();
    assert_eq!(uart.sent(0x10), vec![&vec![0x10]]);
    assert_eq!(uart.dev_bps, 38400);
}

/// A reset whose `91` is damaged on the line, followed by the device's power-on message `90`
/// (§4: `10` → `91`, then `90`): the power-on is what the reset asked for, not a failure; the
/// reset is tried again and acknowledged.
#[test]
fn a_power_on_message_while_waiting_for_the_reset_ack_is_no_failure() {
    let t = Time::default();
    let mut d = Driver::new(
        Lms::new(t.clone(), 9600),
        t.clone(),
        t.clone(),
        Config::default().with_baud(Baud::B9600),
    );
    d.init().unwrap();
    d.stop().unwrap();
    let (mut uart, delay, clock) = d.release();
    let mut ack91 = common::lms::device_telegram(&[0x91, 0x10]);
    let last = ack91.len() - 1;
    ack91[last] ^= 0xFF;
    let power_on = common::lms::device_telegram(&[&[0x90][..], b"LMS200", &[0x10]].concat());
    uart.replace_reply = Some((
        uart.commands.len(),
        [&[0x06][..], &ack91, &power_on].concat(),
    ));
    let mut d = Driver::new(uart, delay, clock, Config::default().with_baud(Baud::B9600));
    assert_eq!(d.reset_device(), Ok(()));
    assert_eq!(d.counters().device_resets, 0);
    assert_eq!(
        d.release().0.sent(0x10).len(),
        2,
        "the reset is tried again"
    );
}

/// `config_refused` counts initialisations whose unit change was refused (a `92` answer to
/// `77`, §4): none when nothing had to change, one when the device refused; the device's unit
/// (mm) is then kept.
#[test]
fn config_refused_counts_only_refusals() {
    let mut d = driver(38400, Config::default());
    d.init().unwrap();
    assert_eq!(d.counters().config_refused, 0);

    // 20 25, 3A, 31, 74, 20 00 (install), 77: its answer replaced by ACK + `92`.
    let t = Time::default();
    let mut lms = Lms::new(t.clone(), 38400);
    let refuse = common::lms::device_telegram(&[0x92, 0x10]);
    lms.replace_reply = Some((5, [&[0x06][..], &refuse].concat()));
    let cfg = Config::default().with_unit(lms2xx::codec::types::Unit::Cm);
    let mut d = Driver::new(lms, t.clone(), t, cfg);
    d.init().unwrap();
    assert_eq!(d.counters().config_refused, 1);
    assert_eq!(d.device().unit, Some(lms2xx::codec::types::Unit::Mm));
    let (uart, _, _) = d.release();
    assert_eq!(uart.sent(0x77).len(), 1);
}

/// A delay that records every wait, on the shared simulated time.
#[derive(Clone)]
struct Recorded(Time, std::rc::Rc<std::cell::RefCell<Vec<u32>>>);

impl embedded_hal::delay::DelayNs for Recorded {
    fn delay_ns(&mut self, ns: u32) {
        self.1.borrow_mut().push(ns);
        self.0.delay_ns(ns);
    }
}

/// A clock that advances the simulated time by 1 µs at every reading, so the driver gets on
/// even if it never waited.
#[derive(Clone)]
struct Ticking(Time);

impl lms2xx::driver::Clock for Ticking {
    fn now_ms(&mut self) -> u32 {
        self.0 .0.set(self.0 .0.get() + 1);
        (self.0 .0.get() / 1000) as u32
    }
}

/// While waiting for a reply at 38 400 Bd the driver waits half a character (10 bits, §8) at a
/// time: 5 000 000 / 38 400 = 130 µs, never 0.
#[test]
fn waits_for_replies_are_half_a_character_never_zero() {
    let t = Time::default();
    let log = std::rc::Rc::new(std::cell::RefCell::new(Vec::new()));
    let mut d = Driver::new(
        Lms::new(t.clone(), 38400),
        Recorded(t.clone(), log.clone()),
        Ticking(t),
        Config::default(),
    );
    d.init().unwrap();
    let waits = log.borrow();
    assert!(waits.iter().all(|&ns| ns > 0), "a zero wait");
    let half_chars = waits.iter().filter(|&&ns| ns == 130_000).count();
    assert!(half_chars > 20, "{half_chars} waits of 130 µs");
}

/// At 9600 Bd a 361-value telegram is 2 × 361 + 10 = 732 bytes, 762.5 ms (§7, §8); the silence
/// limit is two of them, 1525 ms. A device sending a scan every 1.5 s is not silent.
#[test]
fn silence_limit_counts_the_ten_framing_bytes() {
    let t = Time::default();
    let mut lms = Lms::new(t.clone(), 9600);
    lms.scan_period_us = 1_500_000;
    let mut d = Driver::new(lms, t.clone(), t, Config::default().with_baud(Baud::B9600));
    for _ in 0..6 {
        d.next_scan().unwrap();
    }
    assert_eq!(d.counters().reinits, 0);
}

/// `with_silence_timeout_ms` sets the timeout and keeps the other settings: at 19 200 Bd with a
/// 3 s timeout a device scanning every 2.5 s is neither switched to another rate nor
/// re-initialised.
#[test]
fn silence_timeout_setting_keeps_the_other_settings() {
    let t = Time::default();
    let mut lms = Lms::new(t.clone(), 19200);
    lms.scan_period_us = 2_500_000;
    let cfg = Config::default()
        .with_baud(Baud::B19200)
        .with_silence_timeout_ms(3000);
    let mut d = Driver::new(lms, t.clone(), t, cfg);
    assert_eq!(d.config().silence_timeout_ms, 3000);
    assert_eq!(d.config().baud, Baud::B19200);
    for _ in 0..4 {
        d.next_scan().unwrap();
    }
    assert_eq!(d.counters().reinits, 0);
    let (uart, _, _) = d.release();
    assert_eq!(uart.dev_bps, 19200);
}

/// A device that refuses `3B` and does not answer `31` keeps its variant; its scans' value
/// count names it (§7: 181 values = 180° at 1°).
#[test]
fn the_value_count_names_the_variant_the_device_kept() {
    let t = Time::default();
    let mut lms = Lms::new(t.clone(), 38400);
    lms.variant = (180, 100);
    lms.answer_status = false;
    // 20 25, 3A, 31 (refused), 74, 3B: its answer replaced by ACK + `92`.
    let refuse = common::lms::device_telegram(&[0x92, 0x10]);
    lms.replace_reply = Some((4, [&[0x06][..], &refuse].concat()));
    let mut d = Driver::new(lms, t.clone(), t, Config::default());
    let s = d.next_scan().unwrap();
    assert_eq!(s.len(), 181);
    assert_eq!(s.variant, lms2xx::codec::types::Variant::A180_R100);
    assert_eq!(d.counters().variant_refused, 1);
}

/// A device that restarts (power-on `90`, §4) in place of every scan is re-initialised
/// `max_reinits_per_call` (2) times; then `next_scan` gives up with `Silence`.
#[test]
fn next_scan_gives_up_after_its_reinitialisations() {
    let t = Time::default();
    let mut lms = Lms::new(t.clone(), 38400);
    lms.power_on_scans = (1..=40).collect();
    let mut d = Driver::new(lms, t.clone(), t, Config::default());
    assert_eq!(d.next_scan().map(|s| s.len()), Err(Error::Silence));
    assert_eq!(d.counters().reinits, 2);
    assert!(!d.is_streaming());
}

/// A scan's value `i` is split per measuring mode 0 (§5: range bits 0–12, flags 13–15): the
/// scripted device's value 0 is 1000 mm with no flag; there is no value 361.
#[test]
fn scan_measurements_split_the_value_words() {
    use lms2xx::codec::reply::{Measurement, RangeCode};
    let mut d = driver(38400, Config::default());
    let s = d.next_scan().unwrap();
    assert_eq!(
        s.measurement(0),
        Some(Measurement {
            code: 1000,
            flags: 0,
            kind: RangeCode::Valid(1000)
        })
    );
    assert_eq!(s.measurement(360).map(|m| m.code), Some(1360));
    assert_eq!(s.measurement(361), None);
}

/// Unrequested replies while streaming: an `A0` soon after the last command (`20 24`) is a late
/// answer to it, and any other reply (a type string `BA`) is no reset; an `A0` seconds after
/// the last command can only come from a device that restarted: it re-initialises.
#[test]
fn unrequested_replies_while_streaming() {
    let a0 = vec![0xA0, 0x00, 0x10];
    let ba = [&[0xBA][..], b"LMS200;30106", &[0x10]].concat();
    // (after scan, payload, resets expected). At 38 400 Bd a scan takes 190 ms: scan 2 ends
    // 0.4 s after `20 24`, scan 20 ends 3.8 s after it.
    for (after, payload, resets) in [(2u32, a0.clone(), 0u32), (3, ba, 0), (20, a0, 1)] {
        let t = Time::default();
        let mut lms = Lms::new(t.clone(), 38400);
        lms.stray_after_scan = vec![(after, payload.clone())];
        let mut d = Driver::new(lms, t.clone(), t, Config::default());
        for _ in 0..25 {
            d.next_scan().unwrap();
        }
        let what = format!("{payload:02x?} after scan {after}");
        assert_eq!(d.counters().device_resets, resets, "{what}");
        assert_eq!(d.counters().reinits, resets, "{what}");
    }
}
