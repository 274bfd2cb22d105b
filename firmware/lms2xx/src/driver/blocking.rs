//! The blocking driver: a loop that carries out the [`Machine`]'s actions on an `embedded-io`
//! UART, busy-polling through `DelayNs`.

use embedded_hal::delay::DelayNs;
use embedded_io::{Read, ReadReady, Write};

use super::machine::{Action, Machine, Request};
use super::{Clock, Config, Counters, DeviceState, Error, ScanData, SetBaud};

/// The LMS200 driver. See the [module](super) docs for the sequence.
///
/// ```no_run
/// # fn demo<U, D, C>(uart: U, delay: D, clock: C) -> Result<(), lms2xx::driver::Error<U::Error>>
/// # where U: embedded_io::Read + embedded_io::Write + embedded_io::ReadReady + lms2xx::driver::SetBaud,
/// #       D: embedded_hal::delay::DelayNs, C: lms2xx::driver::Clock {
/// use lms2xx::driver::{Config, Driver};
/// let mut lms = Driver::new(uart, delay, clock, Config::default());
/// lms.init()?;
/// loop {
///     let scan = lms.next_scan()?;
///     let _ranges = scan.codes(); // 361 range codes in mm
/// #   break;
/// }
/// let (_uart, _delay, _clock) = lms.release();
/// # Ok(()) }
/// ```
pub struct Driver<U, D, C> {
    uart: U,
    delay: D,
    clock: C,
    machine: Machine,
}

/// How an operation ended.
enum End {
    Scan,
    Done,
}

impl<U, D, C> Driver<U, D, C>
where
    U: Read + Write + ReadReady + SetBaud,
    D: DelayNs,
    C: Clock,
{
    /// A driver owning the UART, a delay and a clock. Nothing is sent until [`Driver::init`] or
    /// [`Driver::next_scan`].
    pub fn new(uart: U, delay: D, clock: C, config: Config) -> Self {
        Self {
            uart,
            delay,
            clock,
            machine: Machine::new(config),
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
    pub fn init(&mut self) -> Result<(), Error<U::Error>> {
        self.run(Request::Init).map(|_| ())
    }

    /// Waits for the next scan, initialising first if needed and re-initialising after
    /// [`Config::silence_timeout_ms`] (at least two telegrams' time) without a scan or after a
    /// device reset.
    pub fn next_scan(&mut self) -> Result<&ScanData, Error<U::Error>> {
        self.run(Request::NextScan)?;
        Ok(self.machine.scan())
    }

    /// Non-blocking: decodes whatever bytes are available and returns a scan if one completed.
    /// Does not re-initialise; [`Driver::next_scan`] does.
    pub fn poll(&mut self) -> Result<Option<&ScanData>, Error<U::Error>> {
        Ok(match self.run(Request::Poll)? {
            End::Scan => Some(self.machine.scan()),
            End::Done => None,
        })
    }

    /// Stops continuous output (`20 25`).
    pub fn stop(&mut self) -> Result<(), Error<U::Error>> {
        self.run(Request::Stop).map(|_| ())
    }

    /// Sends the reset command `10` and waits for `91`; the device then restarts at 9600.
    pub fn reset_device(&mut self) -> Result<(), Error<U::Error>> {
        self.run(Request::ResetDevice).map(|_| ())
    }

    /// Carries out the machine's actions until `request` ends.
    fn run(&mut self, request: Request) -> Result<End, Error<U::Error>> {
        self.machine.start(request);
        loop {
            let now = self.clock.now_ms();
            let io = match self.machine.step(now) {
                Action::Write(bytes) => write_all(&mut self.uart, bytes),
                Action::SetBaud(bps) => self.uart.set_baud(bps).map_err(Error::Io),
                Action::Read => match read_available(&mut self.uart, self.machine.rx_buffer()) {
                    Ok(n) => {
                        self.machine.received(n);
                        Ok(())
                    }
                    Err(e) => Err(e),
                },
                Action::Idle(us) => {
                    self.delay.delay_us(us);
                    Ok(())
                }
                Action::Wait(ms) => {
                    self.delay.delay_ms(ms);
                    Ok(())
                }
                Action::Scan => return Ok(End::Scan),
                Action::Done => return Ok(End::Done),
                Action::Failed(e) => return Err(e.widen()),
            };
            if let Err(e) = io {
                self.machine.abort();
                return Err(e);
            }
        }
    }
}

fn write_all<U: Write>(uart: &mut U, mut buf: &[u8]) -> Result<(), Error<U::Error>> {
    while !buf.is_empty() {
        match uart.write(buf) {
            Ok(0) => return Err(Error::WriteZero),
            Ok(n) => buf = buf.get(n..).unwrap_or(&[]),
            Err(e) => return Err(Error::Io(e)),
        }
    }
    uart.flush().map_err(Error::Io)
}

/// Reads what is available without blocking; 0 when nothing is (or on a spurious `Ok(0)`:
/// some HALs, or EOF on a host port).
fn read_available<U: Read + ReadReady>(
    uart: &mut U,
    buf: &mut [u8],
) -> Result<usize, Error<U::Error>> {
    if !uart.read_ready().map_err(Error::Io)? {
        return Ok(0);
    }
    uart.read(buf).map_err(Error::Io)
}
