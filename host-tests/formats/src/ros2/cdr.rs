//! `sensor_msgs/msg/LaserScan` decoded from CDR.

use std::fmt;

use pfe_core::ScanGeometry;

use crate::Record;
use crate::MAX_BEAMS;

/// A decoded `sensor_msgs/msg/LaserScan`.
#[derive(Clone, Debug, PartialEq)]
pub struct LaserScanMsg {
    /// `header.stamp.sec`.
    pub sec: i32,
    /// `header.stamp.nanosec`.
    pub nanosec: u32,
    /// `header.frame_id`.
    pub frame_id: String,
    /// Bearing of the first beam, rad.
    pub angle_min: f32,
    /// Bearing of the last beam, rad.
    pub angle_max: f32,
    /// Angle between beams, rad.
    pub angle_increment: f32,
    /// Time between beams, s.
    pub time_increment: f32,
    /// Time between scans, s.
    pub scan_time: f32,
    /// Shortest valid range, m.
    pub range_min: f32,
    /// Longest valid range, m.
    pub range_max: f32,
    /// Ranges, m.
    pub ranges: Vec<f32>,
    /// Intensities (device units; empty or one per beam).
    pub intensities: Vec<f32>,
}

/// A CDR payload that is not a LaserScan.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum CdrError {
    /// Fewer bytes than the field at `offset` needs.
    Truncated {
        /// The field.
        field: &'static str,
        /// Offset of the field in the payload (after the 4-byte encapsulation header).
        offset: usize,
    },
    /// An encapsulation other than plain CDR (big or little endian).
    Encapsulation([u8; 2]),
    /// `frame_id` is not NUL-terminated UTF-8.
    BadString,
}

impl fmt::Display for CdrError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CdrError::Truncated { field, offset } => {
                write!(f, "CDR data ends in {field} (offset {offset})")
            }
            CdrError::Encapsulation(k) => write!(
                f,
                "unsupported CDR encapsulation {:02x}{:02x} (plain CDR only)",
                k[0], k[1]
            ),
            CdrError::BadString => f.write_str("frame_id is not a NUL-terminated UTF-8 string"),
        }
    }
}

impl std::error::Error for CdrError {}

/// CDR reader: alignment relative to the end of the encapsulation header.
struct Cdr<'a> {
    data: &'a [u8],
    pos: usize,
    little: bool,
}

impl<'a> Cdr<'a> {
    fn take(&mut self, field: &'static str, n: usize, align: usize) -> Result<&'a [u8], CdrError> {
        let start = self.pos.next_multiple_of(align);
        let err = CdrError::Truncated {
            field,
            offset: start,
        };
        let end = start.checked_add(n).ok_or(err.clone())?;
        let bytes = self.data.get(start..end).ok_or(err)?;
        self.pos = end;
        Ok(bytes)
    }

    fn u32(&mut self, field: &'static str) -> Result<u32, CdrError> {
        let b: [u8; 4] = self
            .take(field, 4, 4)?
            .try_into()
            .map_err(|_| CdrError::Truncated {
                field,
                offset: self.pos,
            })?;
        Ok(if self.little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    }

    fn f32(&mut self, field: &'static str) -> Result<f32, CdrError> {
        self.u32(field).map(f32::from_bits)
    }

    fn f32_seq(&mut self, field: &'static str) -> Result<Vec<f32>, CdrError> {
        let n = self.u32(field)? as usize;
        // The length is checked against the bytes present before anything is allocated.
        let bytes = self.take(field, n.saturating_mul(4), 4)?;
        Ok(bytes
            .chunks_exact(4)
            .map(|c| {
                let b = [c[0], c[1], c[2], c[3]];
                f32::from_bits(if self.little {
                    u32::from_le_bytes(b)
                } else {
                    u32::from_be_bytes(b)
                })
            })
            .collect())
    }

    fn string(&mut self, field: &'static str) -> Result<String, CdrError> {
        let n = self.u32(field)? as usize;
        let bytes = self.take(field, n, 1)?;
        match bytes.split_last() {
            Some((0, text)) => std::str::from_utf8(text)
                .map(str::to_string)
                .map_err(|_| CdrError::BadString),
            // An empty string is sometimes written with length 0.
            None => Ok(String::new()),
            Some(_) => Err(CdrError::BadString),
        }
    }
}

impl LaserScanMsg {
    /// Decodes a CDR payload (4-byte encapsulation header, then the message), either byte order.
    ///
    /// ```
    /// use pfe_formats::ros2::LaserScanMsg;
    /// let mut b = vec![0, 1, 0, 0];                       // CDR, little endian
    /// b.extend(7i32.to_le_bytes());                       // stamp.sec
    /// b.extend(5u32.to_le_bytes());                       // stamp.nanosec
    /// b.extend(2u32.to_le_bytes()); b.extend(b"l\0\0\0"); // frame_id "l" + padding
    /// for v in [-1.5f32, 1.5, 1.5, 0.0, 0.1, 0.01, 50.0] { b.extend(v.to_le_bytes()); }
    /// b.extend(3u32.to_le_bytes());
    /// for r in [1.0f32, 2.0, 3.0] { b.extend(r.to_le_bytes()); }
    /// b.extend(0u32.to_le_bytes());                       // no intensities
    /// let m = LaserScanMsg::decode(&b).unwrap();
    /// assert_eq!((m.sec, m.frame_id.as_str(), m.ranges.len()), (7, "l", 3));
    /// ```
    pub fn decode(payload: &[u8]) -> Result<Self, CdrError> {
        let (head, data) = payload
            .split_first_chunk::<4>()
            .ok_or(CdrError::Truncated {
                field: "encapsulation header",
                offset: 0,
            })?;
        let little = match [head[0], head[1]] {
            [0, 0] => false,
            [0, 1] => true,
            k => return Err(CdrError::Encapsulation(k)),
        };
        let mut c = Cdr {
            data,
            pos: 0,
            little,
        };
        Ok(Self {
            sec: c.u32("header.stamp.sec")? as i32,
            nanosec: c.u32("header.stamp.nanosec")?,
            frame_id: c.string("header.frame_id")?,
            angle_min: c.f32("angle_min")?,
            angle_max: c.f32("angle_max")?,
            angle_increment: c.f32("angle_increment")?,
            time_increment: c.f32("time_increment")?,
            scan_time: c.f32("scan_time")?,
            range_min: c.f32("range_min")?,
            range_max: c.f32("range_max")?,
            ranges: c.f32_seq("ranges")?,
            intensities: c.f32_seq("intensities")?,
        })
    }

    /// `header.stamp` in ns since the epoch (an error before 1970).
    pub fn stamp_ns(&self) -> Result<u64, String> {
        let ns = i64::from(self.sec) * 1_000_000_000 + i64::from(self.nanosec);
        u64::try_from(ns).map_err(|_| format!("stamp before 1970 ({} s)", self.sec))
    }

    /// The scan as a [`Record`] with ID `id`: ranges in mm, `NaN` outside
    /// `[range_min, range_max]` and for NaN/±inf; `r_max` = `range_max` in mm.
    pub fn record(&self, id: u64) -> Result<Record, String> {
        let n = self.ranges.len();
        if n == 0 {
            return Err("no ranges".into());
        }
        if n > MAX_BEAMS {
            return Err(format!(
                "{n} ranges, more than the {MAX_BEAMS} the extractor holds"
            ));
        }
        let geometry = ScanGeometry::new(
            self.angle_min,
            self.angle_increment,
            self.range_max * 1000.0,
        );
        if !(geometry.is_valid() && self.range_min.is_finite() && self.range_min >= 0.0) {
            return Err(format!(
                "unusable geometry (angle_min {} rad, angle_increment {} rad, range {}..{} m)",
                self.angle_min, self.angle_increment, self.range_min, self.range_max
            ));
        }
        let (lo, hi) = (self.range_min, self.range_max);
        let ranges_mm = self
            .ranges
            .iter()
            .map(|&r| {
                if r.is_finite() && r >= lo && r <= hi {
                    r * 1000.0
                } else {
                    f32::NAN
                }
            })
            .collect();
        Ok(Record {
            id,
            geometry,
            ranges_mm,
            time: Some(f64::from(self.sec) + f64::from(self.nanosec) * 1e-9),
            pose: None,
            sweeps: None,
        })
    }
}
