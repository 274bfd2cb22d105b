//! The emulator's own telegram encoder, written from the protocol notes
//! (`../shared/docs/lms200-protocol.md` §1), not from the firmware's codec: the emulator and the
//! driver under test are two independent sides, so a framing or CRC bug in one is seen by the
//! other. Checked against the published vectors (`lms200-test-vectors.txt`) in the tests below.
//!
//! ```text
//! STX(0x02) | ADR | LEN_L LEN_H | CMD | DATA ... | STATUS | CRC_L CRC_H
//! ```
//! LEN counts CMD through STATUS; the CRC covers STX through STATUS and goes low byte first.

/// Start of every telegram.
pub const STX: u8 = 0x02;
/// Address byte of LMS→host telegrams.
pub const FROM_DEVICE: u8 = 0x80;

/// The protocol's CRC16 (notes §1, "CRC16"): not a standard CRC-16, it shifts once per byte
/// with polynomial 0x8005 and XORs in the 16-bit word (previous byte : current byte).
pub fn crc16(bytes: &[u8]) -> u16 {
    let mut crc: u16 = 0;
    let mut prev: u8 = 0;
    for &b in bytes {
        crc = if crc & 0x8000 != 0 {
            ((crc & 0x7FFF) << 1) ^ 0x8005
        } else {
            crc << 1
        };
        crc ^= u16::from_be_bytes([prev, b]);
        prev = b;
    }
    crc
}

/// A telegram to the host with `payload` = CMD, DATA and the status byte; `None` when the
/// payload does not fit the 16-bit length field.
pub fn device_telegram(payload: &[u8]) -> Option<Vec<u8>> {
    telegram(FROM_DEVICE, payload)
}

/// A telegram with address byte `address` around `payload` (CMD through the last byte before
/// the CRC).
pub fn telegram(address: u8, payload: &[u8]) -> Option<Vec<u8>> {
    let len = u16::try_from(payload.len()).ok()?;
    let mut t = Vec::with_capacity(payload.len() + 6);
    t.push(STX);
    t.push(address);
    t.extend_from_slice(&len.to_le_bytes());
    t.extend_from_slice(payload);
    let crc = crc16(&t);
    t.extend_from_slice(&crc.to_le_bytes());
    Some(t)
}

#[cfg(test)]
mod tests {
    use super::{crc16, device_telegram, telegram};

    /// Hex bytes of a vector line (`label   02 00 ...   (crc=0x....)`).
    fn vector(line: &str) -> Option<(Vec<u8>, u16)> {
        let (body, crc) = line.split_once("(crc=0x")?;
        let crc = u16::from_str_radix(crc.trim_end_matches(')').trim(), 16).ok()?;
        let words: Vec<&str> = body.split_whitespace().collect();
        let start = words.iter().position(|w| *w == "02")?;
        let bytes: Option<Vec<u8>> = words[start..]
            .iter()
            .map(|w| u8::from_str_radix(w, 16).ok())
            .collect();
        Some((bytes?, crc))
    }

    #[test]
    fn crc_and_framing_match_the_notes_examples() {
        // Notes §1: `02 00 02 00 20 24` has CRC 0x0834 (not BUYPASS 0x98DB nor ARC 0x8119).
        assert_eq!(crc16(&[0x02, 0x00, 0x02, 0x00, 0x20, 0x24]), 0x0834);
        assert_eq!(
            telegram(0x00, &[0x20, 0x24]).unwrap(),
            [0x02, 0x00, 0x02, 0x00, 0x20, 0x24, 0x34, 0x08]
        );
        // The 3-value B0 in cm, status 0x10.
        assert_eq!(
            device_telegram(&[0xB0, 0x03, 0x00, 0x64, 0x00, 0xC8, 0x00, 0x2C, 0x01, 0x10]).unwrap(),
            [
                0x02, 0x80, 0x0A, 0x00, 0xB0, 0x03, 0x00, 0x64, 0x00, 0xC8, 0x00, 0x2C, 0x01, 0x10,
                0xBE, 0x64
            ]
        );
    }

    #[test]
    fn every_published_vector_is_reproduced() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../../shared/docs/lms200-test-vectors.txt");
        let Ok(text) = std::fs::read_to_string(&path) else {
            pfe_testkit::skip::skip(
                "emulator telegram vectors",
                &format!("{} is absent", path.display()),
                pfe_testkit::skip::Need::InCi,
            );
            return;
        };
        let mut n = 0;
        for line in text.lines() {
            let Some((bytes, crc)) = vector(line) else {
                continue;
            };
            let (address, payload) = (bytes[1], &bytes[4..bytes.len() - 2]);
            assert_eq!(telegram(address, payload).unwrap(), bytes, "{line}");
            assert_eq!(crc16(&bytes[..bytes.len() - 2]), crc, "{line}");
            n += 1;
        }
        assert!(n >= 20, "{n} vectors in {}", path.display());
    }
}
