//! Initialisation: baud probe and switch, type, status, configuration, variant, unit and
//! measuring mode, continuous output.

use embedded_hal::delay::DelayNs;
use embedded_io::{Read, ReadReady, Write};

use super::config::poll_interval;
use super::{Clock, Driver, SetBaud};
use crate::codec::command::{code, Command, PASSWORD};
use crate::codec::reply::{ConfigBlock, Reply, StatusInfo};
use crate::codec::types::Baud;
use crate::driver::Error;

impl<U, D, C> Driver<U, D, C>
where
    U: Read + Write + ReadReady + SetBaud,
    D: DelayNs,
    C: Clock,
{
    pub(super) fn set_local_baud(&mut self, baud: Baud) -> Result<(), Error<U::Error>> {
        self.uart.set_baud(baud.bps()).map_err(Error::Io)?;
        self.idle_us = poll_interval(self.config.poll_interval_us, baud);
        self.decoder.clear();
        self.rx_pos = 0;
        self.rx_len = 0;
        Ok(())
    }

    /// Finds the device's baud rate with `20 25` (which also stops continuous output).
    pub(super) fn probe(&mut self) -> Result<Baud, Error<U::Error>> {
        let mut order = [Baud::B9600; 6];
        let mut k = 0;
        let first = [self.device.baud, Some(self.config.baud)];
        for b in first.into_iter().flatten().chain(Baud::ALL) {
            if !order.get(..k).unwrap_or(&[]).contains(&b) {
                if let Some(slot) = order.get_mut(k) {
                    *slot = b;
                    k += 1;
                }
            }
        }
        for round in 0..self.config.tries.max(1) {
            for i in 0..k {
                let Some(&b) = order.get(i) else { break };
                self.set_local_baud(b)?;
                // A telegram at 9600 takes up to 850 ms: allow one to finish first.
                let timeout = self.config.reply_timeout_ms;
                match self.transact_n(&Command::OnRequest, timeout, 1) {
                    Ok(()) => {
                        log!(info, "lms: device answers at {} baud", b.bps());
                        self.device.baud = Some(b);
                        return Ok(b);
                    }
                    Err(Error::Timeout { .. } | Error::Nak { .. } | Error::DeviceReset) => {}
                    Err(e) => return Err(e),
                }
                let _ = round;
            }
        }
        self.device.baud = None;
        Err(Error::NoDevice)
    }

    /// Initialises the device (see the module docs) and starts continuous output.
    pub fn init(&mut self) -> Result<(), Error<U::Error>> {
        if !self.config.variant.is_valid() {
            return Err(Error::InvalidConfig);
        }
        if self.initialised_once {
            self.counters.reinits = self.counters.reinits.saturating_add(1);
        }
        self.initialised_once = true;
        self.streaming = false;
        self.reset_seen = false;
        let found = self.probe()?;
        if found != self.config.baud {
            let target = self.config.baud;
            match self.mode(&Command::SetBaud(target)) {
                Ok(()) => {
                    // The reply came at the old rate; the device switches after sending it.
                    self.set_local_baud(target)?;
                    self.device.baud = Some(target);
                    self.delay.delay_ms(self.config.baud_switch_wait_ms);
                    self.mode(&Command::OnRequest)?;
                }
                // A device that cannot run at the rate (an RS-232 LMS200 has no 500 000 Bd)
                // is used at the rate it answered at.
                Err(Error::Rejected { .. } | Error::Nak { .. }) => {
                    log!(
                        warn,
                        "lms: {} baud refused, staying at {}",
                        target.bps(),
                        found.bps()
                    );
                    self.counters.baud_refused = self.counters.baud_refused.saturating_add(1);
                }
                Err(e) => return Err(e),
            }
        }
        // Type string and status: informative, so a device that refuses them (92) or does
        // not answer is still used (the variant then comes from the 3B below).
        if self.optional(&Command::Type)? {
            if let Some(Reply::Type(s)) = self.parsed().map(|p| p.reply) {
                let mut t = [0u8; 20];
                for (d, s) in t.iter_mut().zip(s) {
                    *d = *s;
                }
                self.device.type_string = t;
            }
        }
        let mut variant_known = false;
        if self.optional(&Command::Status)? {
            if let Some(Reply::Status(s)) = self.parsed().map(|p| p.reply) {
                let s = StatusInfo::new(s.payload());
                if let Some(v) = s.variant() {
                    self.device.variant = v;
                    variant_known = true;
                }
            }
        }
        // Configuration (a device that does not report it is used as it is: its scans carry
        // their unit).
        let block = match self.transact(&Command::GetConfig) {
            Ok(()) => match self.parsed().map(|p| p.reply) {
                Some(Reply::Config(c)) => Some(c),
                _ => {
                    return Err(Error::BadReply {
                        command: code::GET_CONFIG,
                    })
                }
            },
            Err(Error::Rejected { .. } | Error::Nak { .. }) => None,
            Err(e) => return Err(e),
        };
        match &block {
            Some(b) => self.apply_block(b),
            None => self.device.unit = None,
        }
        // Variant (also when the status did not say which one is set).
        if !variant_known || self.device.variant != self.config.variant {
            let v = self.config.variant;
            match self.transact(&Command::SetVariant(v)) {
                Ok(()) => match self.parsed().map(|p| p.reply) {
                    Some(Reply::Variant { ok: true, .. }) => self.device.variant = v,
                    Some(Reply::Variant { ok: false, .. }) => self.variant_refused(),
                    _ => {
                        return Err(Error::BadReply {
                            command: code::VARIANT,
                        })
                    }
                },
                Err(Error::Rejected { .. } | Error::Nak { .. }) => self.variant_refused(),
                Err(e) => return Err(e),
            }
        }
        // Unit and measuring mode. A device that refuses the change (password, no 77) or
        // does not report its configuration is used as configured: every scan carries its
        // unit, and ranges are scaled by it.
        if !self.set_unit_and_mode(block)? {
            log!(
                warn,
                "lms: unit / measuring mode not set, using the device's"
            );
            self.counters.config_refused = self.counters.config_refused.saturating_add(1);
        }
        self.scan.variant = self.device.variant;
        self.mode(&Command::Continuous)?;
        self.streaming = true;
        self.reset_seen = false;
        self.last_scan_ms = self.clock.now_ms();
        Ok(())
    }

    /// The device keeps its variant: the one its status named, else the one its scans'
    /// value count gives (see [`Self::accept_scan`]).
    pub(super) fn variant_refused(&mut self) {
        log!(warn, "lms: variant refused, using the device's");
        self.counters.variant_refused = self.counters.variant_refused.saturating_add(1);
    }

    /// Sets [`Config::unit`] and the measuring mode where `block` (the device's configuration)
    /// differs; `Ok(false)` when the device refused or did not report its configuration.
    pub(super) fn set_unit_and_mode(
        &mut self,
        block: Option<ConfigBlock>,
    ) -> Result<bool, Error<U::Error>> {
        let Some(mut block) = block else {
            return Ok(false);
        };
        let want_mode = self.config.measuring_mode.unwrap_or(block.measuring_mode());
        if block.unit() == Some(self.config.unit) && block.measuring_mode() == want_mode {
            return Ok(true);
        }
        block.set_unit(self.config.unit);
        block.set_measuring_mode(want_mode);
        match self.write_config(&block) {
            Ok(()) => Ok(true),
            Err(Error::Rejected { .. } | Error::Nak { .. }) => {
                self.mode(&Command::OnRequest)?;
                Ok(false)
            }
            Err(e) => Err(e),
        }
    }

    /// Installation mode, `77` with `block`, back to request mode.
    pub(super) fn write_config(&mut self, block: &ConfigBlock) -> Result<(), Error<U::Error>> {
        self.mode(&Command::Install(&PASSWORD))?;
        let cmd = Command::SetConfig(block);
        self.transact_n(&cmd, self.config.config_timeout_ms, self.config.tries)?;
        match self.parsed().map(|p| p.reply) {
            Some(Reply::ConfigSet { ok: true, config }) => self.apply_block(&config),
            Some(Reply::ConfigSet { ok: false, .. }) => {
                return Err(Error::Rejected {
                    command: code::SET_CONFIG,
                    code: 0,
                })
            }
            _ => {
                return Err(Error::BadReply {
                    command: code::SET_CONFIG,
                })
            }
        }
        self.mode(&Command::OnRequest)
    }

    pub(super) fn apply_block(&mut self, b: &ConfigBlock) {
        self.device.unit = b.unit();
        self.device.measuring_mode = b.measuring_mode();
        self.device.realtime_index = b.realtime_index();
    }

    /// Stops continuous output (`20 25`).
    pub fn stop(&mut self) -> Result<(), Error<U::Error>> {
        self.streaming = false;
        self.mode(&Command::OnRequest)
    }

    /// Sends the reset command `10` and waits for `91`; the device then restarts at 9600.
    pub fn reset_device(&mut self) -> Result<(), Error<U::Error>> {
        self.streaming = false;
        self.transact(&Command::Reset)?;
        self.device.baud = Some(Baud::B9600);
        Ok(())
    }
}
