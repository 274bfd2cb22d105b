//! Per-point flags of one scan (valid, segment start, segment end, jump, veil) and a search over
//! them that reads four flags at a time.

/// A valid point.
pub(crate) const VALID: u8 = 1;
/// First point of a segment (a mark point in the paper's sense).
pub(crate) const START: u8 = 2;
/// Last point of a segment (the paired mark point).
pub(crate) const END: u8 = 4;
/// A segment start caused by a jump (never inside one surface, so never merged).
pub(crate) const JUMP: u8 = 8;
/// A point of a line the scanner cannot see (a mixed pixel of a veil along a line of sight),
/// in no feature.
pub(crate) const VEIL: u8 = 16;

/// What [`next_flag`] looks for.
#[derive(Clone, Copy)]
pub(crate) enum Seek {
    /// A valid point that starts a segment.
    Mark,
    /// A point that is not a valid segment start.
    NotMark,
    /// A valid point.
    Valid,
    /// The end of a segment's points: a start or an invalid point.
    SegmentEnd,
}

impl Seek {
    /// A valid segment start.
    pub(crate) const MARK: u8 = VALID | START;
    /// `VALID` / `VALID | START` in each byte of a word of four flags.
    const V4: u32 = u32::from_le_bytes([VALID; 4]);
    const M4: u32 = u32::from_le_bytes([Self::MARK; 4]);

    fn hit(self, f: u8) -> bool {
        match self {
            Seek::Mark => f & Self::MARK == Self::MARK,
            Seek::NotMark => f & Self::MARK != Self::MARK,
            Seek::Valid => f & VALID != 0,
            Seek::SegmentEnd => f & Self::MARK != VALID,
        }
    }

    /// True when none of the four flags in `word` is a hit.
    fn none_in(self, word: u32) -> bool {
        match self {
            Seek::Mark => word & (Self::M4 & !Self::V4) == 0,
            Seek::NotMark => word & Self::M4 == Self::M4,
            Seek::Valid => word & Self::V4 == 0,
            Seek::SegmentEnd => word & Self::M4 == Self::V4,
        }
    }
}

/// The first index from `from` whose flag `seek` finds, four flags at a time where it can tell
/// from their word that none of them is one.
#[inline(always)]
pub(crate) fn next_flag(flags: &[u8], from: usize, seek: Seek) -> Option<usize> {
    let flags = flags.get(from..)?;
    let mut chunks = flags.chunks_exact(4);
    let mut base = from;
    for chunk in chunks.by_ref() {
        if let [a, b, c, d] = *chunk {
            if !seek.none_in(u32::from_le_bytes([a, b, c, d])) {
                if let Some(i) = chunk.iter().position(|&f| seek.hit(f)) {
                    return Some(base + i);
                }
            }
        }
        base += 4;
    }
    let rest = chunks.remainder();
    Some(base + rest.iter().position(|&f| seek.hit(f))?)
}

/// Each byte of a word of four flags.
const BYTES: u32 = 0x0101_0101;

/// Rewrites every flag of `flags` by `rule`, four at a time: `rule(word, lanes)` changes each
/// byte of `word` on its own (no carry between bytes) with its masks times `lanes`, so the
/// same rule rewrites the four bytes of a word (`lanes` = [`BYTES`]) and the flags left over
/// one by one (`lanes` = 1).
#[inline(always)]
pub(crate) fn rewrite(flags: &mut [u8], rule: impl Fn(u32, u32) -> u32) {
    let mut words = flags.chunks_exact_mut(4);
    for w in words.by_ref() {
        if let Ok(b) = <[u8; 4]>::try_from(&*w) {
            w.copy_from_slice(&rule(u32::from_le_bytes(b), BYTES).to_le_bytes());
        }
    }
    for f in words.into_remainder() {
        *f = rule(u32::from(*f), 1) as u8;
    }
}

/// Segment starts among `flags`, four flags at a time.
pub(crate) fn starts(flags: &[u8]) -> usize {
    const SHIFT: u32 = START.trailing_zeros();
    let mut words = flags.chunks_exact(4);
    let mut n = 0usize;
    for w in words.by_ref() {
        if let Ok(b) = <[u8; 4]>::try_from(w) {
            // Each byte 0 or 1; the product's top byte is their sum.
            let ones = (u32::from_le_bytes(b) >> SHIFT) & BYTES;
            n += (ones.wrapping_mul(BYTES) >> 24) as usize;
        }
    }
    let rest = words.remainder().iter();
    n + rest.filter(|f| **f & START != 0).count()
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;

    /// Flags rewritten four at a time are each rewritten by the rule on its own, and the
    /// starts counted four at a time are the starts: every length to 11 of flags made of
    /// every byte value.
    #[test]
    fn flags_four_at_a_time_are_flags_one_by_one() {
        let rule = |f: u32, lanes: u32| {
            let valid = f & (u32::from(VALID) * lanes);
            let walked = (f & (u32::from(START | JUMP) * lanes)) << 4;
            valid | (walked & (valid * 0xff)) | (f & (0x40 * lanes))
        };
        let mut s = 5u32;
        for t in 0..3000 {
            let len = t % 12;
            let flags: std::vec::Vec<u8> = (0..len)
                .map(|_| {
                    s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                    (s >> 24) as u8
                })
                .collect();
            let mut got = flags.clone();
            rewrite(&mut got, rule);
            let want: std::vec::Vec<u8> =
                flags.iter().map(|&f| rule(u32::from(f), 1) as u8).collect();
            assert_eq!(got, want, "{flags:?}");
            let count = flags.iter().filter(|&&f| f & START != 0).count();
            assert_eq!(starts(&flags), count, "{flags:?}");
        }
    }

    /// `Seek::none_in` never skips a word with a hit: every word of four flags made of the
    /// five flag bits.
    #[test]
    fn seek_skips_only_words_without_hits() {
        for seek in [Seek::Mark, Seek::NotMark, Seek::Valid, Seek::SegmentEnd] {
            for w in 0u32..1 << 20 {
                let bytes = [0u32, 5, 10, 15].map(|s| ((w >> s) & 0x1f) as u8);
                let word = u32::from_le_bytes(bytes);
                if seek.none_in(word) {
                    assert!(!bytes.iter().any(|&f| seek.hit(f)), "{word:#010x}");
                }
            }
        }
    }

    /// On the flags a scan has (a segment start is a valid point), `Seek::none_in` is exact:
    /// it also skips every word without a hit, so the search reads a word's four flags one
    /// by one only where one of them is what it seeks.
    #[test]
    fn seek_skips_every_word_without_hits() {
        // The four low bits in every combination, less a start on an invalid point.
        let flags: std::vec::Vec<u8> = (0..16u8)
            .filter(|f| f & START == 0 || f & VALID != 0)
            .collect();
        for seek in [Seek::Mark, Seek::NotMark, Seek::Valid, Seek::SegmentEnd] {
            for w in 0..flags.len().pow(4) {
                let pick = |k: u32| flags[(w / flags.len().pow(k)) % flags.len()];
                let bytes = [pick(0), pick(1), pick(2), pick(3)];
                let word = u32::from_le_bytes(bytes);
                assert_eq!(
                    seek.none_in(word),
                    !bytes.iter().any(|&f| seek.hit(f)),
                    "{word:#010x}"
                );
            }
        }
    }
}
