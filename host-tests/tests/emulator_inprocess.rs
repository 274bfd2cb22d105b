//! The firmware driver against the emulated LMS200 over the in-process link (virtual time).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: a panic fails the test

use firmware::app::ScanDataExt;
use lms200_emulator::{
    Emulator, EmulatorConfig, HostPort, Link, LinkClock, LinkDelay, SourceKind, TaggedSource,
};
use lms2xx::codec::frame::{encode_telegram, Decoder, Event, MAX_TELEGRAM};
use lms2xx::codec::reply::{parse_reply, ConfigBlock, Reply, ReplyOptions};
use lms2xx::codec::types::{Baud, MeasuringMode, Unit, Variant};
use lms2xx::driver::{Config, Driver};

type Lms = Driver<HostPort, LinkDelay, LinkClock>;

fn setup(cfg: EmulatorConfig, driver: Config) -> (Link, Lms) {
    let link = Link::new(Emulator::from_config(cfg), Some(9600));
    let d = Driver::new(link.host_port(), link.delay(), link.clock(), driver);
    (link, d)
}

fn tagged() -> EmulatorConfig {
    EmulatorConfig {
        source: SourceKind::Tagged,
        ..Default::default()
    }
}

#[test]
fn init_like_sicktoolbox_then_stream_exact_ranges() {
    let (link, mut lms) = setup(EmulatorConfig::default(), Config::default());
    lms.init().unwrap();
    let cmds = link.with_emulator(|e| e.report().commands.clone()).unwrap();
    // 20 25 probe (fails at 38400: device at 9600, garbled), ... found at 9600, 20 40, 20 25,
    // 3A, 31, 74, 20 24. Unit mm and 180/0.5 are the emulator's defaults: no 3B / 77.
    assert_eq!(cmds, [0x20, 0x20, 0x20, 0x3A, 0x31, 0x74, 0x20]);
    assert_eq!(link.with_emulator(|e| e.baud()).unwrap(), Baud::B38400);
    assert_eq!(link.host_baud(), Some(38400));
    assert_eq!(lms.device().unit, Some(Unit::Mm));
    let mut got = Vec::new();
    for _ in 0..5 {
        let s = lms.next_scan().unwrap();
        assert_eq!(s.len(), 361);
        assert_eq!(s.unit(), Unit::Mm);
        got.push(s.codes().to_vec());
    }
    let sent = link.with_emulator(|e| e.report().scans.clone()).unwrap();
    for (g, s) in got.iter().zip(&sent) {
        assert_eq!(g, &s.words);
        // Independent truth: the room's geometry, to the mm quantum.
        for (i, (&c, &r)) in g.iter().zip(&s.ranges_mm).enumerate() {
            if r.is_finite() && r <= 8182.0 {
                assert!((f32::from(c) - r).abs() <= 0.5, "beam {i}: {c} vs {r}");
            } else {
                assert!(
                    c > 8182,
                    "beam {i}: {r} mm must be a reserved code, got {c}"
                );
            }
        }
    }
    let c = lms.counters();
    assert_eq!(c.scans, 5);
    assert_eq!(c.crc_errors, 0);
    assert_eq!(c.reinits, 0);
    assert!(c.timeouts >= 1, "the probe at 38400 timed out: {c:?}");
}

#[test]
fn device_without_type_and_status_commands_is_still_used() {
    // A device (or emulator) that answers 3A and 31 with 92 "incorrect command": the driver
    // goes on without them and, not knowing the variant from the status, sets it with 3B.
    let cfg = EmulatorConfig {
        unsupported: vec![0x3A, 0x31],
        ..tagged()
    };
    let (link, mut lms) = setup(cfg, Config::default());
    lms.init().unwrap();
    let cmds = link.with_emulator(|e| e.report().commands.clone()).unwrap();
    assert_eq!(cmds, [0x20, 0x20, 0x20, 0x3A, 0x31, 0x74, 0x3B, 0x20]);
    assert_eq!(lms.device().variant, Variant::A180_R050);
    for _ in 0..3 {
        assert_eq!(lms.next_scan().unwrap().len(), 361);
    }
    let sent = link.with_emulator(|e| e.report().scans.clone()).unwrap();
    assert!(sent.len() >= 3 && sent.iter().all(|s| !s.damaged));
    assert_eq!(lms.counters().scans, 3);
}

#[test]
fn refused_baud_rate_keeps_the_one_found() {
    // An RS-232 device without 500 000 Bd answers the switch `A0 01`: the driver streams at
    // the rate the device answered at (9600) and says so in its counters.
    let cfg = EmulatorConfig {
        refused_bauds: vec![Baud::B500000],
        ..tagged()
    };
    let (link, mut lms) = setup(cfg, Config::default().with_baud(Baud::B500000));
    for k in 0..3u32 {
        let s = lms.next_scan().unwrap();
        assert_eq!(s.len(), 361);
        assert_eq!(TaggedSource::tag_of(s.codes()), Some(k));
    }
    assert_eq!(link.with_emulator(|e| e.baud()).unwrap(), Baud::B9600);
    assert_eq!(link.host_baud(), Some(9600));
    assert_eq!(lms.device().baud, Some(Baud::B9600));
    let c = lms.counters();
    assert_eq!((c.baud_refused, c.reinits, c.crc_errors), (1, 0, 0));
}

#[test]
fn refused_unit_change_streams_in_the_devices_unit() {
    // A device left in cm that does not implement 77: the driver keeps cm, and the ranges it
    // reports (range_mm) are the room's to the cm quantum.
    let mut block = ConfigBlock::default_mm();
    block.set_unit(Unit::Cm);
    let cfg = EmulatorConfig {
        config: block,
        unsupported: vec![0x77],
        ..Default::default()
    };
    let (link, mut lms) = setup(cfg, Config::default());
    let mut got = Vec::new();
    for _ in 0..3 {
        let s = lms.next_scan().unwrap();
        assert_eq!(s.unit(), Unit::Cm);
        got.push((0..s.len()).map(|i| s.range_mm(i)).collect::<Vec<_>>());
    }
    let sent = link.with_emulator(|e| e.report().scans.clone()).unwrap();
    for (g, s) in got.iter().zip(&sent) {
        for (i, (&r, &truth)) in g.iter().zip(&s.ranges_mm).enumerate() {
            match r {
                Some(r) => assert!((r - truth).abs() <= 5.0, "beam {i}: {r} vs {truth}"),
                None => assert!(
                    truth.is_nan() || truth > 8000.0,
                    "beam {i}: {truth} mm lost"
                ),
            }
        }
    }
    let c = lms.counters();
    assert_eq!((c.config_refused, c.reinits, c.device_resets), (1, 0, 0));
    assert_eq!(lms.device().unit, Some(Unit::Cm));
}

#[test]
fn device_that_does_not_report_its_configuration_is_still_used() {
    // 74 answered 92: no unit or mode change is possible; the scans (mm, the emulator's
    // power-on unit) are delivered with their own unit.
    let cfg = EmulatorConfig {
        unsupported: vec![0x74],
        ..tagged()
    };
    let (_link, mut lms) = setup(cfg, Config::default());
    for k in 0..3u32 {
        let s = lms.next_scan().unwrap();
        assert_eq!((s.len(), s.unit()), (361, Unit::Mm));
        assert_eq!(TaggedSource::tag_of(s.codes()), Some(k));
    }
    let c = lms.counters();
    assert_eq!((c.config_refused, c.reinits), (1, 0));
}

#[test]
fn restart_flag_that_stays_set_costs_one_reinit_not_the_stream() {
    // Status 0x30 on every telegram (restart bit 5 set): the first scan looks like a device
    // reset and re-initialises; the same flag after that is how this device reports, so the
    // scans are delivered.
    let cfg = EmulatorConfig {
        status: 0x30,
        ..tagged()
    };
    let (_link, mut lms) = setup(cfg, Config::default());
    let mut tags = Vec::new();
    for _ in 0..4 {
        let s = lms.next_scan().unwrap();
        assert!(s.status.restart());
        tags.push(TaggedSource::tag_of(s.codes()).unwrap());
    }
    assert!(tags.windows(2).all(|w| w[1] == w[0] + 1), "{tags:?}");
    let c = lms.counters();
    assert_eq!((c.reinits, c.device_resets, c.scans), (1, 1, 4));
}

#[test]
fn silence_timeout_is_never_shorter_than_two_telegrams() {
    // At 9600 Bd a 401-value telegram takes 845 ms: a 300 ms silence timeout would re-init
    // between every two scans; the driver waits at least two telegrams' time instead.
    let (_link, mut lms) = setup(
        tagged(),
        Config::default()
            .with_baud(Baud::B9600)
            .with_variant(Variant::A100_R025)
            .with_silence_timeout_ms(300),
    );
    for k in 0..3u32 {
        let s = lms.next_scan().unwrap();
        assert_eq!(TaggedSource::tag_of(s.codes()), Some(k));
    }
    assert_eq!(lms.counters().reinits, 0);
}

#[test]
fn refused_variant_is_read_from_the_scans() {
    // A device at 100°/0.25° that neither reports its status nor accepts 3B: the driver
    // takes the variant from the value count (401), so the geometry is the device's.
    let cfg = EmulatorConfig {
        variant: Variant::A100_R025,
        unsupported: vec![0x31, 0x3B],
        ..tagged()
    };
    let (_link, mut lms) = setup(cfg, Config::default());
    for k in 0..2u32 {
        let s = lms.next_scan().unwrap();
        assert_eq!((s.len(), s.variant), (401, Variant::A100_R025));
        assert_eq!(TaggedSource::tag_of(s.codes()), Some(k));
        let g = s.geometry();
        assert!((g.start_angle + 50f32.to_radians()).abs() < 1e-6);
        assert!((g.angle_step - 0.25f32.to_radians()).abs() < 1e-7);
    }
    let c = lms.counters();
    assert_eq!((c.variant_refused, c.reinits), (1, 0));
}

#[test]
fn scan_rate_follows_baud_and_variant() {
    for (baud, variant, hz) in [
        (Baud::B38400, Variant::A180_R050, 5.2),
        (Baud::B9600, Variant::A180_R100, 2.6),
        (Baud::B500000, Variant::A180_R050, 37.5),
        (Baud::B500000, Variant::A100_R025, 18.75),
        (Baud::B19200, Variant::A100_R100, 9.1),
    ] {
        let (link, mut lms) = setup(
            tagged(),
            Config::default().with_baud(baud).with_variant(variant),
        );
        lms.next_scan().unwrap();
        let t0 = link.now_us();
        let n = 20;
        for _ in 0..n {
            let s = lms.next_scan().unwrap();
            assert_eq!(s.len(), variant.values());
        }
        let rate = n as f64 / ((link.now_us() - t0) as f64 / 1e6);
        assert!(
            (rate - hz).abs() / hz < 0.08,
            "{baud:?} {variant:?}: {rate:.2} Hz, want {hz}"
        );
    }
}

#[test]
fn variant_and_cm_unit_via_installation_mode() {
    let cfg = Config::default()
        .with_variant(Variant::A100_R025)
        .with_unit(Unit::Cm)
        .with_baud(Baud::B500000);
    let (link, mut lms) = setup(EmulatorConfig::default(), cfg);
    let s = lms.next_scan().unwrap().clone();
    assert_eq!(s.len(), 401);
    assert_eq!(s.unit(), Unit::Cm);
    let cmds = link.with_emulator(|e| e.report().commands.clone()).unwrap();
    assert!(
        cmds.ends_with(&[0x3A, 0x31, 0x74, 0x3B, 0x20, 0x77, 0x20, 0x20]),
        "{cmds:02X?}"
    );
    let block = link.with_emulator(|e| e.config_block()).unwrap();
    assert_eq!(block.unit(), Some(Unit::Cm));
    let sent = link
        .with_emulator(|e| e.report().scans.last().cloned())
        .unwrap()
        .unwrap();
    // cm quantum: every valid value within 5 mm of the room geometry, and every beam the room
    // returns (finite range within the 8 m of the room's walls) is valid: a scan reported all
    // invalid fails.
    let mut valid = 0;
    for i in 0..401 {
        let truth = sent.ranges_mm[i];
        match s.range_mm(i) {
            Some(mm) => {
                valid += 1;
                assert!((mm - truth).abs() <= 5.0, "beam {i}: {mm} vs {truth}");
            }
            None => assert!(
                !(truth > 0.0 && truth < 8000.0),
                "beam {i}: the room returns {truth} mm, reported invalid"
            ),
        }
    }
    assert!(valid * 10 >= 401 * 9, "{valid} of 401 beams valid");
    // The pfe-core view uses the same numbers.
    let scan = s.as_pfe_scan();
    assert_eq!(scan.ranges.len(), 401);
    assert!((scan.geometry.angle_step.to_degrees() - 0.25).abs() < 1e-4);
}

#[test]
fn mrpt_style_32m_mode_decodes_15_bit_ranges() {
    let cfg = Config::default().with_measuring_mode(MeasuringMode(6));
    let (link, mut lms) = setup(tagged(), cfg);
    let s = lms.next_scan().unwrap();
    assert_eq!(s.mode, MeasuringMode(6));
    assert_eq!(s.max_valid(), 32758);
    let tag = TaggedSource::tag_of(s.codes()).unwrap();
    let sent = link
        .with_emulator(|e| e.report().scans[tag as usize].clone())
        .unwrap();
    assert_eq!(s.codes(), &sent.words[..]);
}

#[test]
fn driver_restart_finds_device_streaming_at_38400() {
    let (link, mut lms) = setup(tagged(), Config::default());
    lms.next_scan().unwrap();
    let (port, delay, clock) = lms.release();
    // A new driver (e.g. after a firmware reset): the device still streams at 38400.
    let mut lms2 = Driver::new(port, delay, clock, Config::default());
    let s = lms2.next_scan().unwrap();
    assert_eq!(s.len(), 361);
    let cmds = link.with_emulator(|e| e.report().commands.clone()).unwrap();
    // Second init: 20 25 probe answered at once at 38400; no baud change.
    assert_eq!(&cmds[7..], &[0x20, 0x3A, 0x31, 0x74, 0x20]);
}

#[test]
fn invalid_variant_is_rejected_by_config_check() {
    let (_, mut lms) = setup(
        tagged(),
        Config::default().with_variant(Variant::new(180, 25)),
    );
    assert!(matches!(
        lms.init(),
        Err(lms2xx::driver::Error::InvalidConfig)
    ));
}

// ------------------------------------------------------------------ emulator alone

fn talk(emu: &mut Emulator, t: &mut u64, payload: &[u8]) -> Vec<(Option<u8>, Vec<u8>)> {
    let mut buf = [0u8; 64];
    let n = encode_telegram(0x00, payload, &mut buf).unwrap();
    emu.receive(*t, None, &buf[..n]);
    *t += 1_000_000;
    let mut out = Vec::new();
    emu.take_ready(*t, None, &mut out);
    let mut dec = Decoder::<MAX_TELEGRAM>::new();
    let mut ev = Vec::new();
    let mut rest = &out[..];
    loop {
        let (u, e) = dec.feed(rest);
        rest = &rest[u..];
        match e {
            Some(Event::Ack) => ev.push((Some(0x06), vec![])),
            Some(Event::Nak) => ev.push((Some(0x15), vec![])),
            Some(Event::Telegram(t)) => ev.push((None, t.payload().to_vec())),
            None => break,
        }
    }
    ev
}

#[test]
fn emulator_replies() {
    let mut e = Emulator::from_config(EmulatorConfig::default());
    let mut t = 0;
    let r = talk(&mut e, &mut t, &[0x3B, 0xB4, 0x00, 0x19, 0x00]); // 180/0.25: invalid
    assert_eq!(
        r,
        vec![
            (Some(6), vec![]),
            (None, vec![0xBB, 0x00, 0xB4, 0x00, 0x19, 0x00, 0x10])
        ]
    );
    let r = talk(&mut e, &mut t, &[0x3B, 0x64, 0x00, 0x32, 0x00]); // 100/0.5 ok
    assert_eq!(r[1].1[1], 1);
    assert_eq!(e.variant(), Variant::A100_R050);
    // 77 outside installation mode fails, inside works.
    let mut block = e.config_block();
    block.set_unit(Unit::Cm);
    let mut p = vec![0x77];
    p.extend(block.as_bytes());
    let r = talk(&mut e, &mut t, &p);
    assert_eq!(&r[1].1[..2], &[0xF7, 0x00]);
    let mut inst = vec![0x20, 0x00];
    inst.extend(b"SICK_LMX");
    let r = talk(&mut e, &mut t, &inst);
    assert_eq!(r[1].1, vec![0xA0, 0x01, 0x10], "bad password");
    inst[9] = b'S';
    assert_eq!(talk(&mut e, &mut t, &inst)[1].1, vec![0xA0, 0x00, 0x10]);
    let r = talk(&mut e, &mut t, &p);
    assert_eq!(&r[1].1[..2], &[0xF7, 0x01]);
    assert_eq!(e.config_block().unit(), Some(Unit::Cm));
    // Unknown command: 92.
    assert_eq!(talk(&mut e, &mut t, &[0x55])[1].1, vec![0x92, 0x10]);
    // Single scan on request: B0 with 201 values in cm.
    let r = talk(&mut e, &mut t, &[0x30, 0x01]);
    let pr = parse_reply(&r[1].1, ReplyOptions::default()).unwrap();
    let Reply::Values(v) = pr.reply else { panic!() };
    assert_eq!((v.len(), v.unit()), (201, Some(Unit::Cm)));
    // B1 reports what was set.
    let r = talk(&mut e, &mut t, &[0x31]);
    let Reply::Status(s) = parse_reply(&r[1].1, ReplyOptions::default()).unwrap().reply else {
        panic!()
    };
    assert_eq!(s.variant(), Some(Variant::A100_R050));
    assert_eq!(s.baud(), Some(Baud::B9600));
    assert_eq!(s.unit(), Some(Unit::Cm));
    // Bad CRC: NAK only.
    e.receive(t, None, &[0x02, 0x00, 0x01, 0x00, 0x31, 0x00, 0x00]);
    t += 50_000;
    let mut out = Vec::new();
    e.take_ready(t, None, &mut out);
    assert_eq!(out, vec![0x15]);
}

#[test]
fn baud_switch_reply_at_old_rate_then_garbled_mismatch() {
    let mut e = Emulator::from_config(EmulatorConfig::default());
    let mut buf = [0u8; 16];
    let n = encode_telegram(0x00, &[0x20, 0x40], &mut buf).unwrap();
    e.receive(0, Some(9600), &buf[..n]);
    let mut out = Vec::new();
    e.take_ready(100_000, Some(9600), &mut out);
    assert_eq!(
        out,
        vec![0x06, 0x02, 0x80, 0x03, 0x00, 0xA0, 0x00, 0x10, 0x16, 0x0A]
    );
    // 10 bytes at 9600 take 10.4 ms: the device was still at 9600 while sending them.
    assert_eq!(e.baud(), Baud::B38400);
    // A host still at 9600 is not understood now.
    let n = encode_telegram(0x00, &[0x31], &mut buf).unwrap();
    e.receive(200_000, Some(9600), &buf[..n]);
    out.clear();
    e.take_ready(400_000, Some(9600), &mut out);
    assert!(out.is_empty());
    assert_eq!(e.report().garbled_in, n as u64);
}

#[test]
fn a_slow_caller_gets_the_waiting_scans_without_a_reinit() {
    // The caller takes 1.5 s over a scan (longer than the 1 s silence timeout) while the
    // scanner keeps streaming into the receive buffer: the scans that arrived meanwhile come
    // next, in order, and the driver does not re-initialise a device that never fell silent.
    let (link, mut lms) = setup(tagged(), Config::default());
    let first = TaggedSource::tag_of(lms.next_scan().unwrap().codes()).unwrap();
    link.advance(1_500_000).unwrap();
    for k in 1..4u32 {
        let s = lms.next_scan().unwrap();
        assert_eq!(TaggedSource::tag_of(s.codes()), Some(first + k));
    }
    assert_eq!(lms.counters().reinits, 0);
}
