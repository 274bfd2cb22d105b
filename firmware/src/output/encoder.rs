//! The frame encoder: scan and report frames streamed to any [`embedded_io::Write`], the
//! features written by hand (byte for byte what postcard writes).

use pfe_core::Feature;

use super::cobs::CobsWriter;
use super::wire::{Header, Report, ScanHeader, MAX_FEATURE_LEN, WIRE_VERSION};

/// Bytes of features [`write_scan`] encodes at a time.
const FEATURE_CHUNK: usize = 6 * MAX_FEATURE_LEN;

/// Why a frame could not be written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum EncodeError<E> {
    /// The writer failed.
    Write(E),
    /// postcard could not serialise an item (cannot happen with the wire types).
    Serialize,
}

impl<E: core::fmt::Debug> core::fmt::Display for EncodeError<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            EncodeError::Write(e) => write!(f, "output write failed: {e:?}"),
            EncodeError::Serialize => f.write_str("serialisation failed"),
        }
    }
}

impl<E: core::fmt::Debug> core::error::Error for EncodeError<E> {}

/// The postcard bytes of `f` in `out` as postcard writes them, by hand (variant index and beam
/// indices as varints, then the `f32`s as 4 little-endian bytes each in declaration order,
/// points as `[x, y]`; see `docs/FRAME.md`). Returns their length.
fn feature_bytes(f: &Feature, out: &mut [u8]) -> usize {
    let mut w = Cursor { out, at: 0 };
    match f {
        Feature::Line(l) => {
            w.head(0, [l.first, l.last, l.points]);
            w.floats(l.values());
        }
        Feature::Circle(c) => {
            w.head(1, [c.first, c.last, c.points]);
            w.floats(c.values());
        }
    }
    w.at
}

/// Writes into a buffer (given at least [`MAX_FEATURE_LEN`] bytes, which every feature fits;
/// a write past its end is dropped, never a panic).
struct Cursor<'a> {
    out: &'a mut [u8],
    at: usize,
}

impl Cursor<'_> {
    /// The variant index and the beam indices (first, last, number of points).
    #[inline(always)]
    fn head(&mut self, tag: u16, beams: [u16; 3]) {
        let [first, last, points] = beams;
        self.varint(tag);
        self.varint(first);
        self.varint(last);
        self.varint(points);
    }

    /// LEB128, as postcard writes integers.
    fn varint(&mut self, mut v: u16) {
        while v >= 0x80 {
            self.byte(v as u8 | 0x80);
            v >>= 7;
        }
        self.byte(v as u8);
    }

    fn byte(&mut self, b: u8) {
        if let Some(slot) = self.out.get_mut(self.at) {
            *slot = b;
            self.at += 1;
        }
    }

    /// The values as 4 little-endian bytes each (one bounds check for all of them).
    fn floats<const K: usize>(&mut self, values: [f32; K]) {
        if let Some(out) = self.out.get_mut(self.at..self.at + 4 * K) {
            for (slot, v) in out.chunks_exact_mut(4).zip(values) {
                slot.copy_from_slice(&v.to_le_bytes());
            }
            self.at += 4 * K;
        }
    }
}

/// Writes one scan frame: `header` (its `n_features` is overwritten with `features.len()`)
/// then every feature.
pub fn write_scan<W: embedded_io::Write>(
    w: &mut W,
    header: &ScanHeader,
    features: &[Feature],
) -> Result<(), EncodeError<W::Error>> {
    let mut h = *header;
    h.n_features = u16::try_from(features.len()).unwrap_or(u16::MAX);
    let mut enc = CobsWriter::new(w);
    enc.put_item(&(WIRE_VERSION, Header::Scan(h)))?;
    // Features gathered into a chunk, encoded a chunk at a time (fewer calls, and fewer
    // bytes left over from the encoder's words).
    let mut chunk = [0u8; FEATURE_CHUNK];
    let mut len = 0usize;
    for f in features.iter().take(usize::from(h.n_features)) {
        if len + MAX_FEATURE_LEN > FEATURE_CHUNK {
            enc.put(chunk.get(..len).unwrap_or(&[]))
                .map_err(EncodeError::Write)?;
            len = 0;
        }
        len += chunk
            .get_mut(len..)
            .map_or(0, |rest| feature_bytes(f, rest));
    }
    enc.put(chunk.get(..len).unwrap_or(&[]))
        .map_err(EncodeError::Write)?;
    enc.finish().map_err(EncodeError::Write)
}

/// Writes one report frame.
pub fn write_report<W: embedded_io::Write>(
    w: &mut W,
    report: &Report,
) -> Result<(), EncodeError<W::Error>> {
    let mut enc = CobsWriter::new(w);
    enc.put_item(&(WIRE_VERSION, Header::Report(*report)))?;
    enc.finish().map_err(EncodeError::Write)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::indexing_slicing)]
    use super::*;
    use pfe_core::{CircleFeature, LineFeature, Point};
    use serde::Serialize;

    /// The feature layout of `docs/FRAME.md` as a serde type: what postcard writes for it is
    /// what `feature_bytes` must write.
    #[derive(Serialize)]
    enum Spec {
        Line(u16, u16, u16, [f32; 5], [f32; 2], [f32; 2]),
        Circle(u16, u16, u16, [f32; 2], f32, [[f32; 3]; 3], f32, f32),
    }

    impl From<&Feature> for Spec {
        fn from(f: &Feature) -> Self {
            match *f {
                Feature::Line(l) => Spec::Line(
                    l.first,
                    l.last,
                    l.points,
                    [l.alpha, l.rho, l.var_alpha, l.var_rho, l.cov_alpha_rho],
                    [l.start.x, l.start.y],
                    [l.end.x, l.end.y],
                ),
                Feature::Circle(c) => Spec::Circle(
                    c.first,
                    c.last,
                    c.points,
                    [c.center.x, c.center.y],
                    c.radius,
                    c.cov,
                    c.start_angle,
                    c.end_angle,
                ),
            }
        }
    }

    /// The hand-written feature bytes are postcard's, for lines and circles with fields of
    /// every bit pattern and beam indices at every varint length.
    #[test]
    fn feature_bytes_are_postcards() -> Result<(), postcard::Error> {
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        let edges = [0u16, 1, 127, 128, 300, 16383, 16384, 65535];
        for k in 0..20_000usize {
            let mut f32s = [0.0f32; 15];
            for v in &mut f32s {
                *v = f32::from_bits(next() as u32);
            }
            let [a, b, c, d, e, g, h, i, j, l, m, n, o, p, q] = f32s;
            let idx = |r: u64| edges[(r % 8) as usize].wrapping_add((r >> 8) as u16 % 3);
            let (first, last, points) = (idx(next()), idx(next()), idx(next()));
            let f = if k % 2 == 0 {
                Feature::Line(LineFeature {
                    first,
                    last,
                    points,
                    alpha: a,
                    rho: b,
                    var_alpha: c,
                    var_rho: d,
                    cov_alpha_rho: e,
                    start: Point::new(g, h),
                    end: Point::new(i, j),
                })
            } else {
                Feature::Circle(CircleFeature {
                    first,
                    last,
                    points,
                    center: Point::new(a, b),
                    radius: c,
                    cov: [[d, e, g], [h, i, j], [l, m, n]],
                    start_angle: o,
                    end_angle: p + q,
                })
            };
            let mut want = [0u8; MAX_FEATURE_LEN];
            let want = postcard::to_slice(&Spec::from(&f), &mut want)?;
            let mut got = [0u8; MAX_FEATURE_LEN];
            let n = feature_bytes(&f, &mut got);
            assert_eq!(&got[..n], &want[..], "{f:?}");
        }
        Ok(())
    }
}
