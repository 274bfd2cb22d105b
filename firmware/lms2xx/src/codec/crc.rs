//! The LMS2xx telegram checksum.
//!
//! It is *not* a standard CRC-16: the register shifts once per byte (not once per bit) and the
//! data word is `previous byte << 8 | current byte` (protocol fact sheet §1). Polynomial 0x8005,
//! initial value 0, sent low byte first.

/// Polynomial of the LMS2xx checksum.
pub const POLY: u16 = 0x8005;

/// One byte `b` after `prev`: shift the register once (folding in the polynomial when its top
/// bit falls out), then add the data word `prev << 8 | b`. The definition; [`Crc`] computes
/// the same value faster (and is tested against it).
#[cfg(test)]
const fn step(crc: u16, prev: u8, b: u8) -> u16 {
    shift(crc, 1) ^ (((prev as u16) << 8) | b as u16)
}

/// `Lᵏ(crc)`: the register shifted `k` times with no data, L one shift.
#[inline(always)]
const fn shift(mut crc: u16, k: u32) -> u16 {
    let mut i = 0;
    while i < k {
        // All ones when the top bit is set (arithmetic shift), else zero.
        let fold = ((crc as i16) >> 15) as u16 & POLY;
        crc = (crc << 1) ^ fold;
        i += 1;
    }
    crc
}

/// `L⁸` of the register's top eight bits, built at compile time (512 bytes of flash); the low
/// eight just shift.
#[allow(clippy::indexing_slicing)] // compile time: an index out of range is a build error
const TOP: [u16; 256] = {
    let mut t = [0u16; 256];
    let mut i = 0;
    while i < 256 {
        t[i] = shift((i as u16) << 8, 8);
        i += 1;
    }
    t
};

/// Incremental form of [`crc16`]: feed bytes in any chunking, read [`Crc::value`].
///
/// The checksum is linear over GF(2) and a byte shifted up to eight times never reaches the
/// register's top bit, so the data words split: after bytes `b₀ … bₙ₋₁` the checksum is
/// `S ^ L⁷(S ^ bₙ₋₁)` with `S = Σ Lⁿ⁻¹⁻ʲ(bⱼ)` the plain byte sum (`S ← L(S) ^ b` a byte),
/// and eight bytes add to `S` as `L⁸(S) ^ Σ bⱼ << (7 − j)`: shifts and one table lookup.
///
/// ```
/// use lms2xx::codec::crc::Crc;
/// let mut c = Crc::new();
/// c.update(&[0x02, 0x00, 0x02]);
/// c.update(&[0x00, 0x20, 0x24]);
/// assert_eq!(c.value(), 0x0834);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Crc {
    /// `S`, the plain byte sum.
    sum: u16,
    /// The last byte.
    last: u8,
}

impl Crc {
    /// A checksum over no bytes.
    pub const fn new() -> Self {
        Self { sum: 0, last: 0 }
    }

    /// Adds `bytes`.
    pub fn update(&mut self, bytes: &[u8]) {
        // Eight bytes an iteration, the sum in a local: the decoder runs this over every
        // telegram byte.
        let mut sum = self.sum;
        let mut octets = bytes.chunks_exact(8);
        for octet in octets.by_ref() {
            if let Ok(b) = <[u8; 8]>::try_from(octet) {
                sum = add8(sum, b);
            }
        }
        for &b in octets.remainder() {
            sum = shift(sum, 1) ^ u16::from(b);
        }
        self.sum = sum;
        if let Some(&b) = bytes.last() {
            self.last = b;
        }
    }

    /// The checksum so far.
    pub const fn value(&self) -> u16 {
        self.sum ^ shift(self.sum ^ self.last as u16, 7)
    }
}

/// Eight bytes added to the plain sum `s` (see [`Crc`]); the table index is < 256 by type, so
/// `get` never fails.
#[inline(always)]
fn add8(s: u16, b: [u8; 8]) -> u16 {
    let [b0, b1, b2, b3, b4, b5, b6, b7] = b;
    let [w0, w1] = [[b0, b1, b2, b3], [b4, b5, b6, b7]].map(u32::from_le_bytes);
    // Byte j of the eight moved to bit 7 − j (its four bytes from `top` down).
    let spread = |w: u32, top: u32| {
        ((w & 0xFF) << top)
            ^ (((w >> 8) & 0xFF) << (top - 1))
            ^ (((w >> 16) & 0xFF) << (top - 2))
            ^ ((w >> 24) << (top - 3))
    };
    let bytes = spread(w0, 7) ^ spread(w1, 3);
    let top = TOP.get(usize::from(s >> 8)).copied().unwrap_or(0);
    (s << 8) ^ top ^ bytes as u16
}

/// Checksum of `bytes` (STX up to the last byte before the CRC).
///
/// ```
/// use lms2xx::codec::crc::crc16;
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

    /// The fast form agrees with the definition, byte by byte, for data of every kind and
    /// length (0 to 40 bytes, so every remainder after the eight-byte steps) fed in any
    /// chunking.
    #[test]
    fn fast_form_matches_the_definition() {
        let mut x = 0x1234_5678_9abc_def0u64;
        for k in 0..100_000u32 {
            // xorshift: bytes of every kind.
            let mut data = [0u8; 40];
            for b in &mut data {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                *b = (x >> 24) as u8;
            }
            let len = (k % 41) as usize;
            let data = &data[..len];
            let (mut want, mut prev) = (0u16, 0u8);
            for &b in data {
                want = step(want, prev, b);
                prev = b;
            }
            assert_eq!(crc16(data), want, "{data:02x?}");
            let cut = (x as usize) % (len + 1);
            let mut c = Crc::new();
            c.update(&data[..cut]);
            c.update(&[]);
            c.update(&data[cut..]);
            assert_eq!(c.value(), want, "{data:02x?} cut at {cut}");
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
