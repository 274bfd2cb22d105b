//! Streaming: scans out of continuous output, device resets and silence re-initialise.

use embedded_hal::delay::DelayNs;
use embedded_io::{Read, ReadReady, Write};

use super::pump::Rx;
use super::{Clock, Driver, ScanData, SetBaud};
use crate::codec::reply::code as rcode;
use crate::codec::types::Variant;
use crate::driver::Error;

impl<U, D, C> Driver<U, D, C>
where
    U: Read + Write + ReadReady + SetBaud,
    D: DelayNs,
    C: Clock,
{
    /// Non-blocking: decodes whatever bytes are available and returns a scan if one completed.
    /// Does not re-initialise; [`Driver::next_scan`] does.
    pub fn poll(&mut self) -> Result<Option<&ScanData>, Error<U::Error>> {
        loop {
            match self.pump()? {
                None => return Ok(None),
                Some(Rx::Scan) => {
                    if self.accept_scan() {
                        return Ok(Some(&self.scan));
                    }
                }
                Some(Rx::Reply(c)) => self.unexpected_reply(c),
                Some(_) => {}
            }
        }
    }

    /// [`Config::silence_timeout_ms`](super::Config::silence_timeout_ms), but at least two scan telegrams' time at the current
    /// baud rate (at 9600 Bd one 361-value telegram takes 760 ms, a 401-value one 845 ms).
    pub(super) fn silence_limit_ms(&self) -> u32 {
        let bps = self.device.baud.unwrap_or(self.config.baud).bps().max(1);
        let bytes = (self.device.variant.values() as u32).saturating_mul(2) + 10;
        let two_telegrams = bytes.saturating_mul(2 * 10 * 1000) / bps;
        self.config.silence_timeout_ms.max(two_telegrams)
    }

    pub(super) fn accept_scan(&mut self) -> bool {
        let unit_ok = self.device.unit.is_none_or(|u| u == self.scan.unit());
        let looks_reset = !unit_ok || self.scan.status.restart();
        if looks_reset && self.reset_check_armed {
            // The device lost its configuration (e.g. reset to cm): re-initialise, once. When
            // the scans after that look the same (a restart flag that stays set, a unit the
            // configuration does not name), that is how the device reports: they are used,
            // with the unit they carry.
            self.reset_check_armed = false;
            self.note_reset("scan with another unit or the restart flag");
            return false;
        }
        self.reset_check_armed |= !looks_reset;
        if !unit_ok {
            self.device.unit = Some(self.scan.unit());
        }
        // The value count names the variant (the five counts differ): a device that was not
        // set to the configured one, or changed, is still described right.
        if self.scan.len() != self.device.variant.values() {
            if let Some(v) = Variant::from_values(self.scan.len()) {
                self.device.variant = v;
            }
        }
        self.counters.scans = self.counters.scans.saturating_add(1);
        self.scan.seq = self.counters.scans;
        self.scan.variant = self.device.variant;
        self.scan_ok = true;
        self.last_scan_ms = self.clock.now_ms();
        self.scan.time_ms = self.last_scan_ms;
        true
    }

    pub(super) fn unexpected_reply(&mut self, c: u8) {
        // A late A0 answering a retried command is not a reset.
        let late_answer = c == rcode::MODE
            && self.elapsed_since(self.last_cmd_ms)
                < self.config.reply_timeout_ms.saturating_mul(2);
        if matches!(c, rcode::POWER_ON | rcode::RESET_ACK | rcode::MODE) && !late_answer {
            self.note_reset("unrequested reply");
        }
    }

    /// Waits for the next scan, initialising first if needed and re-initialising after
    /// [`Config::silence_timeout_ms`](super::Config::silence_timeout_ms) (at least two telegrams' time) without a scan or after a
    /// device reset.
    pub fn next_scan(&mut self) -> Result<&ScanData, Error<U::Error>> {
        let mut reinits = 0u8;
        if !self.streaming {
            self.init()?;
        }
        loop {
            // What is waiting is read first: after a slow caller the scans that arrived
            // meanwhile are in the receive buffer, and the line was not silent.
            let drained = match self.pump()? {
                Some(Rx::Scan) => {
                    if self.accept_scan() {
                        return Ok(&self.scan);
                    }
                    false
                }
                Some(Rx::Reply(c)) => {
                    self.unexpected_reply(c);
                    false
                }
                Some(_) => false,
                None => true,
            };
            // The limit is at least the configured timeout: compare with that first (this
            // runs at every poll).
            let silent = self.elapsed_since(self.last_scan_ms);
            if self.reset_seen
                || (drained
                    && silent >= self.config.silence_timeout_ms
                    && silent >= self.silence_limit_ms())
            {
                log!(
                    warn,
                    "lms: re-initialising ({}, {} ms since the last scan)",
                    if self.reset_seen {
                        "device reset"
                    } else {
                        "silence"
                    },
                    self.elapsed_since(self.last_scan_ms)
                );
                if reinits >= self.config.max_reinits_per_call {
                    self.streaming = false;
                    return Err(Error::Silence);
                }
                reinits += 1;
                self.init()?;
                continue;
            }
            if drained {
                self.idle();
            }
        }
    }
}
