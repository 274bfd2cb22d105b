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
fn step(crc: u16, prev: u8, b: u8) -> u16 {
    // All ones when the top bit is set (arithmetic shift), else zero.
    let fold = ((crc as i16) >> 15) as u16 & POLY;
    ((crc << 1) ^ fold) ^ ((u16::from(prev) << 8) | u16::from(b))
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
        // Two bytes an iteration, the register and the previous byte in locals: the decoder
        // runs this over every telegram byte.
        let (mut crc, mut prev) = (self.crc, self.prev);
        let mut pairs = bytes.chunks_exact(2);
        for pair in pairs.by_ref() {
            if let [a, b] = *pair {
                crc = step(crc, prev, a);
                crc = step(crc, a, b);
                prev = b;
            }
        }
        for &b in pairs.remainder() {
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
