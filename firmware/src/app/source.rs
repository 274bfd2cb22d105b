//! Where the application's scans come from: [`ScanSource`], implemented by the LMS driver.

use embedded_hal::delay::DelayNs;
use embedded_io::{Read, ReadReady, Write};

use super::{RawScan, ScanDataExt};
use lms2xx::driver::{self, Clock, Driver, SetBaud};
use pfe_frame::Counters;

/// Where scans come from (the LMS200 driver through a small adapter, or a test double).
pub trait ScanSource {
    /// Why no scan could be delivered.
    type Error: core::fmt::Debug;
    /// Blocks (with a timeout) until the next complete scan; returns it with the link
    /// counters after it.
    fn next_scan(&mut self) -> Result<(RawScan<'_>, Counters), Self::Error>;
}

/// The driver's counters as the output frame's link counters (`crc_dropped` = CRC errors +
/// bad lengths / overflows).
pub fn link_counters(c: &driver::Counters) -> Counters {
    Counters {
        telegrams_ok: c.telegrams_ok,
        crc_dropped: c.crc_errors.saturating_add(c.bad_length),
        bytes_skipped: c.bytes_skipped,
        reinits: c.reinits,
    }
}

/// The LMS200 driver as a scan source: geometry, unit and measuring mode from the driver,
/// counters as the output's.
impl<U, D, C> ScanSource for Driver<U, D, C>
where
    U: Read + Write + ReadReady + SetBaud,
    U::Error: core::fmt::Debug,
    D: DelayNs,
    C: Clock,
{
    type Error = lms2xx::driver::Error<U::Error>;

    fn next_scan(&mut self) -> Result<(RawScan<'_>, Counters), Self::Error> {
        Driver::next_scan(self)?;
        let counters = link_counters(&self.counters());
        Ok((self.last_scan().raw(), counters))
    }
}
