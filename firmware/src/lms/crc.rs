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

/// Contributions to the register after four bytes `b0 b1 b2 b3` following `prev`: `L⁴(c) ^
/// L³(prev << 8 | b0) ^ L²(b0 << 8 | b1) ^ L(b1 << 8 | b2) ^ (b2 << 8 | b3)`, L one shift.
/// Tables built at compile time (1.6 KiB of flash); `L(b2) = b2 << 1` and `b3` need none.
struct Tables {
    /// `L⁴` of the register's top four bits (the low twelve just shift).
    top: [u16; 16],
    /// `L³(prev << 8)`.
    prev: [u16; 256],
    /// `L³(b0) ^ L²(b0 << 8)`.
    b0: [u16; 256],
    /// `L²(b1) ^ L(b1 << 8)`.
    b1: [u16; 256],
}

#[allow(clippy::indexing_slicing)] // compile time: an index out of range is a build error
const TABLES: Tables = {
    let mut t = Tables {
        top: [0; 16],
        prev: [0; 256],
        b0: [0; 256],
        b1: [0; 256],
    };
    let mut i = 0;
    while i < 256 {
        let v = i as u16;
        if i < 16 {
            t.top[i] = shift(v << 12, 4);
        }
        t.prev[i] = shift(v << 8, 3);
        t.b0[i] = shift(v, 3) ^ shift(v << 8, 2);
        t.b1[i] = shift(v, 2) ^ shift(v << 8, 1);
        i += 1;
    }
    t
};

/// Four bytes at once (see [`Tables`]); indices are < 16 or < 256 by type, so `get` never
/// fails.
#[inline(always)]
fn step4(crc: u16, prev: u8, [b0, b1, b2, b3]: [u8; 4]) -> u16 {
    let t = &TABLES;
    let at = |table: &[u16], i: usize| table.get(i).copied().unwrap_or(0);
    let b2 = u16::from(b2);
    (crc << 4)
        ^ at(&t.top, usize::from(crc >> 12))
        ^ at(&t.prev, usize::from(prev))
        ^ at(&t.b0, usize::from(b0))
        ^ at(&t.b1, usize::from(b1))
        ^ (b2 << 1)
        ^ (b2 << 8)
        ^ u16::from(b3)
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
        // Four bytes an iteration, the register and the previous byte in locals: the decoder
        // runs this over every telegram byte.
        let (mut crc, mut prev) = (self.crc, self.prev);
        let mut quads = bytes.chunks_exact(4);
        for quad in quads.by_ref() {
            if let [a, b, c, d] = *quad {
                crc = step4(crc, prev, [a, b, c, d]);
                prev = d;
            }
        }
        for &b in quads.remainder() {
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

    /// Four bytes at once agree with four single steps, for every register value with the
    /// top four bits and many byte quadruples.
    #[test]
    fn four_bytes_at_once_match_four_steps() {
        let mut x = 0x1234_5678u32;
        for k in 0..200_000u32 {
            // xorshift: bytes and registers of every kind.
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            let [a, b, c, d] = x.to_le_bytes();
            let crc = (x >> 7) as u16 ^ (k as u16);
            let prev = (x >> 24) as u8 ^ (k >> 8) as u8;
            let by_one = step(step(step(step(crc, prev, a), a, b), b, c), c, d);
            assert_eq!(
                step4(crc, prev, [a, b, c, d]),
                by_one,
                "{crc:#06x} {prev:#04x} {x:#010x}"
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
