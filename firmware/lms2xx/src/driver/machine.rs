//! The protocol as a sans-IO state machine: every decision of the driver (initialisation, baud
//! change, retries, re-initialisation, streaming, timeouts, counters) is made here, and the
//! I/O is left to a thin loop around it — the blocking [`Driver`](super::Driver) or the
//! `AsyncDriver` (feature `async`).
//!
//! The loop starts an operation ([`Machine::start`]), then calls [`Machine::step`] with the
//! current time until it returns a result ([`Action::Scan`], [`Action::Done`],
//! [`Action::Failed`]), carrying out each other [`Action`] in between: write bytes, set the
//! local baud rate, read into [`Machine::rx_buffer`] and report the count with
//! [`Machine::received`] (0 when nothing is available), wait. When the I/O fails, the loop calls
//! [`Machine::abort`] and reports its own error.
//!
//! ```
//! use lms2xx::driver::machine::{Action, Machine, Request};
//! use lms2xx::driver::Config;
//!
//! // Initialisation begins with the baud probe: the configured rate (38 400 Bd), then `20 25`.
//! let mut m = Machine::new(Config::default());
//! m.start(Request::Init);
//! assert_eq!(m.step(0), Action::SetBaud(38_400));
//! assert_eq!(m.step(0), Action::Write(&[0x02, 0x00, 0x02, 0x00, 0x20, 0x25, 0x35, 0x08]));
//! // The device does not answer: the machine asks for bytes, then waits half a character.
//! assert_eq!(m.step(0), Action::Read);
//! m.received(0);
//! assert_eq!(m.step(0), Action::Idle(130));
//! ```

use core::convert::Infallible;

use super::config::poll_interval;
use super::{Config, Counters, DeviceState, Error, ScanData};
use crate::codec::command::Command;
use crate::codec::frame::{Decoder, Event, MAX_TELEGRAM};
use crate::codec::reply::{
    code as rcode, parse_reply, ConfigBlock, ParsedReply, Reply, ReplyOptions,
};
use crate::codec::types::Baud;

/// The machine's errors: the driver's [`Error`] without a bus error (the loop owns the bus).
pub type MachineError = Error<Infallible>;

impl Error<Infallible> {
    /// The same error for a driver whose bus error is `E`.
    pub fn widen<E>(self) -> Error<E> {
        match self {
            Error::Io(never) => match never {},
            Error::WriteZero => Error::WriteZero,
            Error::Timeout { command } => Error::Timeout { command },
            Error::Nak { command } => Error::Nak { command },
            Error::NoDevice => Error::NoDevice,
            Error::Rejected { command, code } => Error::Rejected { command, code },
            Error::BadReply { command } => Error::BadReply { command },
            Error::DeviceReset => Error::DeviceReset,
            Error::Silence => Error::Silence,
            Error::Encode(e) => Error::Encode(e),
            Error::InvalidConfig => Error::InvalidConfig,
        }
    }
}

/// What the I/O loop must do next.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action<'a> {
    /// Write all these bytes and flush (`write` returning 0 is [`Error::WriteZero`]).
    Write(&'a [u8]),
    /// Switch the local UART to this many bits per second.
    SetBaud(u32),
    /// Read the bytes available into [`Machine::rx_buffer`] and report them with
    /// [`Machine::received`] (0 when none are available now).
    Read,
    /// Nothing was available: wait this many µs (at most half a character time at the current
    /// rate) before the next step.
    Idle(u32),
    /// Wait this many ms without reading (after a baud change).
    Wait(u32),
    /// The operation ended with a scan: [`Machine::scan`].
    Scan,
    /// The operation ended without a scan (also: no operation is running).
    Done,
    /// The operation failed.
    Failed(MachineError),
}

/// An operation of the driver.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Request {
    /// Initialise (see the [driver](super) docs) and start continuous output.
    Init,
    /// The next scan: initialise first if not streaming, re-initialise after silence or a
    /// device reset.
    NextScan,
    /// Decode what is available; a scan if one completed, else [`Action::Done`].
    Poll,
    /// Stop continuous output (`20 25`).
    Stop,
    /// Send the reset command `10` and wait for `91`.
    ResetDevice,
}

/// What a pumped telegram was, copied out of the decoder.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Rx {
    Ack,
    Nak,
    Scan,
    Reply(u8),
}

/// The receive pump's answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Pump {
    Event(Rx),
    /// The receive buffer is used up: ask the loop for bytes.
    NeedRead,
    /// The last read gave nothing.
    Empty,
}

/// An internal step result: an action without its borrow.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Out {
    Write,
    SetBaud(u32),
    Read,
    Idle(u32),
    Wait(u32),
    Scan,
    Done,
    Failed(MachineError),
}

/// A sub-machine's step: an action to hand out, or its end.
pub(super) enum Sub<T> {
    Out(Out),
    Finished(Result<T, MachineError>),
}

/// How a transaction's reply is checked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Check {
    /// Any reply with the expected code.
    Plain,
    /// A `20 xx` command: the reply must be `A0 00`.
    Mode,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Txn {
    Send { i: u8 },
    Wait { i: u8, t0: Option<u32> },
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Op {
    Idle,
    Failed(MachineError),
    Init,
    NextScan { reinits: u8, initing: bool },
    Poll,
    Stop,
    ResetDevice,
}

pub(super) const REPLY_CAP: usize = 192;
pub(super) const RX_CHUNK: usize = 64;
const TX_CAP: usize = 48;

/// The LMS2xx protocol state machine. See the module docs.
pub struct Machine {
    pub(super) config: Config,
    pub(super) decoder: Decoder<MAX_TELEGRAM>,
    pub(super) rx: [u8; RX_CHUNK],
    pub(super) rx_pos: usize,
    pub(super) rx_len: usize,
    /// The last read gave nothing (not yet reported by the pump).
    pub(super) rx_empty: bool,
    /// Current poll interval, µs (see [`Config::poll_interval_us`]).
    pub(super) idle_us: u32,
    pub(super) reply: [u8; REPLY_CAP],
    pub(super) reply_len: usize,
    pub(super) scan: ScanData,
    pub(super) device: DeviceState,
    pub(super) streaming: bool,
    pub(super) initialised_once: bool,
    pub(super) reset_seen: bool,
    /// A scan that looks like a device reset re-initialises only while this is set; cleared
    /// by that re-initialisation, set again by a scan that looks normal.
    pub(super) reset_check_armed: bool,
    pub(super) last_scan_ms: u32,
    pub(super) last_cmd_ms: u32,
    pub(super) counters: Counters,
    pub(super) op: Op,
    // The transaction in flight.
    pub(super) tx: [u8; TX_CAP],
    pub(super) tx_len: usize,
    pub(super) txn: Txn,
    pub(super) txn_command: u8,
    pub(super) txn_reply: u8,
    pub(super) txn_timeout_ms: u32,
    pub(super) txn_tries: u8,
    pub(super) txn_check: Check,
    // Initialisation.
    pub(super) init: super::init::InitStep,
    pub(super) probe_order: [Baud; 6],
    pub(super) probe_len: usize,
    pub(super) found: Baud,
    pub(super) variant_known: bool,
    pub(super) block: Option<ConfigBlock>,
}

impl Machine {
    /// A machine in its power-on state: nothing known about the device, no operation.
    pub fn new(config: Config) -> Self {
        Self {
            config,
            decoder: Decoder::new(),
            rx: [0; RX_CHUNK],
            rx_pos: 0,
            rx_len: 0,
            rx_empty: false,
            idle_us: poll_interval(config.poll_interval_us, Baud::B9600),
            reply: [0; REPLY_CAP],
            reply_len: 0,
            scan: ScanData::default(),
            device: DeviceState::default(),
            streaming: false,
            initialised_once: false,
            reset_seen: false,
            reset_check_armed: true,
            last_scan_ms: 0,
            last_cmd_ms: 0,
            counters: Counters::default(),
            op: Op::Idle,
            tx: [0; TX_CAP],
            tx_len: 0,
            txn: Txn::Send { i: 0 },
            txn_command: 0,
            txn_reply: 0,
            txn_timeout_ms: 0,
            txn_tries: 1,
            txn_check: Check::Plain,
            init: super::init::InitStep::Start,
            probe_order: [Baud::B9600; 6],
            probe_len: 0,
            found: Baud::B9600,
            variant_known: false,
            block: None,
        }
    }

    /// Starts `request`, replacing any operation still running.
    pub fn start(&mut self, request: Request) {
        self.rx_empty = false;
        self.op = match request {
            Request::Init => {
                self.init = super::init::InitStep::Start;
                Op::Init
            }
            Request::NextScan => {
                let initing = !self.streaming;
                if initing {
                    self.init = super::init::InitStep::Start;
                }
                Op::NextScan {
                    reinits: 0,
                    initing,
                }
            }
            Request::Poll => Op::Poll,
            Request::Stop => {
                self.streaming = false;
                match self.begin(&Command::OnRequest, Check::Mode) {
                    Ok(()) => Op::Stop,
                    Err(e) => Op::Failed(e),
                }
            }
            Request::ResetDevice => {
                self.streaming = false;
                match self.begin(&Command::Reset, Check::Plain) {
                    Ok(()) => Op::ResetDevice,
                    Err(e) => Op::Failed(e),
                }
            }
        };
    }

    /// Ends the running operation (the loop's I/O failed). The device state stays as it was.
    pub fn abort(&mut self) {
        self.op = Op::Idle;
    }

    /// The next thing to do, at time `now_ms` (a wrapping millisecond clock, read just before
    /// this call).
    pub fn step(&mut self, now_ms: u32) -> Action<'_> {
        let out = self.step_op(now_ms);
        if matches!(out, Out::Scan | Out::Done | Out::Failed(_)) {
            self.op = Op::Idle;
        }
        match out {
            Out::Write => Action::Write(self.tx.get(..self.tx_len).unwrap_or(&[])),
            Out::SetBaud(b) => Action::SetBaud(b),
            Out::Read => Action::Read,
            Out::Idle(us) => Action::Idle(us),
            Out::Wait(ms) => Action::Wait(ms),
            Out::Scan => Action::Scan,
            Out::Done => Action::Done,
            Out::Failed(e) => Action::Failed(e),
        }
    }

    fn step_op(&mut self, now: u32) -> Out {
        match self.op {
            Op::Idle => Out::Done,
            Op::Failed(e) => Out::Failed(e),
            Op::Init => match self.init_step(now) {
                Sub::Out(o) => o,
                Sub::Finished(Ok(())) => Out::Done,
                Sub::Finished(Err(e)) => Out::Failed(e),
            },
            Op::NextScan { .. } => self.next_scan_step(now),
            Op::Poll => self.poll_step(now),
            Op::Stop => match self.txn_step(now) {
                Sub::Out(o) => o,
                Sub::Finished(Ok(())) => Out::Done,
                Sub::Finished(Err(e)) => Out::Failed(e),
            },
            Op::ResetDevice => match self.txn_step(now) {
                Sub::Out(o) => o,
                Sub::Finished(Ok(())) => {
                    self.device.baud = Some(Baud::B9600);
                    Out::Done
                }
                Sub::Finished(Err(e)) => Out::Failed(e),
            },
        }
    }

    /// Where the loop reads bytes to after [`Action::Read`].
    pub fn rx_buffer(&mut self) -> &mut [u8] {
        &mut self.rx
    }

    /// After [`Action::Read`]: `n` bytes were read into [`Machine::rx_buffer`] (0: none
    /// available).
    pub fn received(&mut self, n: usize) {
        self.rx_pos = 0;
        self.rx_len = n.min(RX_CHUNK);
        self.rx_empty = n == 0;
    }

    /// The poll interval at the current rate, µs: how long an [`Action::Idle`] lasts.
    pub fn poll_interval_us(&self) -> u32 {
        self.idle_us
    }

    /// Counters so far (decoder counters included).
    pub fn counters(&self) -> Counters {
        let s = self.decoder.stats();
        Counters {
            telegrams_ok: s.telegrams,
            crc_errors: s.crc_errors,
            bad_length: s.bad_length.saturating_add(s.overflows),
            bytes_skipped: s.bytes_skipped,
            naks: s.naks,
            ..self.counters
        }
    }

    /// What the machine knows about the device.
    pub fn device(&self) -> &DeviceState {
        &self.device
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// The last scan delivered (empty before the first).
    pub fn scan(&self) -> &ScanData {
        &self.scan
    }

    /// True while the device is in continuous output.
    pub fn is_streaming(&self) -> bool {
        self.streaming
    }

    pub(super) fn set_local_baud(&mut self, baud: Baud) -> Out {
        self.idle_us = poll_interval(self.config.poll_interval_us, baud);
        self.decoder.clear();
        self.rx_pos = 0;
        self.rx_len = 0;
        self.rx_empty = false;
        Out::SetBaud(baud.bps())
    }

    /// Decodes at most one event from the received bytes.
    pub(super) fn pump(&mut self) -> Pump {
        loop {
            if self.rx_pos >= self.rx_len {
                self.rx_pos = 0;
                self.rx_len = 0;
                if core::mem::take(&mut self.rx_empty) {
                    return Pump::Empty;
                }
                return Pump::NeedRead;
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
            return Pump::Event(rx);
        }
    }

    pub(super) fn reply_payload(&self) -> &[u8] {
        self.reply.get(..self.reply_len).unwrap_or(&[])
    }

    pub(super) fn parsed(&self) -> Option<ParsedReply<'_>> {
        parse_reply(self.reply_payload(), ReplyOptions::default()).ok()
    }

    pub(super) fn note_reset(&mut self, _why: &'static str) {
        log!(warn, "lms: device reset seen: {=str}", _why);
        self.reset_seen = true;
        self.counters.device_resets = self.counters.device_resets.saturating_add(1);
    }

    /// Prepares a transaction with the ordinary reply timeout and tries.
    pub(super) fn begin(&mut self, cmd: &Command<'_>, check: Check) -> Result<(), MachineError> {
        self.begin_n(cmd, check, self.config.reply_timeout_ms, self.config.tries)
    }

    /// Prepares a transaction: `cmd` is sent and its reply awaited for `timeout_ms`, `tries`
    /// times; the reply is left in `self.reply`.
    pub(super) fn begin_n(
        &mut self,
        cmd: &Command<'_>,
        check: Check,
        timeout_ms: u32,
        tries: u8,
    ) -> Result<(), MachineError> {
        self.tx_len = cmd.encode(&mut self.tx)?;
        self.txn = Txn::Send { i: 0 };
        self.txn_command = cmd.code();
        self.txn_reply = cmd.reply_code();
        self.txn_timeout_ms = timeout_ms;
        self.txn_tries = tries.max(1);
        self.txn_check = check;
        Ok(())
    }

    /// One step of the transaction in flight.
    pub(super) fn txn_step(&mut self, now: u32) -> Sub<()> {
        let command = self.txn_command;
        let code = self.txn_reply;
        loop {
            let (i, t0) = match self.txn {
                Txn::Send { i } => {
                    if i > 0 {
                        self.counters.retries = self.counters.retries.saturating_add(1);
                    }
                    self.last_cmd_ms = now;
                    self.txn = Txn::Wait { i, t0: None };
                    return Sub::Out(Out::Write);
                }
                Txn::Wait { i, t0: Some(t0) } => (i, t0),
                Txn::Wait { i, t0: None } => {
                    // The wait starts once the command is out.
                    self.txn = Txn::Wait { i, t0: Some(now) };
                    (i, now)
                }
            };
            let result = match self.pump() {
                Pump::NeedRead => return Sub::Out(Out::Read),
                Pump::Event(Rx::Reply(c)) if c == code => Ok(()),
                Pump::Event(Rx::Nak) => Err(Error::Nak { command }),
                Pump::Event(Rx::Reply(rcode::POWER_ON | rcode::RESET_ACK))
                    if code != rcode::RESET_ACK =>
                {
                    self.note_reset("power-on or reset reply while waiting");
                    Err(Error::DeviceReset)
                }
                Pump::Event(Rx::Reply(rcode::INCORRECT)) => Err(Error::Rejected {
                    command,
                    code: rcode::INCORRECT,
                }),
                // Anything else (a scan, another reply) does not answer: the wait still ends at
                // its timeout, even on a line that never falls quiet.
                event => {
                    if now.wrapping_sub(t0) >= self.txn_timeout_ms {
                        self.counters.timeouts = self.counters.timeouts.saturating_add(1);
                        Err(Error::Timeout { command })
                    } else if event == Pump::Empty {
                        return Sub::Out(Out::Idle(self.idle_us));
                    } else {
                        continue;
                    }
                }
            };
            match result {
                Ok(()) => return Sub::Finished(self.check_reply()),
                // The last try's timeout or NAK is the transaction's error.
                Err(e @ (Error::Timeout { .. } | Error::Nak { .. })) => {
                    if i.saturating_add(1) >= self.txn_tries {
                        return Sub::Finished(Err(e));
                    }
                    self.txn = Txn::Send {
                        i: i.saturating_add(1),
                    };
                }
                Err(e) => return Sub::Finished(Err(e)),
            }
        }
    }

    fn check_reply(&self) -> Result<(), MachineError> {
        let command = self.txn_command;
        match self.txn_check {
            Check::Plain => Ok(()),
            Check::Mode => match self.parsed().map(|p| p.reply) {
                Some(Reply::Mode(0)) => Ok(()),
                Some(Reply::Mode(code)) => Err(Error::Rejected { command, code }),
                _ => Err(Error::BadReply { command }),
            },
        }
    }
}
