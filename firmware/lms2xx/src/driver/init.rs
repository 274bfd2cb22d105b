//! Initialisation steps of the [`Machine`]: baud probe and switch, type, status,
//! configuration, variant, unit and measuring mode, continuous output.

use super::machine::{Check, Machine, MachineError, Out, Sub};
use crate::codec::command::{code, Command, PASSWORD};
use crate::codec::reply::{Reply, StatusInfo};
use crate::codec::types::Baud;
use crate::driver::Error;

/// Where the initialisation is; `…Txn` steps wait for their transaction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum InitStep {
    Start,
    Probe { round: u8, i: u8 },
    ProbeTxn { round: u8, i: u8, baud: Baud },
    BaudTxn,
    BaudWait,
    BaudConfirmTxn,
    TypeTxn,
    StatusTxn,
    ConfigTxn,
    VariantTxn,
    InstallTxn,
    SetConfigTxn,
    ConfigBackTxn,
    RefusedBackTxn,
    ContinuousTxn,
}

/// `Sub::Finished(Err(e))` out of a `Result`.
macro_rules! tri {
    ($e:expr) => {
        match $e {
            Ok(v) => v,
            Err(e) => return Sub::Finished(Err(e)),
        }
    };
}

/// The transaction's end, or its action handed out.
macro_rules! txn {
    ($self:ident, $now:ident) => {
        match $self.txn_step($now) {
            Sub::Out(o) => return Sub::Out(o),
            Sub::Finished(r) => r,
        }
    };
}

impl Machine {
    /// One step of the initialisation (see the [driver](super) docs).
    pub(super) fn init_step(&mut self, now: u32) -> Sub<()> {
        use InitStep as S;
        loop {
            match self.init {
                S::Start => {
                    if !self.config.variant.is_valid() {
                        return Sub::Finished(Err(Error::InvalidConfig));
                    }
                    if self.initialised_once {
                        self.counters.reinits = self.counters.reinits.saturating_add(1);
                    }
                    self.initialised_once = true;
                    self.streaming = false;
                    self.reset_seen = false;
                    self.probe_order_fill();
                    self.init = S::Probe { round: 0, i: 0 };
                }
                // Finds the device's baud rate with `20 25` (which also stops continuous output).
                S::Probe { round, i } => {
                    if round >= self.config.tries.max(1) {
                        self.device.baud = None;
                        return Sub::Finished(Err(Error::NoDevice));
                    }
                    let Some(&baud) = self
                        .probe_order
                        .get(usize::from(i))
                        .filter(|_| usize::from(i) < self.probe_len)
                    else {
                        self.init = S::Probe {
                            round: round.saturating_add(1),
                            i: 0,
                        };
                        continue;
                    };
                    let out = self.set_local_baud(baud);
                    // A telegram at 9600 takes up to 850 ms: allow one to finish first.
                    let timeout = self.config.reply_timeout_ms;
                    tri!(self.begin_n(&Command::OnRequest, Check::Plain, timeout, 1));
                    self.init = S::ProbeTxn { round, i, baud };
                    return Sub::Out(out);
                }
                S::ProbeTxn { round, i, baud } => match txn!(self, now) {
                    Ok(()) => {
                        log!(info, "lms: device answers at {} baud", baud.bps());
                        self.device.baud = Some(baud);
                        self.found = baud;
                        if baud != self.config.baud {
                            tri!(self.begin(&Command::SetBaud(self.config.baud), Check::Mode));
                            self.init = S::BaudTxn;
                        } else {
                            tri!(self.start_type());
                        }
                    }
                    Err(Error::Timeout { .. } | Error::Nak { .. } | Error::DeviceReset) => {
                        self.init = S::Probe {
                            round,
                            i: i.saturating_add(1),
                        };
                    }
                    Err(e) => return Sub::Finished(Err(e)),
                },
                S::BaudTxn => match txn!(self, now) {
                    Ok(()) => {
                        // The reply came at the old rate; the device switches after sending it.
                        let target = self.config.baud;
                        let out = self.set_local_baud(target);
                        self.device.baud = Some(target);
                        self.init = S::BaudWait;
                        return Sub::Out(out);
                    }
                    // A device that cannot run at the rate (an RS-232 LMS200 has no 500 000 Bd)
                    // is used at the rate it answered at.
                    Err(Error::Rejected { .. } | Error::Nak { .. }) => {
                        log!(
                            warn,
                            "lms: {} baud refused, staying at {}",
                            self.config.baud.bps(),
                            self.found.bps()
                        );
                        self.counters.baud_refused = self.counters.baud_refused.saturating_add(1);
                        tri!(self.start_type());
                    }
                    Err(e) => return Sub::Finished(Err(e)),
                },
                S::BaudWait => {
                    tri!(self.begin(&Command::OnRequest, Check::Mode));
                    self.init = S::BaudConfirmTxn;
                    return Sub::Out(Out::Wait(self.config.baud_switch_wait_ms));
                }
                S::BaudConfirmTxn => {
                    tri!(txn!(self, now));
                    tri!(self.start_type());
                }
                // Type string and status: informative, so a device that refuses them (92) or
                // does not answer is still used (the variant then comes from the 3B below).
                S::TypeTxn => {
                    if tri!(optional(txn!(self, now))) {
                        if let Some(Reply::Type(s)) = self.parsed().map(|p| p.reply) {
                            let mut t = [0u8; 20];
                            for (d, s) in t.iter_mut().zip(s) {
                                *d = *s;
                            }
                            self.device.type_string = t;
                        }
                    }
                    self.variant_known = false;
                    tri!(self.begin(&Command::Status, Check::Plain));
                    self.init = S::StatusTxn;
                }
                S::StatusTxn => {
                    if tri!(optional(txn!(self, now))) {
                        if let Some(Reply::Status(s)) = self.parsed().map(|p| p.reply) {
                            let s = StatusInfo::new(s.payload());
                            if let Some(v) = s.variant() {
                                self.device.variant = v;
                                self.variant_known = true;
                            }
                        }
                    }
                    tri!(self.begin(&Command::GetConfig, Check::Plain));
                    self.init = S::ConfigTxn;
                }
                // Configuration (a device that does not report it is used as it is: its scans
                // carry their unit).
                S::ConfigTxn => {
                    self.block = match txn!(self, now) {
                        Ok(()) => match self.parsed().map(|p| p.reply) {
                            Some(Reply::Config(c)) => Some(c),
                            _ => {
                                return Sub::Finished(Err(Error::BadReply {
                                    command: code::GET_CONFIG,
                                }))
                            }
                        },
                        Err(Error::Rejected { .. } | Error::Nak { .. }) => None,
                        Err(e) => return Sub::Finished(Err(e)),
                    };
                    match self.block {
                        Some(b) => self.apply_block(&b),
                        None => self.device.unit = None,
                    }
                    // Variant (also when the status did not say which one is set).
                    if !self.variant_known || self.device.variant != self.config.variant {
                        tri!(self.begin(&Command::SetVariant(self.config.variant), Check::Plain));
                        self.init = S::VariantTxn;
                    } else {
                        tri!(self.start_unit_and_mode());
                    }
                }
                S::VariantTxn => {
                    match txn!(self, now) {
                        Ok(()) => match self.parsed().map(|p| p.reply) {
                            Some(Reply::Variant { ok: true, .. }) => {
                                self.device.variant = self.config.variant
                            }
                            Some(Reply::Variant { ok: false, .. }) => self.variant_refused(),
                            _ => {
                                return Sub::Finished(Err(Error::BadReply {
                                    command: code::VARIANT,
                                }))
                            }
                        },
                        Err(Error::Rejected { .. } | Error::Nak { .. }) => self.variant_refused(),
                        Err(e) => return Sub::Finished(Err(e)),
                    }
                    tri!(self.start_unit_and_mode());
                }
                // Installation mode, `77` with the block, back to request mode.
                S::InstallTxn => match txn!(self, now) {
                    Ok(()) => {
                        let Some(block) = self.block else {
                            return Sub::Finished(Err(Error::BadReply {
                                command: code::SET_CONFIG,
                            }));
                        };
                        let (timeout, tries) = (self.config.config_timeout_ms, self.config.tries);
                        let cmd = Command::SetConfig(&block);
                        tri!(self.begin_n(&cmd, Check::Plain, timeout, tries));
                        self.init = S::SetConfigTxn;
                    }
                    Err(e) => tri!(self.write_config_failed(e)),
                },
                S::SetConfigTxn => {
                    let r = txn!(self, now).and_then(|()| match self.parsed().map(|p| p.reply) {
                        Some(Reply::ConfigSet { ok: true, config }) => Ok(config),
                        Some(Reply::ConfigSet { ok: false, .. }) => Err(Error::Rejected {
                            command: code::SET_CONFIG,
                            code: 0,
                        }),
                        _ => Err(Error::BadReply {
                            command: code::SET_CONFIG,
                        }),
                    });
                    match r {
                        Ok(config) => {
                            self.apply_block(&config);
                            tri!(self.begin(&Command::OnRequest, Check::Mode));
                            self.init = S::ConfigBackTxn;
                        }
                        Err(e) => tri!(self.write_config_failed(e)),
                    }
                }
                S::ConfigBackTxn => match txn!(self, now) {
                    Ok(()) => tri!(self.finish_config(true)),
                    Err(e) => tri!(self.write_config_failed(e)),
                },
                S::RefusedBackTxn => {
                    tri!(txn!(self, now));
                    tri!(self.finish_config(false));
                }
                S::ContinuousTxn => {
                    tri!(txn!(self, now));
                    self.streaming = true;
                    self.reset_seen = false;
                    self.last_scan_ms = now;
                    return Sub::Finished(Ok(()));
                }
            }
        }
    }

    /// The baud rates to probe: the one known, the configured one, then the others.
    fn probe_order_fill(&mut self) {
        let mut k = 0;
        let first = [self.device.baud, Some(self.config.baud)];
        for b in first.into_iter().flatten().chain(Baud::ALL) {
            if !self.probe_order.get(..k).unwrap_or(&[]).contains(&b) {
                if let Some(slot) = self.probe_order.get_mut(k) {
                    *slot = b;
                    k += 1;
                }
            }
        }
        self.probe_len = k;
    }

    fn start_type(&mut self) -> Result<(), MachineError> {
        self.begin(&Command::Type, Check::Plain)?;
        self.init = InitStep::TypeTxn;
        Ok(())
    }

    /// The device keeps its variant: the one its status named, else the one its scans'
    /// value count gives (see [`Self::accept_scan`]).
    fn variant_refused(&mut self) {
        log!(warn, "lms: variant refused, using the device's");
        self.counters.variant_refused = self.counters.variant_refused.saturating_add(1);
    }

    /// Unit and measuring mode. A device that refuses the change (password, no 77) or does
    /// not report its configuration is used as configured: every scan carries its unit, and
    /// ranges are scaled by it. Sets [`Config::unit`](super::Config::unit) and the measuring
    /// mode where the device's configuration differs.
    fn start_unit_and_mode(&mut self) -> Result<(), MachineError> {
        let Some(mut block) = self.block else {
            return self.finish_config(false);
        };
        let want_mode = self.config.measuring_mode.unwrap_or(block.measuring_mode());
        if block.unit() == Some(self.config.unit) && block.measuring_mode() == want_mode {
            return self.finish_config(true);
        }
        block.set_unit(self.config.unit);
        block.set_measuring_mode(want_mode);
        self.block = Some(block);
        self.begin(&Command::Install(&PASSWORD), Check::Mode)?;
        self.init = InitStep::InstallTxn;
        Ok(())
    }

    /// Writing the configuration failed with `e`: a refusal goes back to request mode and
    /// keeps the device's settings, anything else ends the initialisation.
    fn write_config_failed(&mut self, e: MachineError) -> Result<(), MachineError> {
        match e {
            Error::Rejected { .. } | Error::Nak { .. } => {
                self.begin(&Command::OnRequest, Check::Mode)?;
                self.init = InitStep::RefusedBackTxn;
                Ok(())
            }
            e => Err(e),
        }
    }

    /// Unit and mode are settled (`set`: as configured); continuous output next.
    fn finish_config(&mut self, set: bool) -> Result<(), MachineError> {
        if !set {
            log!(
                warn,
                "lms: unit / measuring mode not set, using the device's"
            );
            self.counters.config_refused = self.counters.config_refused.saturating_add(1);
        }
        self.scan.variant = self.device.variant;
        self.begin(&Command::Continuous, Check::Mode)?;
        self.init = InitStep::ContinuousTxn;
        Ok(())
    }

    fn apply_block(&mut self, b: &crate::codec::reply::ConfigBlock) {
        self.device.unit = b.unit();
        self.device.measuring_mode = b.measuring_mode();
        self.device.realtime_index = b.realtime_index();
    }
}

/// A command the device may not implement: `Ok(false)` when it was refused (92 or another
/// refusal), NAKed or not answered.
fn optional(r: Result<(), MachineError>) -> Result<bool, MachineError> {
    match r {
        Ok(()) => Ok(true),
        Err(Error::Rejected { .. } | Error::Nak { .. } | Error::Timeout { .. }) => Ok(false),
        Err(e) => Err(e),
    }
}
