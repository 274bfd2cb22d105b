//! The sans-IO protocol machine on its own: a hand-written I/O loop (as an RTIC task or an
//! interrupt-driven firmware would write one) against the scripted LMS200 gets the same scans
//! and counters as the blocking Driver, and the loop's own errors end an operation cleanly.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]

mod common;

use common::lms::Lms;
use common::Time;
use embedded_hal::delay::DelayNs;
use embedded_io::{Read, ReadReady, Write};
use lms2xx::driver::machine::{Action, Machine, Request};
use lms2xx::driver::{Config, Driver, SetBaud};

/// What one operation ended with: a scan's (seq, time, first value), done, or the error.
type End = Result<Option<(u32, u32, u16)>, String>;

/// Carries out the machine's actions on `lms` until `request` ends.
fn run(m: &mut Machine, lms: &mut Lms, t: &mut Time, request: Request) -> End {
    m.start(request);
    loop {
        let now = (t.0.get() / 1000) as u32;
        match m.step(now) {
            Action::Write(b) => assert_eq!(lms.write(b).unwrap(), b.len()),
            Action::SetBaud(bps) => lms.set_baud(bps).unwrap(),
            Action::Read => {
                let n = if lms.read_ready().unwrap() {
                    lms.read(m.rx_buffer()).unwrap()
                } else {
                    0
                };
                m.received(n);
            }
            Action::Idle(us) => t.delay_us(us),
            Action::Wait(ms) => t.delay_ms(ms),
            Action::Scan => {
                let s = m.scan();
                return Ok(Some((s.seq, s.time_ms, s.codes()[0])));
            }
            Action::Done => return Ok(None),
            Action::Failed(e) => return Err(e.to_string()),
        }
    }
}

#[test]
fn a_hand_written_loop_matches_the_driver() {
    // A device at 9600 Bd (probe, switch to 38 400) that restarts in place of scan 4.
    let mut t = Time::default();
    let mut lms = Lms::new(t.clone(), 9600);
    lms.power_on_scans = vec![4];
    let mut m = Machine::new(Config::default());
    let by_hand: Vec<End> = (0..8)
        .map(|_| run(&mut m, &mut lms, &mut t, Request::NextScan))
        .collect();

    let t2 = Time::default();
    let mut lms2 = Lms::new(t2.clone(), 9600);
    lms2.power_on_scans = vec![4];
    let mut d = Driver::new(lms2, t2.clone(), t2.clone(), Config::default());
    let by_driver: Vec<End> = (0..8)
        .map(|_| {
            d.next_scan()
                .map(|s| Some((s.seq, s.time_ms, s.codes()[0])))
                .map_err(|e| e.to_string())
        })
        .collect();

    assert_eq!(by_hand, by_driver);
    assert_eq!(m.counters(), d.counters());
    assert_eq!(m.counters().reinits, 1);
    assert!(by_hand.iter().all(|e| matches!(e, Ok(Some((_, _, 1000))))));
    assert_eq!(t.0.get(), t2.0.get());
    assert_eq!(lms.commands, d.release().0.commands);
}

/// The loop's own I/O failure aborts the operation: the machine is idle after it (a step
/// says done) and the next operation starts afresh.
#[test]
fn abort_ends_the_operation() {
    let mut t = Time::default();
    let mut lms = Lms::new(t.clone(), 38400);
    let mut m = Machine::new(Config::default());
    m.start(Request::Init);
    assert_eq!(m.step(0), Action::SetBaud(38_400));
    m.abort();
    assert_eq!(m.step(0), Action::Done);
    assert_eq!(run(&mut m, &mut lms, &mut t, Request::Init), Ok(None));
    assert!(m.is_streaming());
    assert_eq!(m.device().baud, Some(lms2xx::codec::types::Baud::B38400));
}
