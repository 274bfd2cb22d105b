//! Output-frame facts the other tests leave open, checked against the COBS definition, not
//! against the code's own output (docs/TESTING.md, mutation section).

use firmware::output::{max_frame_len, MAX_FEATURE_LEN};

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
