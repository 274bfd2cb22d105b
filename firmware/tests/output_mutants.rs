//! Output-frame facts the other tests leave open, checked against the COBS definition, not
//! against the code's own output (docs/TESTING.md, mutation section).

use firmware::output::{
    decode_frame, max_frame_len, DecodeError, EncodeError, MAX_FEATURE_LEN, WIRE_VERSION,
};

/// `max_frame_len` covers the worst case of COBS: `raw` bytes (header ≤ 64, features, CRC 4)
/// take one code byte per started run of 254, plus the terminating zero; and it adds no more
/// than one byte of slack beyond that.
#[test]
fn max_frame_len_is_the_cobs_worst_case() {
    for n in [0usize, 1, 2, 3, 10, 33, 64] {
        let raw = 64 + n * MAX_FEATURE_LEN + 4;
        let worst = raw + raw.div_ceil(254) + 1;
        let got = max_frame_len(n);
        assert!(got >= worst, "{n} features: {got} < {worst}");
        assert!(got <= worst + 1, "{n} features: {got} > {worst} + 1");
    }
}

/// COBS output holds no zero byte: a zero code inside a frame is broken COBS, whatever the
/// rest would decode to. (Hand-made: code 3 → two data bytes and a zero, then a zero code.)
#[test]
fn a_zero_code_byte_is_broken_cobs() {
    let mut buf = [0x03, 0x11, 0x22, 0x00, 0x01];
    assert_eq!(decode_frame(&mut buf), Err(DecodeError::Cobs));
    // A code that runs past the end.
    let mut buf = [0x05, 0x11, 0x22];
    assert_eq!(decode_frame(&mut buf), Err(DecodeError::Cobs));
}

/// The error messages say what went wrong, with the values involved.
#[test]
fn error_messages_name_the_values() {
    let crc = DecodeError::Crc {
        expected: 0x1234_5678,
        got: 0x0BAD_F00D,
    }
    .to_string();
    assert!(
        crc.contains("0x12345678") && crc.contains("0x0badf00d"),
        "{crc}"
    );
    let v = DecodeError::UnknownVersion { version: 7 }.to_string();
    assert!(
        v.contains('7') && v.contains(&WIRE_VERSION.to_string()),
        "{v}"
    );
    let n = DecodeError::TooManyFeatures { n: 999 }.to_string();
    assert!(n.contains("999"), "{n}");
    let others = [
        DecodeError::Overflow,
        DecodeError::Cobs,
        DecodeError::TooShort,
        DecodeError::Payload,
        DecodeError::TrailingBytes,
    ]
    .map(|e| e.to_string());
    for (i, m) in others.iter().enumerate() {
        assert!(!m.is_empty());
        assert!(!others[..i].contains(m), "two errors read {m:?}");
    }
    let w = EncodeError::Write("uart gone").to_string();
    assert!(w.contains("uart gone"), "{w}");
    assert!(!EncodeError::<()>::Serialize.to_string().is_empty());
}
