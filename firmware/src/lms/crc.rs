//! The LMS2xx telegram checksum.
//!
//! It is *not* a standard CRC-16: the register shifts once per byte (not once per bit) and the
//! data word is `previous byte << 8 | current byte` (protocol fact sheet §1). Polynomial 0x8005,
//! initial value 0, sent low byte first.

/// Polynomial of the LMS2xx checksum.
pub const POLY: u16 = 0x8005;

/// One byte `b` after `prev`: shift the register once (folding in the polynomial when its top
/// bit falls out), then add the data word `prev << 8 | b`.
#[inline(always)]
const fn step(crc: u16, prev: u8, b: u8) -> u16 {
    // All ones when the top bit is set (arithmetic shift), else zero.
    let fold = ((crc as i16) >> 15) as u16 & POLY;
    ((crc << 1) ^ fold) ^ (((prev as u16) << 8) | b as u16)
}

/// The register shifted `k` times with no data (the checksum is linear over GF(2): four steps
/// are the register shifted four times plus each byte's own contribution).
const fn shift(mut crc: u16, k: u32) -> u16 {
    let mut i = 0;
    while i < k {
        crc = step(crc, 0, 0);
        i += 1;
    }
    crc
}

/// Contributions to the register after eight bytes `b0 … b7` following `prev`:
/// `L⁸(c) ^ L⁷(prev << 8 | b0) ^ L⁶(b0 << 8 | b1) ^ … ^ L(b5 << 8 | b6) ^ (b6 << 8 | b7)`, L
/// one shift, grouped by byte. Tables built at compile time (4 KiB of flash); `L(b6) = b6 << 1`
/// and `b7` need none.
struct Tables {
    /// `L⁸` of the register's top eight bits (the low eight just shift).
    top: [u16; 256],
    /// `L⁷(prev << 8)`.
    prev: [u16; 256],
    /// `L^(7−k)(b) ^ L^(6−k)(b << 8)` for byte `k` = 0 … 5.
    bytes: [[u16; 256]; 6],
}

#[allow(clippy::indexing_slicing)] // compile time: an index out of range is a build error
const TABLES: Tables = {
    let mut t = Tables {
        top: [0; 256],
        prev: [0; 256],
        bytes: [[0; 256]; 6],
    };
    let mut i = 0;
    while i < 256 {
        let v = i as u16;
        t.top[i] = shift(v << 8, 8);
        t.prev[i] = shift(v << 8, 7);
        let mut k = 0;
        while k < 6 {
            t.bytes[k][i] = shift(v, 7 - k as u32) ^ shift(v << 8, 6 - k as u32);
            k += 1;
        }
        i += 1;
    }
    t
};

/// Eight bytes at once (see [`Tables`]); indices are < 256 by type, so `get` never fails.
#[inline(always)]
fn step8(crc: u16, prev: u8, b: [u8; 8]) -> u16 {
    let t = &TABLES;
    let at = |table: &[u16; 256], i: u8| table.get(usize::from(i)).copied().unwrap_or(0);
    let [b0, b1, b2, b3, b4, b5, b6, b7] = b;
    let [tb0, tb1, tb2, tb3, tb4, tb5] = &t.bytes;
    let b6 = u16::from(b6);
    (crc << 8)
        ^ at(&t.top, (crc >> 8) as u8)
        ^ at(&t.prev, prev)
        ^ at(tb0, b0)
        ^ at(tb1, b1)
        ^ at(tb2, b2)
        ^ at(tb3, b3)
        ^ at(tb4, b4)
        ^ at(tb5, b5)
        ^ (b6 << 1)
        ^ (b6 << 8)
        ^ u16::from(b7)
}

/// Incremental form of [`crc16`]: feed bytes in any chunking, read [`Crc::value`].
///
/// ```
/// use firmware::lms::crc::Crc;
/// let mut c = Crc::new();
/// c.update(&[0x02, 0x00, 0x02]);
/// c.update(&[0x00, 0x20, 0x24]);
/// assert_eq!(c.value(), 0x0834);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Crc {
    crc: u16,
    prev: u8,
}

impl Crc {
    /// A checksum over no bytes.
    pub const fn new() -> Self {
        Self { crc: 0, prev: 0 }
    }

    /// Adds `bytes`.
    pub fn update(&mut self, bytes: &[u8]) {
        // Eight bytes an iteration, the register and the previous byte in locals: the decoder
        // runs this over every telegram byte.
        let (mut crc, mut prev) = (self.crc, self.prev);
        let mut octets = bytes.chunks_exact(8);
        for octet in octets.by_ref() {
            if let Ok(b) = <[u8; 8]>::try_from(octet) {
                crc = step8(crc, prev, b);
                prev = b[7];
            }
        }
        for &b in octets.remainder() {
            crc = step(crc, prev, b);
            prev = b;
        }
        (self.crc, self.prev) = (crc, prev);
    }

    /// The checksum so far.
    pub const fn value(&self) -> u16 {
        self.crc
    }
}

/// Checksum of `bytes` (STX up to the last byte before the CRC).
///
/// ```
/// use firmware::lms::crc::crc16;
/// assert_eq!(crc16(&[0x02, 0x00, 0x02, 0x00, 0x20, 0x24]), 0x0834);
/// ```
pub fn crc16(bytes: &[u8]) -> u16 {
    let mut c = Crc::new();
    c.update(bytes);
    c.value()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn differs_from_standard_presets() {
        // CRC-16/BUYPASS gives 0x98DB and CRC-16/ARC 0x8119 for this input (fact sheet §1).
        let v = crc16(&[0x02, 0x00, 0x02, 0x00, 0x20, 0x24]);
        assert_eq!(v, 0x0834);
        assert_ne!(v, 0x98DB);
        assert_ne!(v, 0x8119);
    }

    /// Eight bytes at once agree with eight single steps, for registers, previous bytes and
    /// byte octets of every kind.
    #[test]
    fn eight_bytes_at_once_match_eight_steps() {
        let mut x = 0x1234_5678_9abc_def0u64;
        for k in 0..200_000u32 {
            // xorshift: bytes and registers of every kind.
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let b = x.to_le_bytes();
            let crc = (x >> 11) as u16 ^ (k as u16);
            let prev = (x >> 40) as u8 ^ (k >> 8) as u8;
            let (mut by_one, mut p) = (crc, prev);
            for &byte in &b {
                by_one = step(by_one, p, byte);
                p = byte;
            }
            assert_eq!(
                step8(crc, prev, b),
                by_one,
                "{crc:#06x} {prev:#04x} {x:#018x}"
            );
        }
    }

    #[test]
    fn chunking_does_not_matter() {
        let data = [0x02u8, 0x80, 0x03, 0x00, 0xA0, 0x00, 0x10];
        for split in 0..=data.len() {
            let (a, b) = data.split_at(split);
            let mut c = Crc::new();
            c.update(a);
            c.update(b);
            assert_eq!(c.value(), 0x0A16);
        }
    }
}
