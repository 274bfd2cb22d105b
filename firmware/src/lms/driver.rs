//! LMS200 driver over `embedded-io` UART halves, a delay and a millisecond clock.
//!
//! Initialises like the reference clients (sicktoolbox order): probe the baud rate with `20 25`,
//! switch baud (`20 4x`, the reply comes at the old rate, then wait ≥ 250 ms; a refused rate
//! keeps the one found), type `3A`, status `31`, configuration `74`, variant `3B` when it
//! differs (a refusal keeps the device's, known from the status or the scans' value count),
//! unit / measuring mode through installation mode + `77` when they differ (a refusal
//! keeps the device's: scans carry their unit), then continuous output `20 24`. Every wait has
//! a timeout; commands are tried [`Config::tries`] times; silence or a device reset triggers a
//! re-initialisation. No allocation, no panic.

use embedded_hal::delay::DelayNs;
use embedded_io::{ErrorType, Read, ReadReady, Write};

use crate::lms::command::{Command, PASSWORD};
use crate::lms::error::Error;
use crate::lms::frame::{Decoder, Event, MAX_TELEGRAM};
use crate::lms::reply::{
    self, code as rcode, parse_reply, ConfigBlock, Measurement, ParsedReply, Reply, ReplyOptions,
    Status, StatusInfo,
};
use crate::lms::types::{Baud, MeasuringMode, Unit, Variant};

/// Most values in one B0 telegram (100° at 0.25°).
pub const MAX_VALUES: usize = 401;

/// A millisecond time source (wrapping `u32`).
pub trait Clock {
    /// Milliseconds since an arbitrary origin; may wrap.
    fn now_ms(&mut self) -> u32;
}

/// Changing the UART's baud rate (embedded-io has no notion of it).
pub trait SetBaud: ErrorType {
    /// Switches the local UART to `baud` bits per second.
    fn set_baud(&mut self, baud: u32) -> Result<(), Self::Error>;
}

/// Driver settings. `#[non_exhaustive]`: start from [`Config::default`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub struct Config {
    /// Baud rate to run at.
    pub baud: Baud,
    /// Scan variant to set (default 180° at 0.5°).
    pub variant: Variant,
    /// Range unit to set (default mm).
    pub unit: Unit,
    /// Measuring mode to set; `None` keeps the device's.
    pub measuring_mode: Option<MeasuringMode>,
    /// Reply timeout for ordinary commands, ms.
    pub reply_timeout_ms: u32,
    /// Reply timeout for the configuration write `77`, ms.
    pub config_timeout_ms: u32,
    /// Tries per command.
    pub tries: u8,
    /// Wait after a baud change, ms (sicktoolbox 250, MRPT 500).
    pub baud_switch_wait_ms: u32,
    /// Re-initialise when no scan arrived for this long, ms (at least two telegrams' time at
    /// the current baud rate).
    pub silence_timeout_ms: u32,
    /// Re-initialisations [`Driver::next_scan`] attempts before returning [`Error::Silence`].
    pub max_reinits_per_call: u8,
    /// Longest poll interval while waiting for bytes, µs; the driver never waits longer
    /// than half a character time at the current baud (a 1-byte receive register cannot
    /// overrun while the driver waits).
    pub poll_interval_us: u32,
}

/// The poll interval at `baud`: `max_us`, but at most half a 10-bit character time, ≥ 1 µs.
fn poll_interval(max_us: u32, baud: Baud) -> u32 {
    max_us.min(5_000_000 / baud.bps()).max(1)
}

impl Default for Config {
    fn default() -> Self {
        Self {
            baud: Baud::B38400,
            variant: Variant::A180_R050,
            unit: Unit::Mm,
            measuring_mode: None,
            reply_timeout_ms: 1000,
            config_timeout_ms: 15_000,
            tries: 3,
            baud_switch_wait_ms: 250,
            silence_timeout_ms: 1000,
            max_reinits_per_call: 2,
            poll_interval_us: 500,
        }
    }
}

impl Config {
    /// Default settings with another baud rate.
    pub fn with_baud(mut self, baud: Baud) -> Self {
        self.baud = baud;
        self
    }
    /// Default settings with another variant.
    pub fn with_variant(mut self, variant: Variant) -> Self {
        self.variant = variant;
        self
    }
    /// Default settings with another unit.
    pub fn with_unit(mut self, unit: Unit) -> Self {
        self.unit = unit;
        self
    }
    /// Sets the measuring mode to select.
    pub fn with_measuring_mode(mut self, mode: MeasuringMode) -> Self {
        self.measuring_mode = Some(mode);
        self
    }
    /// Sets the silence timeout.
    pub fn with_silence_timeout_ms(mut self, ms: u32) -> Self {
        self.silence_timeout_ms = ms;
        self
    }
}

/// What the driver knows about the device after initialisation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DeviceState {
    /// Baud rate the device runs at (None before the probe).
    pub baud: Option<Baud>,
    /// Current variant.
    pub variant: Variant,
    /// Current unit.
    pub unit: Option<Unit>,
    /// Current measuring mode.
    pub measuring_mode: MeasuringMode,
    /// B0 telegrams carry a real-time scan index.
    pub realtime_index: bool,
    /// Type string (`LMS200;30106`), ASCII, zero padded.
    pub type_string: [u8; 20],
}

/// Driver counters. All saturate.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Counters {
    /// Telegrams with a good CRC.
    pub telegrams_ok: u32,
    /// Candidate telegrams dropped for a bad CRC.
    pub crc_errors: u32,
    /// Candidates dropped for a bad length or buffer overflow.
    pub bad_length: u32,
    /// Bytes skipped while resynchronising.
    pub bytes_skipped: u32,
    /// NAK bytes received.
    pub naks: u32,
    /// Command tries that timed out.
    pub timeouts: u32,
    /// Command retries (second and later tries).
    pub retries: u32,
    /// Re-initialisations (after the first initialisation).
    pub reinits: u32,
    /// Scans delivered.
    pub scans: u32,
    /// Telegrams with a good CRC but an unusable layout (e.g. B0 length ≠ count).
    pub bad_replies: u32,
    /// Device resets seen (0x90 / 0x91, unexpected A0, restart status).
    pub device_resets: u32,
    /// Initialisations that kept the device's baud rate because it refused [`Config::baud`].
    pub baud_refused: u32,
    /// Initialisations that kept the device's variant because it refused [`Config::variant`].
    pub variant_refused: u32,
    /// Initialisations that kept the device's unit and measuring mode because it refused
    /// [`Config::unit`] / [`Config::measuring_mode`] or did not report its configuration.
    pub config_refused: u32,
}

/// One decoded B0 scan, copied into the driver's fixed buffer.
#[derive(Clone, Debug, PartialEq)]
pub struct ScanData {
    count_word: u16,
    n: usize,
    words: [u16; MAX_VALUES],
    codes: [u16; MAX_VALUES],
    /// Status byte of the telegram.
    pub status: Status,
    /// Real-time scan index, if the device sends it.
    pub scan_index: Option<u8>,
    /// Measuring mode used to split the words.
    pub mode: MeasuringMode,
    /// Variant the driver configured.
    pub variant: Variant,
    /// Sequence number of this scan in the driver (1 = first).
    pub seq: u32,
}

impl Default for ScanData {
    fn default() -> Self {
        Self {
            count_word: 0,
            n: 0,
            words: [0; MAX_VALUES],
            codes: [0; MAX_VALUES],
            status: Status(0),
            scan_index: None,
            mode: MeasuringMode::default(),
            variant: Variant::default(),
            seq: 0,
        }
    }
}

impl ScanData {
    fn fill(&mut self, v: &reply::MeasuredValues<'_>, status: Status, mode: MeasuringMode) {
        self.count_word = v.count_word();
        let mut n = 0;
        for ((w, c), word) in self
            .words
            .iter_mut()
            .zip(self.codes.iter_mut())
            .zip(v.words())
        {
            *w = word;
            *c = word & mode.range_mask();
            n += 1;
        }
        self.n = n;
        self.status = status;
        self.scan_index = v.scan_index();
        self.mode = mode;
    }

    /// Number of values.
    pub fn len(&self) -> usize {
        self.n
    }
    /// True when empty.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }
    /// The raw value words (range and flag bits).
    pub fn words(&self) -> &[u16] {
        self.words.get(..self.n).unwrap_or(&[])
    }
    /// The range codes (range bits only, per measuring mode).
    pub fn codes(&self) -> &[u16] {
        self.codes.get(..self.n).unwrap_or(&[])
    }
    /// The B0 count word.
    pub fn count_word(&self) -> u16 {
        self.count_word
    }
    /// Unit from the count word (falls back to cm for the undefined code).
    pub fn unit(&self) -> Unit {
        Unit::from_count_bits(self.count_word >> reply::count::UNIT_SHIFT).unwrap_or(Unit::Cm)
    }
    /// mm per range unit.
    pub fn mm_per_unit(&self) -> f32 {
        self.unit().mm_per_unit()
    }
    /// Largest valid range code for the measuring mode.
    pub fn max_valid(&self) -> u16 {
        self.mode.max_valid()
    }
    /// Value `i` split into code, flags and meaning.
    pub fn measurement(&self, i: usize) -> Option<Measurement> {
        self.words()
            .get(i)
            .map(|&w| Measurement::decode(w, self.mode))
    }
    /// Range of value `i` in mm, `None` for a reserved code, 0 or out of range.
    pub fn range_mm(&self, i: usize) -> Option<f32> {
        let c = *self.codes().get(i)?;
        (c != 0 && c <= self.max_valid()).then(|| f32::from(c) * self.mm_per_unit())
    }
    /// Beam geometry (centred field, value 0 on the right, counter-clockwise).
    pub fn geometry(&self) -> pfe_core::ScanGeometry {
        let mut g = pfe_core::ScanGeometry::lms200(
            f32::from(self.variant.angle_deg),
            self.variant.resolution_deg(),
        );
        g.r_max = f32::from(self.max_valid()) * self.mm_per_unit();
        g
    }
    /// The scan as pfe-core input (raw codes, no copy).
    pub fn as_pfe_scan(&self) -> pfe_core::Scan<'_> {
        pfe_core::Scan {
            geometry: self.geometry(),
            ranges: pfe_core::scan::Ranges::Raw {
                values: self.codes(),
                mm_per_unit: self.mm_per_unit(),
                max_valid: self.max_valid(),
            },
            motion: None,
        }
    }
}

/// What a pumped telegram was, copied out of the decoder.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Rx {
    Ack,
    Nak,
    Scan,
    Reply(u8),
}

const REPLY_CAP: usize = 192;
const RX_CHUNK: usize = 64;

/// The LMS200 driver. See the module docs for the sequence.
///
/// ```no_run
/// # fn demo<U, D, C>(uart: U, delay: D, clock: C) -> Result<(), firmware::lms::error::Error<U::Error>>
/// # where U: embedded_io::Read + embedded_io::Write + embedded_io::ReadReady + firmware::lms::driver::SetBaud,
/// #       D: embedded_hal::delay::DelayNs, C: firmware::lms::driver::Clock {
/// use firmware::lms::driver::{Config, Driver};
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
    config: Config,
    decoder: Decoder<MAX_TELEGRAM>,
    rx: [u8; RX_CHUNK],
    rx_pos: usize,
    rx_len: usize,
    /// Current poll interval, µs (see [`Config::poll_interval_us`]).
    idle_us: u32,
    reply: [u8; REPLY_CAP],
    reply_len: usize,
    scan: ScanData,
    scan_ok: bool,
    device: DeviceState,
    streaming: bool,
    initialised_once: bool,
    reset_seen: bool,
    /// A scan that looks like a device reset re-initialises only while this is set; cleared
    /// by that re-initialisation, set again by a scan that looks normal.
    reset_check_armed: bool,
    last_scan_ms: u32,
    last_cmd_ms: u32,
    counters: Counters,
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
            config,
            decoder: Decoder::new(),
            rx: [0; RX_CHUNK],
            rx_pos: 0,
            rx_len: 0,
            idle_us: poll_interval(config.poll_interval_us, Baud::B9600),
            reply: [0; REPLY_CAP],
            reply_len: 0,
            scan: ScanData::default(),
            scan_ok: false,
            device: DeviceState::default(),
            streaming: false,
            initialised_once: false,
            reset_seen: false,
            reset_check_armed: true,
            last_scan_ms: 0,
            last_cmd_ms: 0,
            counters: Counters::default(),
        }
    }

    /// Gives back the UART, delay and clock.
    pub fn release(self) -> (U, D, C) {
        (self.uart, self.delay, self.clock)
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

    /// What the driver knows about the device.
    pub fn device(&self) -> &DeviceState {
        &self.device
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// The last scan delivered (empty before the first).
    pub fn last_scan(&self) -> &ScanData {
        &self.scan
    }

    /// True while the device is in continuous output.
    pub fn is_streaming(&self) -> bool {
        self.streaming
    }

    // ------------------------------------------------------------------ bytes

    fn elapsed_since(&mut self, t0: u32) -> u32 {
        self.clock.now_ms().wrapping_sub(t0)
    }

    fn write_all(&mut self, mut buf: &[u8]) -> Result<(), Error<U::Error>> {
        while !buf.is_empty() {
            match self.uart.write(buf) {
                Ok(0) => return Err(Error::WriteZero),
                Ok(n) => buf = buf.get(n..).unwrap_or(&[]),
                Err(e) => return Err(Error::Io(e)),
            }
        }
        self.uart.flush().map_err(Error::Io)
    }

    fn send(&mut self, cmd: &Command<'_>) -> Result<(), Error<U::Error>> {
        let mut buf = [0u8; 48];
        let n = cmd.encode(&mut buf)?;
        self.last_cmd_ms = self.clock.now_ms();
        self.write_all(buf.get(..n).unwrap_or(&[]))
    }

    /// Reads available bytes (never blocks) and decodes at most one event.
    fn pump(&mut self) -> Result<Option<Rx>, Error<U::Error>> {
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

    fn idle(&mut self) {
        self.delay.delay_us(self.idle_us);
    }

    fn reply_payload(&self) -> &[u8] {
        self.reply.get(..self.reply_len).unwrap_or(&[])
    }

    fn note_reset(&mut self, _why: &'static str) {
        log!(warn, "lms: device reset seen: {=str}", _why);
        self.reset_seen = true;
        self.counters.device_resets = self.counters.device_resets.saturating_add(1);
    }

    /// Waits for reply `code` (or NAK / reset) for at most `timeout_ms`.
    fn wait_reply(
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
                Some(_) => {}
                None => {
                    if self.elapsed_since(t0) >= timeout_ms {
                        self.counters.timeouts = self.counters.timeouts.saturating_add(1);
                        return Err(Error::Timeout { command });
                    }
                    self.idle();
                }
            }
        }
    }

    /// Sends `cmd` and waits for its reply, `tries` times; leaves the reply in `self.reply`.
    fn transact_n(
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

    fn transact(&mut self, cmd: &Command<'_>) -> Result<(), Error<U::Error>> {
        self.transact_n(cmd, self.config.reply_timeout_ms, self.config.tries)
    }

    /// [`Self::transact`] for a command the device may not implement: `Ok(false)` when it was
    /// refused (92 or another refusal), NAKed or not answered.
    fn optional(&mut self, cmd: &Command<'_>) -> Result<bool, Error<U::Error>> {
        match self.transact(cmd) {
            Ok(()) => Ok(true),
            Err(Error::Rejected { .. } | Error::Nak { .. } | Error::Timeout { .. }) => Ok(false),
            Err(e) => Err(e),
        }
    }

    fn parsed(&self) -> Option<ParsedReply<'_>> {
        parse_reply(self.reply_payload(), ReplyOptions::default()).ok()
    }

    /// A `20 xx` command that must be answered `A0 00`.
    fn mode(&mut self, cmd: &Command<'_>) -> Result<(), Error<U::Error>> {
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

    fn set_local_baud(&mut self, baud: Baud) -> Result<(), Error<U::Error>> {
        self.uart.set_baud(baud.bps()).map_err(Error::Io)?;
        self.idle_us = poll_interval(self.config.poll_interval_us, baud);
        self.decoder.clear();
        self.rx_pos = 0;
        self.rx_len = 0;
        Ok(())
    }

    /// Finds the device's baud rate with `20 25` (which also stops continuous output).
    fn probe(&mut self) -> Result<Baud, Error<U::Error>> {
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
                _ => return Err(Error::BadReply { command: 0x74 }),
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
                    _ => return Err(Error::BadReply { command: 0x3B }),
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
    fn variant_refused(&mut self) {
        log!(warn, "lms: variant refused, using the device's");
        self.counters.variant_refused = self.counters.variant_refused.saturating_add(1);
    }

    /// Sets [`Config::unit`] and the measuring mode where `block` (the device's configuration)
    /// differs; `Ok(false)` when the device refused or did not report its configuration.
    fn set_unit_and_mode(&mut self, block: Option<ConfigBlock>) -> Result<bool, Error<U::Error>> {
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
    fn write_config(&mut self, block: &ConfigBlock) -> Result<(), Error<U::Error>> {
        self.mode(&Command::Install(&PASSWORD))?;
        let cmd = Command::SetConfig(block);
        self.transact_n(&cmd, self.config.config_timeout_ms, self.config.tries)?;
        match self.parsed().map(|p| p.reply) {
            Some(Reply::ConfigSet { ok: true, config }) => self.apply_block(&config),
            Some(Reply::ConfigSet { ok: false, .. }) => {
                return Err(Error::Rejected {
                    command: 0x77,
                    code: 0,
                })
            }
            _ => return Err(Error::BadReply { command: 0x77 }),
        }
        self.mode(&Command::OnRequest)
    }

    fn apply_block(&mut self, b: &ConfigBlock) {
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

    /// [`Config::silence_timeout_ms`], but at least two scan telegrams' time at the current
    /// baud rate (at 9600 Bd one 361-value telegram takes 760 ms, a 401-value one 845 ms).
    fn silence_limit_ms(&self) -> u32 {
        let bps = self.device.baud.unwrap_or(self.config.baud).bps().max(1);
        let bytes = (self.device.variant.values() as u32).saturating_mul(2) + 10;
        let two_telegrams = bytes.saturating_mul(2 * 10 * 1000) / bps;
        self.config.silence_timeout_ms.max(two_telegrams)
    }

    fn accept_scan(&mut self) -> bool {
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
        true
    }

    fn unexpected_reply(&mut self, c: u8) {
        // A late A0 answering a retried command is not a reset.
        let late_answer = c == rcode::MODE
            && self.elapsed_since(self.last_cmd_ms)
                < self.config.reply_timeout_ms.saturating_mul(2);
        if matches!(c, rcode::POWER_ON | rcode::RESET_ACK | rcode::MODE) && !late_answer {
            self.note_reset("unrequested reply");
        }
    }

    /// Waits for the next scan, initialising first if needed and re-initialising after
    /// [`Config::silence_timeout_ms`] (at least two telegrams' time) without a scan or after a
    /// device reset.
    pub fn next_scan(&mut self) -> Result<&ScanData, Error<U::Error>> {
        let mut reinits = 0u8;
        if !self.streaming {
            self.init()?;
        }
        loop {
            // The limit is at least the configured timeout: compare with that first (this
            // runs at every poll).
            let silent = self.elapsed_since(self.last_scan_ms);
            if self.reset_seen
                || (silent >= self.config.silence_timeout_ms && silent >= self.silence_limit_ms())
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
            match self.pump()? {
                Some(Rx::Scan) => {
                    if self.accept_scan() {
                        return Ok(&self.scan);
                    }
                }
                Some(Rx::Reply(c)) => self.unexpected_reply(c),
                Some(_) => {}
                None => self.idle(),
            }
        }
    }
}
