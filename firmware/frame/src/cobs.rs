//! COBS framing: the streaming encoder (with the frame's CRC-32 taken in the same loop) and
//! the in-place decoder.

use serde::Serialize;

use super::crc::{crc32_byte, crc32_word};
use super::decoder::DecodeError;
use super::encoder::EncodeError;

/// Streaming COBS encoder with a CRC-32 over what it is given.
pub(super) struct CobsWriter<'w, W> {
    w: &'w mut W,
    /// `block[0]` is the code byte slot, data from 1.
    block: [u8; 255],
    len: usize,
    crc: u32,
}

impl<'w, W: embedded_io::Write> CobsWriter<'w, W> {
    pub(super) fn new(w: &'w mut W) -> Self {
        Self {
            w,
            block: [0; 255],
            len: 1,
            crc: 0,
        }
    }

    fn flush_block(&mut self) -> Result<(), W::Error> {
        if let Some(code) = self.block.first_mut() {
            *code = self.len as u8; // len ≤ 255
        }
        let out = self.block.get(..self.len).unwrap_or(&[]);
        self.w.write_all(out)?;
        self.len = 1;
        Ok(())
    }

    /// COBS-encodes `data` (with `CRC` its CRC-32 is also taken: one loop for both), four
    /// bytes at a time where they hold no zero and fit the block.
    fn encode<const CRC: bool>(&mut self, data: &[u8]) -> Result<(), W::Error> {
        let mut c = !self.crc;
        // Kept below 255 between bytes: a full block is flushed at once.
        let mut len = self.len;
        let mut words = data.chunks_exact(4);
        for word in words.by_ref() {
            let Ok(bytes) = <[u8; 4]>::try_from(word) else {
                continue;
            };
            let w = u32::from_le_bytes(bytes);
            if CRC {
                c = crc32_word(c, w);
            }
            // No zero byte in `w` (the classic bit trick: exact for "has none").
            let no_zero = w.wrapping_sub(0x0101_0101) & !w & 0x8080_8080 == 0;
            let slot = self
                .block
                .get_mut(len..len + 4)
                .and_then(|s| <&mut [u8; 4]>::try_from(s).ok());
            match slot {
                // len + 4 < 255: the block is not full after them.
                Some(slot) if no_zero && len + 4 < 255 => {
                    *slot = bytes;
                    len += 4;
                }
                _ => len = self.bytes(&bytes, len)?,
            }
        }
        self.len = self.bytes(words.remainder(), len)?;
        if CRC {
            self.crc = !words.remainder().iter().fold(c, |c, &b| crc32_byte(c, b));
        }
        Ok(())
    }

    /// COBS-encodes `data` byte by byte into the block at `len`; returns the new length.
    fn bytes(&mut self, data: &[u8], mut len: usize) -> Result<usize, W::Error> {
        for &b in data {
            if b != 0 {
                if let Some(slot) = self.block.get_mut(len) {
                    *slot = b;
                }
                len += 1;
                if len < 255 {
                    continue;
                }
            }
            self.len = len;
            self.flush_block()?;
            len = 1;
        }
        Ok(len)
    }

    fn raw(&mut self, data: &[u8]) -> Result<(), W::Error> {
        self.encode::<false>(data)
    }

    pub(super) fn put(&mut self, data: &[u8]) -> Result<(), W::Error> {
        self.encode::<true>(data)
    }

    pub(super) fn put_item<T: Serialize>(&mut self, item: &T) -> Result<(), EncodeError<W::Error>> {
        let mut scratch = [0u8; 96];
        let bytes = postcard::to_slice(item, &mut scratch).map_err(|_| EncodeError::Serialize)?;
        self.put(bytes).map_err(EncodeError::Write)
    }

    pub(super) fn finish(mut self) -> Result<(), W::Error> {
        let crc = self.crc.to_le_bytes();
        self.raw(&crc)?;
        // The last block ends at the frame end, not at a zero byte: its code says so by
        // being one more than its data length, which is what flush_block writes.
        self.flush_block()?;
        self.w.write_all(&[0])
    }
}

/// COBS-decodes `buf` in place, returning the decoded length.
pub(super) fn cobs_decode_in_place(buf: &mut [u8]) -> Result<usize, DecodeError> {
    let (mut r, mut w) = (0usize, 0usize);
    let n = buf.len();
    while r < n {
        let code = usize::from(*buf.get(r).ok_or(DecodeError::Cobs)?);
        if code == 0 || r + code > n {
            return Err(DecodeError::Cobs);
        }
        r += 1;
        for _ in 1..code {
            let b = *buf.get(r).ok_or(DecodeError::Cobs)?;
            *buf.get_mut(w).ok_or(DecodeError::Cobs)? = b;
            r += 1;
            w += 1;
        }
        if code < 0xFF && r < n {
            *buf.get_mut(w).ok_or(DecodeError::Cobs)? = 0;
            w += 1;
        }
    }
    Ok(w)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::indexing_slicing)]
    use super::*;

    extern crate std;

    /// The word-at-a-time encoder gives the `cobs` crate's bytes and `crc32fast`'s CRC for
    /// zero bytes at every position relative to a block's end and to the words, fed in pieces
    /// of every size.
    #[test]
    fn encoder_matches_cobs_and_crc32_at_every_alignment(
    ) -> Result<(), embedded_io::SliceWriteError> {
        for before in 0..300usize {
            for piece in [1usize, 3, 4, 7, 64] {
                let mut data: std::vec::Vec<u8> =
                    (0..before).map(|i| (i % 251 + 1) as u8).collect();
                data.push(0);
                data.extend((0..520).map(|i| (i % 13 + 1) as u8));
                data.push(0);
                data.extend([5, 0, 0, 6]);
                let mut buf = [0u8; 1024];
                let mut out = &mut buf[..];
                let mut enc = CobsWriter::new(&mut out);
                for chunk in data.chunks(piece) {
                    enc.put(chunk)?;
                }
                enc.finish()?;
                let written = 1024 - out.len();
                let mut raw = data.clone();
                raw.extend(crc32fast::hash(&data).to_le_bytes());
                let mut want = cobs::encode_vec(&raw);
                want.push(0);
                assert_eq!(&buf[..written], &want[..], "before {before} piece {piece}");
            }
        }
        Ok(())
    }
}
