//! Fuzz target `lms_driver_async`: the async LMS driver on the `lms_driver` target's input
//! (same layout, same mock line, emulator and time budgets; see [`crate::lms_driver`]), beside
//! the blocking driver on a second copy of the same line. Both run the one protocol state
//! machine, so every call must end the same way (error, or scan with the same sequence
//! number, time, value count and first value) and the counters must agree at the end; the
//! blocking driver's `poll` calls are `next_scan` here, as the async driver has none.
//!
//! The mock's async read is pending while nothing has arrived; its delay completes at once
//! (advancing the simulated time), so the executor is a no-op-waker loop.

use std::convert::Infallible;
use std::future::{poll_fn, Future};
use std::pin::pin;
use std::task::{Context, Poll, Waker};

use lms2xx::driver::{AsyncDriver, AsyncSetBaud, Counters};

use crate::lms_driver::{
    blocking_session_without_poll, scan_outcome, session, Call, Calls, Mock, Outcome,
};

/// Polls `f` to completion; pending for a million polls is a hang.
fn block_on<F: Future>(f: F) -> F::Output {
    let mut f = pin!(f);
    let mut cx = Context::from_waker(Waker::noop());
    for _ in 0..1_000_000 {
        if let Poll::Ready(v) = f.as_mut().poll(&mut cx) {
            return v;
        }
    }
    panic!("the async driver stayed pending");
}

impl embedded_io_async::ErrorType for Mock {
    type Error = Infallible;
}

impl embedded_io_async::Read for Mock {
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, Infallible> {
        poll_fn(|_| {
            if embedded_io::ReadReady::read_ready(self).unwrap_or(false) {
                Poll::Ready(embedded_io::Read::read(self, buf))
            } else {
                Poll::Pending
            }
        })
        .await
    }
}

impl embedded_io_async::Write for Mock {
    async fn write(&mut self, buf: &[u8]) -> Result<usize, Infallible> {
        embedded_io::Write::write(self, buf)
    }
    async fn flush(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
}

impl AsyncSetBaud for Mock {
    async fn set_baud(&mut self, baud: u32) -> Result<(), Infallible> {
        lms2xx::driver::SetBaud::set_baud(self, baud)
    }
}

impl embedded_hal_async::delay::DelayNs for Mock {
    async fn delay_ns(&mut self, ns: u32) {
        embedded_hal::delay::DelayNs::delay_ns(self, ns);
    }
}

struct Async(AsyncDriver<Mock, Mock, Mock>);

impl Calls for Async {
    fn call(&mut self, c: Call) -> Outcome {
        let d = &mut self.0;
        let done = |r: Result<(), _>| r.map_or_else(Outcome::Failed, |()| Outcome::Done);
        match c {
            Call::Init => done(block_on(d.init())),
            Call::Stop => done(block_on(d.stop())),
            Call::ResetDevice => done(block_on(d.reset_device())),
            Call::Poll | Call::NextScan => match block_on(d.next_scan()) {
                Ok(s) => scan_outcome(s),
                Err(e) => Outcome::Failed(e),
            },
        }
    }
    fn counters(&self) -> Counters {
        self.0.counters()
    }
}

/// Runs the async driver's calls and the blocking driver's on the same script; they must
/// agree call by call. Returns the number of scans delivered.
pub fn lms_driver_async(data: &[u8]) -> usize {
    let Some(a) = session(data, false, |m, cfg| {
        Async(AsyncDriver::new(m.clone(), m.clone(), m, cfg))
    }) else {
        return 0;
    };
    let b = blocking_session_without_poll(data);
    assert_eq!(Some(&a), b.as_ref(), "async and blocking drivers differ");
    a.calls
        .iter()
        .filter(|(_, o)| matches!(o, Outcome::Scan(..)))
        .count()
}
