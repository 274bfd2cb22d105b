//! The driver against a scripted LMS200 (common/lms.rs) that refuses: a variant answered
//! `BB 00`, a configuration answered `F7 00`, a mode change answered `A0` with a code. Each is
//! a refusal the driver counts and works around, never a bad reply (cargo-mutants survivors of
//! stop 33, docs/TESTING.md).
#![allow(clippy::unwrap_used, clippy::indexing_slicing)]

mod common;

use common::lms::Lms;
use common::Time;
use lms2xx::driver::{Config, Driver};

type Lms200 = Driver<Lms, Time, Time>;

/// The index of the first command with code `code` a default init sends to a device set up by
/// `setup` (the scripted device's replies can then be replaced at that index).
fn index_of(code: u8, cfg: Config, setup: impl Fn(&mut Lms)) -> usize {
    let t = Time::default();
    let mut lms = Lms::new(t.clone(), 38400);
    setup(&mut lms);
    let mut d = Driver::new(lms, t.clone(), t, cfg);
    d.init().unwrap();
    let (uart, _, _) = d.release();
    uart.commands
        .iter()
        .position(|c| c.first() == Some(&code))
        .unwrap()
}

/// A driver whose device answers the command at `index` with ACK and `reply` (a payload,
/// status byte included).
fn answering(index: usize, reply: &[u8], cfg: Config, setup: impl Fn(&mut Lms)) -> Lms200 {
    let t = Time::default();
    let mut lms = Lms::new(t.clone(), 38400);
    setup(&mut lms);
    let telegram = common::lms::device_telegram(reply);
    lms.replace_reply = Some((index, [&[0x06][..], &telegram].concat()));
    Driver::new(lms, t.clone(), t, cfg)
}

/// `BB 00`: the device refuses the variant (§4). Init goes on with the device's variant and
/// counts the refusal; it is no bad reply.
#[test]
fn a_variant_answered_not_set_is_a_refusal() {
    let unknown = |l: &mut Lms| l.answer_status = false;
    let at = index_of(0x3B, Config::default(), unknown);
    let refused = [0xBB, 0x00, 0xB4, 0x00, 0x32, 0x00, common::lms::STATUS];
    let mut d = answering(at, &refused, Config::default(), unknown);
    d.init().unwrap();
    assert_eq!(d.counters().variant_refused, 1);
}

/// `F7 00`: the device does not take the configuration (§5). The write is refused (counted),
/// init goes on in the device's unit; it is no bad reply.
#[test]
fn a_configuration_answered_not_taken_is_a_refusal() {
    let cm = Config::default().with_unit(lms2xx::codec::types::Unit::Cm);
    let at = index_of(0x77, cm, |_| {});
    let mut reply = vec![0xF7, 0x00, 0x46, 0, 0, 0, 0, 1];
    reply.resize(36, 0);
    reply.push(common::lms::STATUS);
    let mut d = answering(at, &reply, cm, |_| {});
    d.init().unwrap();
    assert_eq!(d.counters().config_refused, 1);
    assert_eq!(d.device().unit, Some(lms2xx::codec::types::Unit::Mm));
}

/// `A0 01`: the device refuses a mode change with a code (§4, e.g. a wrong password for the
/// installation mode). That is a refusal of the configuration write, not a bad reply: init
/// goes on in the device's unit and sends no `77`.
#[test]
fn a_mode_change_answered_with_a_code_is_a_refusal() {
    let cm = Config::default().with_unit(lms2xx::codec::types::Unit::Cm);
    let at = index_of(0x77, cm, |_| {}) - 1;
    let mut d = answering(at, &[0xA0, 0x01, common::lms::STATUS], cm, |_| {});
    d.init().unwrap();
    assert_eq!(d.counters().config_refused, 1);
    assert_eq!(d.device().unit, Some(lms2xx::codec::types::Unit::Mm));
    let (uart, _, _) = d.release();
    assert!(
        uart.sent(0x77).is_empty(),
        "77 sent after a refused installation mode"
    );
}
