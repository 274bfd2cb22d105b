//! The frame encoder: scan and report frames streamed to any [`embedded_io::Write`], the
//! features written by hand (byte for byte what postcard writes).

use pfe_core::Feature;

use super::cobs::CobsWriter;
use super::wire::{
    Header, PoseBlock, Report, ScanHeader, ScanStatus, MAX_FEATURE_LEN, MAX_POSE_LEN, WIRE_VERSION,
};

/// Bytes of features [`write_scan`] encodes at a time (the pose block fits one).
const FEATURE_CHUNK: usize = 3 * MAX_FEATURE_LEN;
const _: () = assert!(MAX_POSE_LEN <= FEATURE_CHUNK);

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
        Feature::Object(o) => {
            w.head(2, [o.first, o.last, o.points]);
            w.floats(o.values());
        }
        // A kind this version of the frame does not know: a zero-point line that the decoder
        // refuses, never silently another feature (pfe-core adds kinds only with a new
        // frame version).
        _ => w.head(u16::MAX, [0, 0, 0]),
    }
    w.at
}

/// The version byte and `postcard(Header::Scan(h))` in `out`, by hand (every integer a varint
/// in declaration order, the enums as their variant index). Returns their length.
fn scan_header_bytes(h: &ScanHeader, out: &mut [u8]) -> usize {
    let mut w = Cursor { out, at: 0 };
    w.byte(WIRE_VERSION);
    w.varint(0);
    let c = &h.counters;
    for v in [
        h.seq,
        h.time_ms,
        c.telegrams_ok,
        c.crc_dropped,
        c.bytes_skipped,
        c.reinits,
    ] {
        w.varint(v);
    }
    for v in [h.valid, h.segments, h.dropped, h.n_features] {
        w.varint(u32::from(v));
    }
    w.varint(match h.status {
        ScanStatus::Ok => 0,
        ScanStatus::FeatureCapacity => 1,
        ScanStatus::TooManyReadings => 2,
        ScanStatus::InvalidInput => 3,
    });
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
        self.varint(u32::from(tag));
        self.varint(u32::from(first));
        self.varint(u32::from(last));
        self.varint(u32::from(points));
    }

    /// LEB128, as postcard writes integers.
    fn varint(&mut self, mut v: u32) {
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

/// Writes one scan frame: `header` (its `n_features` is overwritten with `features.len()`),
/// every feature, and no pose block (`None`; see [`write_scan_with_pose`]).
pub fn write_scan<W: embedded_io::Write>(
    w: &mut W,
    header: &ScanHeader,
    features: &[Feature],
) -> Result<(), EncodeError<W::Error>> {
    write_scan_with_pose(w, header, features, None)
}

/// Writes one scan frame: `header` (its `n_features` is overwritten with `features.len()`),
/// every feature, then the pose block `pose` (the firmware's odometry for this scan).
///
/// ```
/// use pfe_frame::{write_scan_with_pose, Feed, FrameDecoder, PoseBlock, PoseCov, PoseStatus, ScanHeader};
/// let pose = PoseBlock {
///     rel: PoseCov { x: 120.0, y: -3.5, theta: 0.02, cov: [[25.0, 0.0, 0.0], [0.0, 25.0, 0.0], [0.0, 0.0, 1e-5]] },
///     pose: PoseCov { x: 480.0, y: 10.0, theta: 0.1, cov: [[90.0, 1.0, 0.0], [1.0, 80.0, 0.0], [0.0, 0.0, 4e-5]] },
///     status: PoseStatus::Ok,
/// };
/// let mut buf = [0u8; 512];
/// let mut w = &mut buf[..];
/// write_scan_with_pose(&mut w, &ScanHeader::default(), &[], Some(&pose))?;
/// let n = 512 - w.len();
/// let Feed::Frame { frame, .. } = FrameDecoder::<1024>::new().feed(&buf[..n]) else {
///     return Err("no frame".into());
/// };
/// assert_eq!(frame.pose, Some(pose));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_scan_with_pose<W: embedded_io::Write>(
    w: &mut W,
    header: &ScanHeader,
    features: &[Feature],
    pose: Option<&PoseBlock>,
) -> Result<(), EncodeError<W::Error>> {
    let mut h = *header;
    h.n_features = u16::try_from(features.len()).unwrap_or(u16::MAX);
    let mut enc = CobsWriter::new(w);
    // The header and the features gathered into a chunk, encoded a chunk at a time (fewer
    // calls, and fewer bytes left over from the encoder's words).
    let mut chunk = [0u8; FEATURE_CHUNK];
    let mut len = scan_header_bytes(&h, &mut chunk);
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
    // The pose block: postcard's `Option<PoseBlock>`.
    if len + MAX_POSE_LEN > FEATURE_CHUNK {
        enc.put(chunk.get(..len).unwrap_or(&[]))
            .map_err(EncodeError::Write)?;
        len = 0;
    }
    let rest = chunk.get_mut(len..).unwrap_or(&mut []);
    len += postcard::to_slice(&pose, rest)
        .map_err(|_| EncodeError::Serialize)?
        .len();
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
        Object(u16, u16, u16, [f32; 2], [[f32; 2]; 2], f32),
        Unknown,
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
                Feature::Object(o) => Spec::Object(
                    o.first,
                    o.last,
                    o.points,
                    [o.center.x, o.center.y],
                    o.cov,
                    o.extent,
                ),
                _ => Spec::Unknown,
            }
        }
    }

    /// The hand-written scan header is postcard's `(WIRE_VERSION, Header::Scan(h))`, for
    /// integers at every varint length and every status.
    #[test]
    fn scan_header_bytes_are_postcards() -> Result<(), postcard::Error> {
        use crate::Counters;
        let edges = [
            0u32,
            1,
            127,
            128,
            16383,
            16384,
            2_097_151,
            2_097_152,
            u32::MAX,
        ];
        let statuses = [
            ScanStatus::Ok,
            ScanStatus::FeatureCapacity,
            ScanStatus::TooManyReadings,
            ScanStatus::InvalidInput,
        ];
        for k in 0..2000usize {
            let e = |i: usize| edges[(k * 7 + i * 5 + k / 9 * i) % edges.len()];
            let s = |i: usize| e(i) as u16;
            let h = ScanHeader {
                seq: e(0),
                time_ms: e(1),
                counters: Counters {
                    telegrams_ok: e(2),
                    crc_dropped: e(3),
                    bytes_skipped: e(4),
                    reinits: e(5),
                },
                valid: s(6),
                segments: s(7),
                dropped: s(8),
                n_features: s(9),
                status: statuses[k % 4],
            };
            let mut want = [0u8; 96];
            let want = postcard::to_slice(&(WIRE_VERSION, Header::Scan(h)), &mut want)?;
            let mut got = [0u8; 96];
            let n = scan_header_bytes(&h, &mut got);
            assert_eq!(&got[..n], &want[..], "{h:?}");
        }
        Ok(())
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
                Feature::Line(LineFeature::new(
                    first,
                    last,
                    points,
                    a,
                    b,
                    c,
                    d,
                    e,
                    Point::new(g, h),
                    Point::new(i, j),
                ))
            } else {
                Feature::Circle(CircleFeature::new(
                    first,
                    last,
                    points,
                    Point::new(a, b),
                    c,
                    [[d, e, g], [h, i, j], [l, m, n]],
                    o,
                    p + q,
                ))
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
