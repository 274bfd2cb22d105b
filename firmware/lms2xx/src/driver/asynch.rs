//! The async driver (feature `async`): the same [`Machine`] as the blocking [`Driver`](super::Driver),
//! its actions carried out on an `embedded-io-async` UART and an `embedded-hal-async` delay
//! (embassy's `RingBufferedUartRx` / `BufferedUart` and `embassy_time::Delay`, for instance).
//!
//! Waiting for bytes, without `select!` or an executor dependency: where the blocking driver
//! asks `ReadReady` and then sleeps, this one polls a read once ([`Action::Read`]: ready at
//! once, or nothing is available) and, when the machine then idles, waits for bytes with a
//! timeout ([`read_with_timeout`]: the delay and the read polled together in one
//! `core::future::poll_fn`, the first to finish wins), so the wait ends as soon as a byte
//! arrives. The machine sees "nothing yet" at the same moments as under the blocking driver,
//! so both drivers take the same decisions on the same line. A read that finished during the
//! idle wait is handed to the machine at its next [`Action::Read`]. The UART's `read` must be
//! cancel-safe (a read dropped unfinished loses no byte), as embassy's ring-buffered
//! (`RingBufferedUartRx`) and buffered UARTs are; a plain DMA read into the caller's buffer is
//! not.

use embedded_hal_async::delay::DelayNs;
use embedded_io_async::ErrorType;
use embedded_io_async::{Read, Write};

use core::future::{poll_fn, Future};
use core::pin::pin;
use core::task::Poll;

use super::machine::{Action, Machine, Request};
use super::{Clock, Config, Counters, DeviceState, Error, ScanData};

/// Changing the UART's baud rate, for the [`AsyncDriver`] (embedded-io-async has no notion of
/// it). Implement it on the type that joins the receive and transmit halves.
#[allow(async_fn_in_trait)]
pub trait AsyncSetBaud: ErrorType {
    /// Switches the local UART to `baud` bits per second.
    async fn set_baud(&mut self, baud: u32) -> Result<(), Self::Error>;
}

/// The LMS200 driver for async code (embassy): the blocking [`Driver`](super::Driver)'s
/// sequence, settings, timeouts, errors and counters, from the same state machine.
///
/// ```no_run
/// # async fn demo<U, D, C>(uart: U, delay: D, clock: C) -> Result<(), lms2xx::driver::Error<U::Error>>
/// # where U: embedded_io_async::Read + embedded_io_async::Write + lms2xx::driver::AsyncSetBaud,
/// #       D: embedded_hal_async::delay::DelayNs, C: lms2xx::driver::Clock {
/// use lms2xx::driver::{AsyncDriver, Config};
/// let mut lms = AsyncDriver::new(uart, delay, clock, Config::default());
/// lms.init().await?;
/// loop {
///     let scan = lms.next_scan().await?;
///     let _ranges = scan.codes(); // 361 range codes in mm
/// #   break;
/// }
/// # Ok(()) }
/// ```
pub struct AsyncDriver<U, D, C> {
    uart: U,
    delay: D,
    clock: C,
    machine: Machine,
    /// Bytes read into the machine's receive buffer during an idle wait, not yet reported.
    early: Option<usize>,
}

impl<U, D, C> AsyncDriver<U, D, C>
where
    U: Read + Write + AsyncSetBaud,
    D: DelayNs,
    C: Clock,
{
    /// A driver owning the UART, a delay and a clock. Nothing is sent until
    /// [`AsyncDriver::init`] or [`AsyncDriver::next_scan`].
    pub fn new(uart: U, delay: D, clock: C, config: Config) -> Self {
        Self {
            uart,
            delay,
            clock,
            machine: Machine::new(config),
            early: None,
        }
    }

    /// Gives back the UART, delay and clock.
    pub fn release(self) -> (U, D, C) {
        (self.uart, self.delay, self.clock)
    }

    /// Counters so far (decoder counters included).
    pub fn counters(&self) -> Counters {
        self.machine.counters()
    }

    /// What the driver knows about the device.
    pub fn device(&self) -> &DeviceState {
        self.machine.device()
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        self.machine.config()
    }

    /// The last scan delivered (empty before the first).
    pub fn last_scan(&self) -> &ScanData {
        self.machine.scan()
    }

    /// True while the device is in continuous output.
    pub fn is_streaming(&self) -> bool {
        self.machine.is_streaming()
    }

    /// Initialises the device (see the [module](super) docs) and starts continuous output.
    pub async fn init(&mut self) -> Result<(), Error<U::Error>> {
        self.run(Request::Init).await
    }

    /// Waits for the next scan, initialising first if needed and re-initialising after
    /// [`Config::silence_timeout_ms`] (at least two telegrams' time) without a scan or after a
    /// device reset.
    pub async fn next_scan(&mut self) -> Result<&ScanData, Error<U::Error>> {
        self.run(Request::NextScan).await?;
        Ok(self.machine.scan())
    }

    /// Stops continuous output (`20 25`).
    pub async fn stop(&mut self) -> Result<(), Error<U::Error>> {
        self.run(Request::Stop).await
    }

    /// Sends the reset command `10` and waits for `91`; the device then restarts at 9600.
    pub async fn reset_device(&mut self) -> Result<(), Error<U::Error>> {
        self.run(Request::ResetDevice).await
    }

    /// Carries out the machine's actions until `request` ends.
    async fn run(&mut self, request: Request) -> Result<(), Error<U::Error>> {
        self.machine.start(request);
        loop {
            let now = self.clock.now_ms();
            let io = match self.machine.step(now) {
                Action::Write(bytes) => write_all(&mut self.uart, bytes).await,
                Action::SetBaud(bps) => self.uart.set_baud(bps).await.map_err(Error::Io),
                Action::Read => {
                    let n = match self.early.take() {
                        Some(n) => Ok(n),
                        None => read_now(&mut self.uart, self.machine.rx_buffer()).await,
                    };
                    n.map(|n| self.machine.received(n)).map_err(Error::Io)
                }
                Action::Idle(us) => {
                    let buf = self.machine.rx_buffer();
                    match read_with_timeout(&mut self.uart, buf, &mut self.delay, us).await {
                        Ok(n) => {
                            self.early = n;
                            Ok(())
                        }
                        Err(e) => Err(Error::Io(e)),
                    }
                }
                Action::Wait(ms) => {
                    self.delay.delay_ms(ms).await;
                    Ok(())
                }
                Action::Scan | Action::Done => return Ok(()),
                Action::Failed(e) => return Err(e.widen()),
            };
            if let Err(e) = io {
                self.machine.abort();
                return Err(e);
            }
        }
    }
}

/// The bytes available now: a read polled once, 0 when it is not ready at once (the read is
/// then dropped: it must be cancel-safe).
async fn read_now<U: Read>(uart: &mut U, buf: &mut [u8]) -> Result<usize, U::Error> {
    let mut read = pin!(uart.read(buf));
    poll_fn(|cx| match read.as_mut().poll(cx) {
        Poll::Ready(r) => Poll::Ready(r),
        Poll::Pending => Poll::Ready(Ok(0)),
    })
    .await
}

async fn write_all<U: Write>(uart: &mut U, mut buf: &[u8]) -> Result<(), Error<U::Error>> {
    while !buf.is_empty() {
        match uart.write(buf).await {
            Ok(0) => return Err(Error::WriteZero),
            Ok(n) => buf = buf.get(n..).unwrap_or(&[]),
            Err(e) => return Err(Error::Io(e)),
        }
    }
    uart.flush().await.map_err(Error::Io)
}

/// Reads into `buf`, waiting at most `timeout_us`: `Ok(Some(n))` when the read finished first,
/// `Ok(None)` when the delay did (the read is then dropped: it must be cancel-safe). The delay
/// is polled first, so a delay that is over at once ends the wait without a read.
///
/// ```
/// # fn block_on<F: core::future::Future>(f: F) -> F::Output {
/// #     let mut f = core::pin::pin!(f);
/// #     let mut cx = core::task::Context::from_waker(core::task::Waker::noop());
/// #     loop { if let core::task::Poll::Ready(v) = f.as_mut().poll(&mut cx) { return v; } }
/// # }
/// /// A delay that is pending once, then over.
/// struct OnePoll;
/// impl embedded_hal_async::delay::DelayNs for OnePoll {
///     async fn delay_ns(&mut self, _: u32) {
///         let mut polled = false;
///         core::future::poll_fn(|_| {
///             if core::mem::replace(&mut polled, true) {
///                 core::task::Poll::Ready(())
///             } else {
///                 core::task::Poll::Pending
///             }
///         })
///         .await
///     }
/// }
/// // A read that has bytes at once wins over a delay still running.
/// let mut uart: &[u8] = &[1, 2, 3];
/// let mut buf = [0u8; 8];
/// let r = block_on(lms2xx::driver::read_with_timeout(&mut uart, &mut buf, &mut OnePoll, 100));
/// assert_eq!(r, Ok(Some(3)));
/// ```
pub async fn read_with_timeout<U: Read, D: DelayNs>(
    uart: &mut U,
    buf: &mut [u8],
    delay: &mut D,
    timeout_us: u32,
) -> Result<Option<usize>, U::Error> {
    let mut read = pin!(uart.read(buf));
    let mut timer = pin!(delay.delay_us(timeout_us));
    poll_fn(|cx| {
        if timer.as_mut().poll(cx).is_ready() {
            return Poll::Ready(Ok(None));
        }
        read.as_mut().poll(cx).map(|r| r.map(Some))
    })
    .await
}
