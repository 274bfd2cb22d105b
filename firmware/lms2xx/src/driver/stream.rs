//! Streaming steps of the [`Machine`]: scans out of continuous output; device resets and
//! silence re-initialise.

use super::machine::{Machine, Op, Out, Pump, Rx, Sub};
use crate::codec::reply::code as rcode;
use crate::codec::types::Variant;
use crate::driver::Error;

impl Machine {
    /// One step of [`Request::Poll`](super::machine::Request::Poll): decodes whatever bytes
    /// are available; a scan if one completed. Does not re-initialise.
    pub(super) fn poll_step(&mut self, now: u32) -> Out {
        loop {
            match self.pump() {
                Pump::NeedRead => return Out::Read,
                Pump::Empty => return Out::Done,
                Pump::Event(Rx::Scan) => {
                    if self.accept_scan(now) {
                        return Out::Scan;
                    }
                }
                Pump::Event(Rx::Reply(c)) => self.unexpected_reply(c, now),
                Pump::Event(_) => {}
            }
        }
    }

    /// [`Config::silence_timeout_ms`](super::Config::silence_timeout_ms), but at least two
    /// scan telegrams' time at the current baud rate (at 9600 Bd one 361-value telegram takes
    /// 760 ms, a 401-value one 845 ms).
    pub(super) fn silence_limit_ms(&self) -> u32 {
        let bps = self.device.baud.unwrap_or(self.config.baud).bps().max(1);
        let bytes = (self.device.variant.values() as u32).saturating_mul(2) + 10;
        let two_telegrams = bytes.saturating_mul(2 * 10 * 1000) / bps;
        self.config.silence_timeout_ms.max(two_telegrams)
    }

    pub(super) fn accept_scan(&mut self, now: u32) -> bool {
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
        self.last_scan_ms = now;
        self.scan.time_ms = now;
        true
    }

    pub(super) fn unexpected_reply(&mut self, c: u8, now: u32) {
        // A late A0 answering a retried command is not a reset.
        let late_answer = c == rcode::MODE
            && now.wrapping_sub(self.last_cmd_ms) < self.config.reply_timeout_ms.saturating_mul(2);
        if matches!(c, rcode::POWER_ON | rcode::RESET_ACK | rcode::MODE) && !late_answer {
            self.note_reset("unrequested reply");
        }
    }

    /// One step of [`Request::NextScan`](super::machine::Request::NextScan): waits for the
    /// next scan, initialising first if needed and re-initialising after
    /// [`Config::silence_timeout_ms`](super::Config::silence_timeout_ms) (at least two
    /// telegrams' time) without a scan or after a device reset.
    pub(super) fn next_scan_step(&mut self, now: u32) -> Out {
        loop {
            let Op::NextScan { reinits, initing } = self.op else {
                return Out::Done;
            };
            if initing {
                match self.init_step(now) {
                    Sub::Out(o) => return o,
                    Sub::Finished(Ok(())) => {
                        self.op = Op::NextScan {
                            reinits,
                            initing: false,
                        }
                    }
                    Sub::Finished(Err(e)) => return Out::Failed(e),
                }
                continue;
            }
            // What is waiting is read first: after a slow caller the scans that arrived
            // meanwhile are in the receive buffer, and the line was not silent.
            let drained = match self.pump() {
                Pump::NeedRead => return Out::Read,
                Pump::Event(Rx::Scan) => {
                    if self.accept_scan(now) {
                        return Out::Scan;
                    }
                    false
                }
                Pump::Event(Rx::Reply(c)) => {
                    self.unexpected_reply(c, now);
                    false
                }
                Pump::Event(_) => false,
                Pump::Empty => true,
            };
            // The limit is at least the configured timeout: compare with that first (this
            // runs at every poll).
            let silent = now.wrapping_sub(self.last_scan_ms);
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
                    silent
                );
                if reinits >= self.config.max_reinits_per_call {
                    self.streaming = false;
                    return Out::Failed(Error::Silence);
                }
                self.init = super::init::InitStep::Start;
                self.op = Op::NextScan {
                    reinits: reinits.saturating_add(1),
                    initing: true,
                };
                continue;
            }
            if drained {
                return Out::Idle(self.idle_us);
            }
        }
    }
}
