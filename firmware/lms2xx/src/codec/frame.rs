//! Telegram framing: an incremental, allocation-free, resynchronising decoder (sans-IO).
//!
//! ```text
//! STX(0x02) | ADR | LEN_L LEN_H | CMD | DATA … | [STATUS] | CRC_L CRC_H
//! ```
//! `LEN` counts CMD through the byte before the CRC. The whole telegram is at most
//! [`MAX_TELEGRAM`] bytes. Single ACK (0x06) / NAK (0x15) bytes between telegrams are events.

use super::crc::{crc16, Crc};
pub use super::error::FrameError;

/// Start of a telegram.
pub const STX: u8 = 0x02;
/// Acknowledge byte sent by the device after a telegram with a good CRC.
pub const ACK: u8 = 0x06;
/// Not-acknowledge byte sent by the device after a telegram with a bad CRC.
pub const NAK: u8 = 0x15;
/// Address byte of telegrams sent by the LMS to the host.
pub const DEVICE_ADDRESS: u8 = 0x80;
/// Address byte of telegrams sent by the host to the LMS.
pub const HOST_ADDRESS: u8 = 0x00;
/// Largest telegram, bytes (STX through CRC).
pub const MAX_TELEGRAM: usize = 812;
/// Framing overhead: STX, ADR, LEN (2) and CRC (2).
pub const OVERHEAD: usize = 6;
/// Largest `LEN` field value.
pub const MAX_LEN: usize = MAX_TELEGRAM - OVERHEAD;

/// One complete telegram with a verified CRC, borrowed from the decoder's buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Telegram<'a> {
    raw: &'a [u8],
}

impl<'a> Telegram<'a> {
    /// Checks framing, length and CRC of a complete telegram in `raw` (exact length).
    ///
    /// ```
    /// use lms2xx::codec::frame::Telegram;
    /// let t = Telegram::parse(&[0x02, 0x80, 0x03, 0x00, 0xA0, 0x00, 0x10, 0x16, 0x0A])?;
    /// assert_eq!(t.command(), 0xA0);
    /// assert_eq!(t.payload(), &[0xA0, 0x00, 0x10]);
    /// # Ok::<(), lms2xx::codec::frame::FrameError>(())
    /// ```
    pub fn parse(raw: &'a [u8]) -> Result<Self, FrameError> {
        let (head, _) = raw.split_first_chunk::<4>().ok_or(FrameError::Truncated)?;
        if head[0] != STX {
            return Err(FrameError::NoStx);
        }
        let len = usize::from(u16::from_le_bytes([head[2], head[3]]));
        if len == 0 || len > MAX_LEN {
            return Err(FrameError::BadLength(len));
        }
        if raw.len() < len + OVERHEAD {
            return Err(FrameError::Truncated);
        }
        if raw.len() > len + OVERHEAD {
            return Err(FrameError::TrailingBytes);
        }
        let (body, crc) = raw.split_at(len + 4);
        let got = match crc {
            [lo, hi] => u16::from_le_bytes([*lo, *hi]),
            _ => return Err(FrameError::Truncated),
        };
        let expected = crc16(body);
        if expected != got {
            return Err(FrameError::Crc { expected, got });
        }
        Ok(Self { raw })
    }

    /// All bytes, STX through CRC.
    pub fn raw(&self) -> &'a [u8] {
        self.raw
    }

    /// The address byte (0x80 from the device, 0x00 from the host).
    pub fn address(&self) -> u8 {
        self.raw.get(1).copied().unwrap_or(0)
    }

    /// The `LEN` bytes: CMD, data and (in replies) the status byte.
    pub fn payload(&self) -> &'a [u8] {
        let end = self.raw.len().saturating_sub(2);
        self.raw.get(4..end).unwrap_or(&[])
    }

    /// The command (or reply) code.
    pub fn command(&self) -> u8 {
        self.raw.get(4).copied().unwrap_or(0)
    }
}

/// Writes a telegram `STX | adr | LEN | payload | CRC` into `out`; returns its length.
///
/// ```
/// use lms2xx::codec::frame::{encode_telegram, HOST_ADDRESS};
/// let mut buf = [0u8; 16];
/// let n = encode_telegram(HOST_ADDRESS, &[0x20, 0x24], &mut buf)?;
/// assert_eq!(&buf[..n], &[0x02, 0x00, 0x02, 0x00, 0x20, 0x24, 0x34, 0x08]);
/// # Ok::<(), lms2xx::codec::frame::FrameError>(())
/// ```
pub fn encode_telegram(adr: u8, payload: &[u8], out: &mut [u8]) -> Result<usize, FrameError> {
    encode_parts(adr, &[payload], out)
}

/// Like [`encode_telegram`] with the payload given as consecutive parts (no copy needed).
pub fn encode_parts(adr: u8, parts: &[&[u8]], out: &mut [u8]) -> Result<usize, FrameError> {
    let len: usize = parts.iter().map(|p| p.len()).sum();
    if len == 0 || len > MAX_LEN {
        return Err(FrameError::BadLength(len));
    }
    let total = len + OVERHEAD;
    let out = out.get_mut(..total).ok_or(FrameError::BufferTooSmall)?;
    let len16 = u16::try_from(len).map_err(|_| FrameError::BadLength(len))?;
    let [l0, l1] = len16.to_le_bytes();
    let (head, rest) = out.split_at_mut(4);
    head.copy_from_slice(&[STX, adr, l0, l1]);
    let mut crc = Crc::new();
    crc.update(head);
    let mut pos = 0usize;
    for p in parts {
        let dst = rest
            .get_mut(pos..pos + p.len())
            .ok_or(FrameError::BufferTooSmall)?;
        dst.copy_from_slice(p);
        crc.update(p);
        pos += p.len();
    }
    let dst = rest
        .get_mut(pos..pos + 2)
        .ok_or(FrameError::BufferTooSmall)?;
    dst.copy_from_slice(&crc.value().to_le_bytes());
    Ok(total)
}

/// What the decoder found in the byte stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Event<'a> {
    /// A single ACK byte (0x06) between telegrams.
    Ack,
    /// A single NAK byte (0x15) between telegrams.
    Nak,
    /// A complete telegram with a good CRC.
    Telegram(Telegram<'a>),
}

/// Counters kept by a [`Decoder`]. All saturate instead of wrapping. `#[non_exhaustive]`:
/// more counters may come.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub struct DecoderStats {
    /// Telegrams delivered with a good CRC.
    pub telegrams: u32,
    /// Candidate telegrams rejected for a bad CRC.
    pub crc_errors: u32,
    /// Candidate telegrams rejected for a `LEN` of 0 or above [`MAX_LEN`].
    pub bad_length: u32,
    /// Candidate telegrams rejected because `LEN` fits the protocol but not the buffer.
    pub overflows: u32,
    /// Bytes discarded while hunting for a telegram (including the STX of each rejected one).
    pub bytes_skipped: u32,
    /// ACK bytes seen.
    pub acks: u32,
    /// NAK bytes seen.
    pub naks: u32,
}

impl DecoderStats {
    /// Candidate telegrams dropped for any reason (CRC, length, overflow).
    pub fn dropped(&self) -> u32 {
        self.crc_errors
            .saturating_add(self.bad_length)
            .saturating_add(self.overflows)
    }
}

enum Settle {
    NeedMore,
    Complete(usize),
}

/// Incremental telegram decoder with a `CAP`-byte buffer (use [`MAX_TELEGRAM`] for all
/// telegrams; a smaller `CAP` rejects longer ones and counts them as overflows).
///
/// Feed it any chunk of received bytes; it returns how many it consumed and, at most, one
/// [`Event`]. Call again with the unconsumed rest until it returns `None`. It never allocates,
/// never panics, rejects a `LEN` above [`MAX_LEN`] before buffering, never accepts a bad CRC, and
/// on any rejection drops only the STX and rescans the buffered bytes, so a good telegram that
/// started inside a damaged one survives.
///
/// ```
/// use lms2xx::codec::frame::{Decoder, Event, MAX_TELEGRAM};
/// let stream = [0xFF, 0x06, 0x02, 0x80, 0x03, 0x00, 0xA0, 0x00, 0x10, 0x16, 0x0A];
/// let mut dec = Decoder::<MAX_TELEGRAM>::new();
/// let mut rest = &stream[..];
/// let mut seen = 0;
/// loop {
///     let (used, ev) = dec.feed(rest);
///     rest = rest.get(used..).unwrap_or(&[]);
///     match ev {
///         Some(Event::Ack) => seen += 1,
///         Some(Event::Telegram(t)) => { assert_eq!(t.payload(), &[0xA0, 0x00, 0x10]); seen += 1 }
///         Some(Event::Nak) => return Err("no NAK in this stream"),
///         None => break,
///     }
/// }
/// assert_eq!(seen, 2);
/// assert_eq!(dec.stats().bytes_skipped, 1);
/// # Ok::<(), &'static str>(())
/// ```
#[derive(Clone, Debug)]
pub struct Decoder<const CAP: usize> {
    buf: [u8; CAP],
    len: usize,
    /// Length of the telegram at the front of `buf` that was last returned (dropped on next feed).
    delivered: usize,
    address: u8,
    stats: DecoderStats,
}

impl<const CAP: usize> Default for Decoder<CAP> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const CAP: usize> Decoder<CAP> {
    /// A decoder for device→host telegrams (address 0x80).
    pub const fn new() -> Self {
        Self::with_address(DEVICE_ADDRESS)
    }

    /// A decoder accepting only telegrams with address byte `address` (0x00 for host→device).
    pub const fn with_address(address: u8) -> Self {
        Self {
            buf: [0; CAP],
            len: 0,
            delivered: 0,
            address,
            stats: DecoderStats {
                telegrams: 0,
                crc_errors: 0,
                bad_length: 0,
                overflows: 0,
                bytes_skipped: 0,
                acks: 0,
                naks: 0,
            },
        }
    }

    /// Counters so far.
    pub fn stats(&self) -> DecoderStats {
        self.stats
    }

    /// Sets all counters to zero.
    pub fn reset_stats(&mut self) {
        self.stats = DecoderStats::default();
    }

    /// Discards any partly received telegram (e.g. after a baud change). Counts them as skipped.
    pub fn clear(&mut self) {
        self.drop_delivered();
        self.skip(self.len);
        self.len = 0;
    }

    /// Bytes buffered for a telegram not yet complete.
    pub fn pending(&self) -> usize {
        self.len.saturating_sub(self.delivered)
    }

    fn skip(&mut self, n: usize) {
        let n = u32::try_from(n).unwrap_or(u32::MAX);
        self.stats.bytes_skipped = self.stats.bytes_skipped.saturating_add(n);
    }

    /// Removes the first `n` buffered bytes.
    fn shift(&mut self, n: usize) {
        // Written so the optimiser can see no bounds check can fail (`cargo xtask no-panic`).
        let len = self.len.min(CAP);
        let n = n.min(len);
        if let Some(live) = self.buf.get_mut(..len) {
            live.copy_within(n.., 0);
        }
        self.len = len - n;
    }

    fn drop_delivered(&mut self) {
        if self.delivered > 0 {
            self.shift(self.delivered);
            self.delivered = 0;
        }
    }

    /// Examines the buffer; drops rejected candidates one STX at a time.
    fn settle(&mut self) -> Settle {
        loop {
            let Some(&first) = self.buf.get(..self.len).and_then(|b| b.first()) else {
                return Settle::NeedMore;
            };
            if first != STX {
                // Rescanned bytes: skip to the next STX (ACK/NAK inside damaged data are noise).
                let pos = self
                    .buf
                    .get(..self.len)
                    .and_then(|b| b.iter().position(|&x| x == STX))
                    .unwrap_or(self.len);
                self.skip(pos);
                self.shift(pos);
                continue;
            }
            let Some(&adr) = self.buf.get(1).filter(|_| self.len >= 2) else {
                return Settle::NeedMore;
            };
            if adr != self.address {
                self.skip(1);
                self.shift(1);
                continue;
            }
            if self.len < 4 {
                return Settle::NeedMore;
            }
            let total = match self.announced_total() {
                Ok(t) => t,
                Err(overflow) => {
                    if overflow {
                        self.stats.overflows = self.stats.overflows.saturating_add(1);
                    } else {
                        self.stats.bad_length = self.stats.bad_length.saturating_add(1);
                    }
                    self.skip(1);
                    self.shift(1);
                    continue;
                }
            };
            if self.len < total {
                return Settle::NeedMore;
            }
            let ok = self
                .buf
                .get(..total)
                .is_some_and(|t| Telegram::parse(t).is_ok());
            if ok {
                self.stats.telegrams = self.stats.telegrams.saturating_add(1);
                return Settle::Complete(total);
            }
            self.stats.crc_errors = self.stats.crc_errors.saturating_add(1);
            self.skip(1);
            self.shift(1);
        }
    }

    /// Total length announced by the buffered header; `Err(true)` for an overflow of `CAP`,
    /// `Err(false)` for a length outside the protocol.
    fn announced_total(&self) -> Result<usize, bool> {
        let (Some(&lo), Some(&hi)) = (self.buf.get(2), self.buf.get(3)) else {
            return Err(false);
        };
        let len = usize::from(u16::from_le_bytes([lo, hi]));
        if len == 0 || len > MAX_LEN {
            return Err(false);
        }
        if len + OVERHEAD > CAP {
            return Err(true);
        }
        Ok(len + OVERHEAD)
    }

    fn event(&self, total: usize) -> Option<Event<'_>> {
        self.buf
            .get(..total)
            .map(|raw| Event::Telegram(Telegram { raw }))
    }

    /// Consumes bytes from `input` until one event is complete or the input is used up.
    /// Returns the number of bytes consumed and the event, if any. A returned telegram borrows
    /// the decoder until the next call.
    pub fn feed(&mut self, input: &[u8]) -> (usize, Option<Event<'_>>) {
        if self.delivered > 0 {
            self.drop_delivered();
            if let Settle::Complete(total) = self.settle() {
                self.delivered = total;
                return (0, self.event(total));
            }
        }
        let mut used = 0usize;
        while let Some(rest) = input.get(used..).filter(|r| !r.is_empty()) {
            if self.len == 0 {
                // Hunting: ACK / NAK are events, STX starts a telegram, all else is skipped.
                let pos = rest
                    .iter()
                    .position(|&b| b == STX || b == ACK || b == NAK)
                    .unwrap_or(rest.len());
                self.skip(pos);
                used = used.saturating_add(pos);
                match rest.get(pos) {
                    Some(&ACK) => {
                        self.stats.acks = self.stats.acks.saturating_add(1);
                        return (used.saturating_add(1), Some(Event::Ack));
                    }
                    Some(&NAK) => {
                        self.stats.naks = self.stats.naks.saturating_add(1);
                        return (used.saturating_add(1), Some(Event::Nak));
                    }
                    Some(&b) => {
                        if let Some(slot) = self.buf.get_mut(0) {
                            *slot = b;
                            self.len = 1;
                        } else {
                            // CAP == 0: nothing can ever be buffered.
                            self.skip(1);
                        }
                        used = used.saturating_add(1);
                        continue;
                    }
                    None => break,
                }
            }
            // The address byte is checked before anything after it is buffered, so a wrong
            // address is rejected at the same byte however the stream is chunked.
            let want = if self.len < 2 {
                2 - self.len
            } else if self.len < 4 {
                4 - self.len
            } else {
                match self.announced_total() {
                    Ok(t) => t.saturating_sub(self.len),
                    Err(_) => 0,
                }
            };
            let take = want.min(rest.len());
            if let (Some(dst), Some(src)) = (
                self.buf.get_mut(self.len..self.len.saturating_add(take)),
                rest.get(..take),
            ) {
                for (d, s) in dst.iter_mut().zip(src) {
                    *d = *s;
                }
                self.len = self.len.saturating_add(take);
                used = used.saturating_add(take);
            } else {
                // Only reachable when CAP cannot even hold a header: drop what we have.
                self.stats.overflows = self.stats.overflows.saturating_add(1);
                self.skip(self.len);
                self.len = 0;
            }
            if let Settle::Complete(total) = self.settle() {
                self.delivered = total;
                return (used, self.event(total));
            }
        }
        (used, None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn encode_round_trip() -> Result<(), FrameError> {
        let mut buf = [0u8; 32];
        let n = encode_telegram(DEVICE_ADDRESS, &[0xA0, 0x00, 0x10], &mut buf)?;
        let sent = buf.get(..n).ok_or(FrameError::BufferTooSmall)?;
        assert_eq!(
            sent,
            &[0x02, 0x80, 0x03, 0x00, 0xA0, 0x00, 0x10, 0x16, 0x0A]
        );
        assert!(Telegram::parse(sent).is_ok());
        assert_eq!(
            encode_telegram(0x80, &[0; 10], &mut [0u8; 15]),
            Err(FrameError::BufferTooSmall)
        );
        assert_eq!(
            encode_telegram(0x80, &[], &mut buf),
            Err(FrameError::BadLength(0))
        );
        Ok(())
    }
}
