//! Bytes in and out: the receive pump (UART → telegram decoder → reply) and command
//! transactions (send, wait for the reply with a timeout, retry).

use embedded_hal::delay::DelayNs;
use embedded_io::{Read, ReadReady, Write};

use super::{Clock, Driver, SetBaud};
use crate::codec::command::Command;
use crate::codec::frame::Event;
use crate::codec::reply::{code as rcode, parse_reply, ParsedReply, Reply, ReplyOptions};
use crate::driver::Error;

/// What a pumped telegram was, copied out of the decoder.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Rx {
    Ack,
    Nak,
    Scan,
    Reply(u8),
}

pub(super) const REPLY_CAP: usize = 192;
pub(super) const RX_CHUNK: usize = 64;

impl<U, D, C> Driver<U, D, C>
where
    U: Read + Write + ReadReady + SetBaud,
    D: DelayNs,
    C: Clock,
{
    pub(super) fn elapsed_since(&mut self, t0: u32) -> u32 {
        self.clock.now_ms().wrapping_sub(t0)
    }

    pub(super) fn write_all(&mut self, mut buf: &[u8]) -> Result<(), Error<U::Error>> {
        while !buf.is_empty() {
            match self.uart.write(buf) {
                Ok(0) => return Err(Error::WriteZero),
                Ok(n) => buf = buf.get(n..).unwrap_or(&[]),
                Err(e) => return Err(Error::Io(e)),
            }
        }
        self.uart.flush().map_err(Error::Io)
    }

    pub(super) fn send(&mut self, cmd: &Command<'_>) -> Result<(), Error<U::Error>> {
        let mut buf = [0u8; 48];
        let n = cmd.encode(&mut buf)?;
        self.last_cmd_ms = self.clock.now_ms();
        self.write_all(buf.get(..n).unwrap_or(&[]))
    }

    /// Reads available bytes (never blocks) and decodes at most one event.
    pub(super) fn pump(&mut self) -> Result<Option<Rx>, Error<U::Error>> {
        loop {
            if self.rx_pos >= self.rx_len {
                self.rx_pos = 0;
                self.rx_len = 0;
                if !self.uart.read_ready().map_err(Error::Io)? {
                    return Ok(None);
                }
                let n = self.uart.read(&mut self.rx).map_err(Error::Io)?;
                if n == 0 {
                    // Spurious Ok(0) (some HALs, or EOF on a host port): nothing now.
                    return Ok(None);
                }
                self.rx_len = n.min(RX_CHUNK);
            }
            let input = self.rx.get(self.rx_pos..self.rx_len).unwrap_or(&[]);
            let (used, ev) = self.decoder.feed(input);
            self.rx_pos += used;
            let rx = match ev {
                None => continue,
                Some(Event::Ack) => Rx::Ack,
                Some(Event::Nak) => Rx::Nak,
                Some(Event::Telegram(t)) => {
                    let payload = t.payload();
                    let opts = ReplyOptions {
                        realtime_index: self.device.realtime_index,
                    };
                    match parse_reply(payload, opts) {
                        Ok(ParsedReply {
                            reply: Reply::Values(v),
                            status,
                        }) => {
                            self.scan.fill(&v, status, self.device.measuring_mode);
                            Rx::Scan
                        }
                        Ok(_) => {
                            let n = payload.len().min(REPLY_CAP);
                            if let (Some(dst), Some(src)) =
                                (self.reply.get_mut(..n), payload.get(..n))
                            {
                                dst.copy_from_slice(src);
                            }
                            self.reply_len = n;
                            Rx::Reply(t.command())
                        }
                        Err(_) => {
                            self.counters.bad_replies = self.counters.bad_replies.saturating_add(1);
                            continue;
                        }
                    }
                }
            };
            return Ok(Some(rx));
        }
    }

    pub(super) fn idle(&mut self) {
        self.delay.delay_us(self.idle_us);
    }

    pub(super) fn reply_payload(&self) -> &[u8] {
        self.reply.get(..self.reply_len).unwrap_or(&[])
    }

    pub(super) fn note_reset(&mut self, _why: &'static str) {
        log!(warn, "lms: device reset seen: {=str}", _why);
        self.reset_seen = true;
        self.counters.device_resets = self.counters.device_resets.saturating_add(1);
    }

    /// Waits for reply `code` (or NAK / reset) for at most `timeout_ms`.
    pub(super) fn wait_reply(
        &mut self,
        command: u8,
        code: u8,
        timeout_ms: u32,
    ) -> Result<(), Error<U::Error>> {
        let t0 = self.clock.now_ms();
        loop {
            match self.pump()? {
                Some(Rx::Reply(c)) if c == code => return Ok(()),
                Some(Rx::Nak) => return Err(Error::Nak { command }),
                Some(Rx::Reply(rcode::POWER_ON | rcode::RESET_ACK)) if code != rcode::RESET_ACK => {
                    self.note_reset("power-on or reset reply while waiting");
                    return Err(Error::DeviceReset);
                }
                Some(Rx::Reply(rcode::INCORRECT)) => {
                    return Err(Error::Rejected {
                        command,
                        code: rcode::INCORRECT,
                    })
                }
                // Anything else (a scan, another reply) does not answer: the wait still ends at
                // its timeout, even on a line that never falls quiet.
                event => {
                    if self.elapsed_since(t0) >= timeout_ms {
                        self.counters.timeouts = self.counters.timeouts.saturating_add(1);
                        return Err(Error::Timeout { command });
                    }
                    if event.is_none() {
                        self.idle();
                    }
                }
            }
        }
    }

    /// Sends `cmd` and waits for its reply, `tries` times; leaves the reply in `self.reply`.
    pub(super) fn transact_n(
        &mut self,
        cmd: &Command<'_>,
        timeout_ms: u32,
        tries: u8,
    ) -> Result<(), Error<U::Error>> {
        let mut last = Error::Timeout {
            command: cmd.code(),
        };
        for i in 0..tries.max(1) {
            if i > 0 {
                self.counters.retries = self.counters.retries.saturating_add(1);
            }
            self.send(cmd)?;
            match self.wait_reply(cmd.code(), cmd.reply_code(), timeout_ms) {
                Ok(()) => return Ok(()),
                Err(e @ (Error::Timeout { .. } | Error::Nak { .. })) => last = e,
                Err(e) => return Err(e),
            }
        }
        Err(last)
    }

    pub(super) fn transact(&mut self, cmd: &Command<'_>) -> Result<(), Error<U::Error>> {
        self.transact_n(cmd, self.config.reply_timeout_ms, self.config.tries)
    }

    /// [`Self::transact`] for a command the device may not implement: `Ok(false)` when it was
    /// refused (92 or another refusal), NAKed or not answered.
    pub(super) fn optional(&mut self, cmd: &Command<'_>) -> Result<bool, Error<U::Error>> {
        match self.transact(cmd) {
            Ok(()) => Ok(true),
            Err(Error::Rejected { .. } | Error::Nak { .. } | Error::Timeout { .. }) => Ok(false),
            Err(e) => Err(e),
        }
    }

    pub(super) fn parsed(&self) -> Option<ParsedReply<'_>> {
        parse_reply(self.reply_payload(), ReplyOptions::default()).ok()
    }

    /// A `20 xx` command that must be answered `A0 00`.
    pub(super) fn mode(&mut self, cmd: &Command<'_>) -> Result<(), Error<U::Error>> {
        self.transact(cmd)?;
        match self.parsed().map(|p| p.reply) {
            Some(Reply::Mode(0)) => Ok(()),
            Some(Reply::Mode(code)) => Err(Error::Rejected {
                command: cmd.code(),
                code,
            }),
            _ => Err(Error::BadReply {
                command: cmd.code(),
            }),
        }
    }
}
