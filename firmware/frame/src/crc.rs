//! CRC-32/ISO-HDLC (the zlib / Ethernet CRC) of the frames, one table lookup a byte.

/// CRC-32/ISO-HDLC of `data`, continuing from `crc` (start with `0`).
///
/// ```
/// assert_eq!(pfe_frame::crc32(0, b"123456789"), 0xCBF4_3926);
/// ```
pub fn crc32(crc: u32, data: &[u8]) -> u32 {
    !data.iter().fold(!crc, |c, &b| crc32_byte(c, b))
}

/// CRC-32 byte table (1 KiB of flash, built at compile time: an index out of range would be a
/// build error, not a panic).
#[allow(clippy::indexing_slicing)]
const CRC32_TABLE: [u32; 256] = {
    let mut t = [0u32; 256];
    let mut i = 0;
    while i < 256 {
        let mut c = i as u32;
        let mut k = 0;
        while k < 8 {
            c = if c & 1 != 0 {
                (c >> 1) ^ 0xEDB8_8320
            } else {
                c >> 1
            };
            k += 1;
        }
        t[i] = c;
        i += 1;
    }
    t
};

/// Shifts one byte out of the (complemented) CRC-32 register: one table lookup.
#[inline(always)]
fn crc32_shift(c: u32) -> u32 {
    // The index is < 256: `get` never fails.
    (c >> 8) ^ CRC32_TABLE.get((c & 0xFF) as usize).copied().unwrap_or(0)
}

/// One byte of CRC-32 (on the complemented register).
#[inline(always)]
pub(super) fn crc32_byte(c: u32, b: u8) -> u32 {
    crc32_shift(c ^ u32::from(b))
}

/// Four bytes of CRC-32, `w` their little-endian word (on the complemented register).
#[inline(always)]
pub(super) fn crc32_word(c: u32, w: u32) -> u32 {
    crc32_shift(crc32_shift(crc32_shift(crc32_shift(c ^ w))))
}
