//! Helpers shared by the firmware's host tests.
#![allow(dead_code)]

use std::cell::Cell;
use std::rc::Rc;

use lms2xx::driver::Clock;

/// Simulated time in µs, shared by every clone: the driver's delays advance it and its clock
/// reads it, so a test's waits take no real time.
#[derive(Clone, Default)]
pub struct Time(pub Rc<Cell<u64>>);

impl embedded_hal::delay::DelayNs for Time {
    fn delay_ns(&mut self, ns: u32) {
        self.0.set(self.0.get() + u64::from(ns).div_ceil(1000));
    }
}

impl Clock for Time {
    fn now_ms(&mut self) -> u32 {
        (self.0.get() / 1000) as u32
    }
}
pub mod lms;

/// A B0 telegram (address 0x80, status 0x10, unit mm) of `count` values `first`, `first + 1`,
/// …, encoded by the firmware's encoder.
pub fn b0_telegram(count: u16, first: u16) -> Vec<u8> {
    let mut payload = vec![0xB0];
    payload.extend_from_slice(&((0b01u16 << 14) | count).to_le_bytes());
    payload.extend((0..count).flat_map(|i| (first + i).to_le_bytes()));
    payload.push(0x10);
    let mut raw = vec![0u8; 2 * usize::from(count) + 16];
    let n = lms2xx::codec::frame::encode_telegram(0x80, &payload, &mut raw).unwrap_or(0);
    raw.truncate(n);
    raw
}
