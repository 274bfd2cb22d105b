//! Helpers shared by the firmware's host tests.
#![allow(dead_code)]

use std::cell::Cell;
use std::rc::Rc;

use firmware::lms::driver::Clock;

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
