//! ROS 2 bags: `sensor_msgs/msg/LaserScan` messages from an MCAP file (rosbag2's default
//! storage), CDR-decoded here.
//!
//! The container is read with the `mcap` crate, streaming (memory grows with the largest chunk,
//! not the file); zstd-compressed chunks (rosbag2's default) are read, lz4 ones are refused with
//! a clear error. Each message becomes a [`Ros2Scan`]: the header's stamp and frame, and a
//! [`Record`] (ranges in mm, geometry from `angle_min`/`angle_increment`/`range_max`). A range
//! outside `[range_min, range_max]`, NaN or ±inf is no return (`NaN` in the record): REP 117's
//! ±inf and drivers' out-of-range codes alike.
//!
//! A damaged bag (truncated, a bad CRC, a bad message) yields the scans read before the damage
//! and then one [`InputError`]; reading stops there.
//!
//! ```no_run
//! use host_tests::formats::ros2;
//! let scans = ros2::read_laser_scans(std::path::Path::new("bag.mcap"), None)?; // the only LaserScan topic
//! for scan in scans {
//!     let scan = scan?;
//!     println!("{} {} {} beams", scan.stamp_ns, scan.frame_id, scan.record.ranges_mm.len());
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::cell::Cell;
use std::collections::BTreeMap;
use std::fmt;
use std::fs::File;
use std::io::{self, BufReader, Read, Seek, SeekFrom};
use std::path::Path;
use std::rc::Rc;

use mcap::sans_io::summary_reader::{SummaryReadEvent, SummaryReader, SummaryReaderOptions};
use mcap::sans_io::LinearReaderOptions;
use pfe_core::ScanGeometry;

use super::{InputError, Location, Record};
use crate::methods::MAX_BEAMS;

/// Largest MCAP record (or chunk) read, bytes.
pub const MAX_RECORD: usize = 1 << 28;

/// Schema name of the messages read here.
pub const LASER_SCAN: &str = "sensor_msgs/msg/LaserScan";

/// One topic (MCAP channel) of a bag.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TopicInfo {
    /// Topic name, e.g. `/scan`.
    pub topic: String,
    /// Schema name, e.g. `sensor_msgs/msg/LaserScan` (empty when the channel has none).
    pub schema: String,
    /// Message encoding, e.g. `cdr`.
    pub encoding: String,
    /// Messages on the topic (from the bag's statistics, or counted).
    pub messages: u64,
}

impl TopicInfo {
    /// The topic of `channel`, with `messages` messages.
    fn of(channel: &mcap::Channel, messages: u64) -> Self {
        TopicInfo {
            topic: channel.topic.clone(),
            schema: channel
                .schema
                .as_ref()
                .map(|s| s.name.clone())
                .unwrap_or_default(),
            encoding: channel.message_encoding.clone(),
            messages,
        }
    }

    /// True for a CDR-encoded `sensor_msgs/msg/LaserScan` topic.
    pub fn is_laser_scan(&self) -> bool {
        self.schema == LASER_SCAN && self.encoding == "cdr"
    }
}

impl fmt::Display for TopicInfo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} [{}, {} messages]",
            self.topic, self.schema, self.messages
        )
    }
}

/// Why no LaserScan topic could be chosen (before any scan is read).
#[derive(Debug)]
#[non_exhaustive]
pub enum TopicError {
    /// The bag has no LaserScan topic; these are its topics.
    NoLaserScan {
        /// Every topic of the bag.
        topics: Vec<TopicInfo>,
    },
    /// Several LaserScan topics and none named.
    Ambiguous {
        /// The LaserScan topics.
        laser_topics: Vec<TopicInfo>,
    },
    /// The named topic is not a LaserScan topic of the bag.
    NotFound {
        /// The topic asked for.
        topic: String,
        /// Every topic of the bag.
        topics: Vec<TopicInfo>,
    },
    /// The bag cannot be read at all.
    Input(InputError),
}

impl From<InputError> for TopicError {
    fn from(e: InputError) -> Self {
        TopicError::Input(e)
    }
}

fn list(topics: &[TopicInfo]) -> String {
    if topics.is_empty() {
        return "none".into();
    }
    topics
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

impl fmt::Display for TopicError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TopicError::NoLaserScan { topics } => write!(
                f,
                "no {LASER_SCAN} topic in the bag (topics: {})",
                list(topics)
            ),
            TopicError::Ambiguous { laser_topics } => write!(
                f,
                "several {LASER_SCAN} topics, choose one with --topic: {}",
                list(laser_topics)
            ),
            TopicError::NotFound { topic, topics } => write!(
                f,
                "{topic} is not a {LASER_SCAN} topic of the bag (topics: {})",
                list(topics)
            ),
            TopicError::Input(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for TopicError {}

/// One scan of a bag.
#[derive(Clone, Debug, PartialEq)]
pub struct Ros2Scan {
    /// `header.stamp`, ns since the epoch.
    pub stamp_ns: u64,
    /// `header.frame_id`.
    pub frame_id: String,
    /// The scan; `id` is its 0-based ordinal on the topic.
    pub record: Record,
}

/// The topics of the bag at `path` (from its summary, or by reading it through).
pub fn topics(path: &Path) -> Result<Vec<TopicInfo>, InputError> {
    topics_in(open_file(path)?)
}

/// The LaserScan topics of the bag at `path`.
pub fn laser_topics(path: &Path) -> Result<Vec<TopicInfo>, InputError> {
    Ok(topics(path)?
        .into_iter()
        .filter(TopicInfo::is_laser_scan)
        .collect())
}

/// The topics of a bag, sorted by name: from the summary section when the bag has one,
/// otherwise by reading it through (a damaged bag: the topics seen before the damage; an error
/// only when nothing could be read).
pub fn topics_in<R: Read + Seek>(mut input: R) -> Result<Vec<TopicInfo>, InputError> {
    if let Some(summary) = read_summary(&mut input) {
        if !summary.channels.is_empty() {
            let counts = summary.stats.as_ref().map(|s| &s.channel_message_counts);
            let mut out: Vec<TopicInfo> = summary
                .channels
                .values()
                .map(|c| {
                    let messages = counts.and_then(|m| m.get(&c.id)).copied().unwrap_or(0);
                    TopicInfo::of(c, messages)
                })
                .collect();
            out.sort_by(|a, b| a.topic.cmp(&b.topic));
            return Ok(out);
        }
    }
    input
        .seek(SeekFrom::Start(0))
        .map_err(|e| byte_error(0, format!("cannot read: {e}")))?;
    let (reader, consumed) = message_reader(input);
    let mut seen: BTreeMap<String, TopicInfo> = BTreeMap::new();
    for m in reader {
        match m {
            Ok(m) => {
                let c = &m.channel;
                seen.entry(c.topic.clone())
                    .or_insert_with(|| TopicInfo::of(c, 0))
                    .messages += 1;
            }
            Err(e) if seen.is_empty() => return Err(mcap_error(consumed.get(), e)),
            Err(_) => break,
        }
    }
    Ok(seen.into_values().collect())
}

/// The bag's summary, if it has an intact one.
fn read_summary<R: Read + Seek>(input: &mut R) -> Option<mcap::Summary> {
    let mut reader = SummaryReader::new_with_options(
        SummaryReaderOptions::default().with_record_length_limit(MAX_RECORD),
    );
    while let Some(event) = reader.next_event() {
        match event.ok()? {
            SummaryReadEvent::ReadRequest(n) => {
                let got = input.read(reader.insert(n)).ok()?;
                reader.notify_read(got);
            }
            SummaryReadEvent::SeekRequest(to) => {
                let pos = input.seek(to).ok()?;
                reader.notify_seeked(pos);
            }
        }
    }
    reader.finish()
}

/// The topic to read: `wanted` if it is a LaserScan topic, else the only LaserScan topic.
pub fn choose_topic(topics: &[TopicInfo], wanted: Option<&str>) -> Result<String, TopicError> {
    let lasers: Vec<TopicInfo> = topics
        .iter()
        .filter(|t| t.is_laser_scan())
        .cloned()
        .collect();
    match wanted {
        Some(w) if lasers.iter().any(|t| t.topic == w) => Ok(w.to_string()),
        Some(w) => Err(TopicError::NotFound {
            topic: w.to_string(),
            topics: topics.to_vec(),
        }),
        None => match lasers.as_slice() {
            [one] => Ok(one.topic.clone()),
            [] => Err(TopicError::NoLaserScan {
                topics: topics.to_vec(),
            }),
            _ => Err(TopicError::Ambiguous {
                laser_topics: lasers,
            }),
        },
    }
}

/// The scans of `topic` (or of the only LaserScan topic) of the bag at `path`, streamed.
pub fn read_laser_scans(
    path: &Path,
    topic: Option<&str>,
) -> Result<LaserScans<BufReader<File>>, TopicError> {
    open_laser_scans(open_file(path)?, topic)
}

/// As [`read_laser_scans`], from any seekable input (e.g. `io::Cursor` over the bytes).
pub fn open_laser_scans<R: Read + Seek>(
    mut input: R,
    topic: Option<&str>,
) -> Result<LaserScans<R>, TopicError> {
    let topic = choose_topic(&topics_in(&mut input)?, topic)?;
    input
        .seek(SeekFrom::Start(0))
        .map_err(|e| byte_error(0, format!("cannot read: {e}")))?;
    Ok(LaserScans::new(input, &topic))
}

fn open_file(path: &Path) -> Result<BufReader<File>, InputError> {
    File::open(path)
        .map(|f| BufReader::with_capacity(1 << 16, f))
        .map_err(|e| byte_error(0, format!("cannot open {}: {e}", path.display())))
}

/// Streaming reader of the LaserScan messages of one topic; stops after the first error.
pub struct LaserScans<R: Read> {
    reader: mcap::io::MessageReader<Counting<R>>,
    consumed: Rc<Cell<u64>>,
    topic: String,
    count: u64,
    done: bool,
}

impl<R: Read> LaserScans<R> {
    /// Reads the messages of `topic` from `input` (positioned at the start of the bag); other
    /// topics are skipped, a non-LaserScan message on `topic` is an error.
    pub fn new(input: R, topic: &str) -> Self {
        let (reader, consumed) = message_reader(input);
        Self {
            reader,
            consumed,
            topic: topic.to_string(),
            count: 0,
            done: false,
        }
    }

    fn decode(&self, m: &mcap::Message<'_>) -> Result<Ros2Scan, InputError> {
        let here = self.consumed.get();
        let what = |msg: String| {
            byte_error(
                here,
                format!("message {} on {}: {msg}", self.count, self.topic),
            )
        };
        let schema = m.channel.schema.as_ref().map(|s| s.name.as_str());
        if schema != Some(LASER_SCAN) || m.channel.message_encoding != "cdr" {
            return Err(what(format!(
                "not a CDR {LASER_SCAN} (schema {schema:?}, encoding {:?})",
                m.channel.message_encoding
            )));
        }
        let msg = LaserScanMsg::decode(&m.data).map_err(|e| what(e.to_string()))?;
        let record = msg.record(self.count).map_err(what)?;
        Ok(Ros2Scan {
            stamp_ns: msg.stamp_ns().map_err(what)?,
            frame_id: msg.frame_id,
            record,
        })
    }
}

impl<R: Read> Iterator for LaserScans<R> {
    type Item = Result<Ros2Scan, InputError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        loop {
            let m = match self.reader.next()? {
                Ok(m) => m,
                Err(e) => {
                    self.done = true;
                    return Some(Err(mcap_error(self.consumed.get(), e)));
                }
            };
            if m.channel.topic != self.topic {
                continue;
            }
            let r = self.decode(&m);
            match r {
                Ok(_) => self.count += 1,
                Err(_) => self.done = true,
            }
            return Some(r);
        }
    }
}

fn message_reader<R: Read>(input: R) -> (mcap::io::MessageReader<Counting<R>>, Rc<Cell<u64>>) {
    let consumed = Rc::new(Cell::new(0));
    let counting = Counting {
        inner: input,
        consumed: Rc::clone(&consumed),
    };
    // A chunk's CRC is checked before any of its messages is used (damage inside a chunk loses
    // that chunk, never yields a wrong scan); a corrupted length cannot make it allocate more
    // than MAX_RECORD.
    let options = LinearReaderOptions::default()
        .with_prevalidate_chunk_crcs(true)
        .with_record_length_limit(MAX_RECORD);
    (
        mcap::io::MessageReader::new_with_options(counting, options),
        consumed,
    )
}

/// Counts the bytes read, for error locations.
struct Counting<R> {
    inner: R,
    consumed: Rc<Cell<u64>>,
}

impl<R: Read> Read for Counting<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.consumed.set(self.consumed.get() + n as u64);
        Ok(n)
    }
}

fn byte_error(at: u64, message: impl Into<String>) -> InputError {
    InputError {
        location: Location::Byte(at),
        message: message.into(),
    }
}

fn mcap_error(at: u64, e: mcap::McapError) -> InputError {
    let what = match e {
        mcap::McapError::UnexpectedEof => {
            "the bag ends in the middle of a record (truncated)".into()
        }
        mcap::McapError::BadMagic => "not an MCAP file (bad magic bytes)".into(),
        mcap::McapError::UnsupportedCompression(c) => {
            format!("chunks compressed with {c}, which this build does not read (zstd only)")
        }
        e => format!("damaged MCAP data: {e}"),
    };
    byte_error(at, what)
}

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
    /// use host_tests::formats::ros2::LaserScanMsg;
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
        let geometry = ScanGeometry {
            start_angle: self.angle_min,
            angle_step: self.angle_increment,
            r_max: self.range_max * 1000.0,
        };
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
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A LaserScan in CDR, `little` or big endian, frame `frame` (its length moves the
    /// alignment of every later field).
    fn encode(little: bool, frame: &str, ranges: &[f32], intensities: &[f32]) -> Vec<u8> {
        let w = |b: &mut Vec<u8>, v: u32| {
            while (b.len() - 4) % 4 != 0 {
                b.push(0xee); // padding: any value
            }
            b.extend(if little {
                v.to_le_bytes()
            } else {
                v.to_be_bytes()
            });
        };
        let mut b = vec![0, u8::from(little), 0, 0];
        w(&mut b, 1_700_000_000);
        w(&mut b, 250_000_000);
        w(&mut b, frame.len() as u32 + 1);
        b.extend(frame.as_bytes());
        b.push(0);
        for v in [-1.0f32, 1.0, 0.5, 0.001, 0.1, 0.05, 20.0] {
            w(&mut b, v.to_bits());
        }
        w(&mut b, ranges.len() as u32);
        for r in ranges {
            w(&mut b, r.to_bits());
        }
        w(&mut b, intensities.len() as u32);
        for r in intensities {
            w(&mut b, r.to_bits());
        }
        b
    }

    #[test]
    fn both_byte_orders_and_every_alignment() {
        let ranges = [
            1.0,
            f32::INFINITY,
            0.01,
            20.0,
            20.5,
            f32::NAN,
            -1.0,
            f32::NEG_INFINITY,
            0.05,
        ];
        for little in [true, false] {
            for frame in ["", "a", "ab", "abc", "laser"] {
                let m = LaserScanMsg::decode(&encode(little, frame, &ranges, &[7.0; 9])).unwrap();
                assert_eq!((m.sec, m.nanosec), (1_700_000_000, 250_000_000));
                assert_eq!(m.frame_id, frame);
                assert_eq!(
                    (m.angle_min, m.angle_max, m.angle_increment),
                    (-1.0, 1.0, 0.5)
                );
                assert_eq!((m.time_increment, m.scan_time), (0.001, 0.1));
                assert_eq!((m.range_min, m.range_max), (0.05, 20.0));
                assert_eq!(m.ranges.len(), 9);
                assert_eq!(m.intensities, [7.0; 9]);
                assert_eq!(m.stamp_ns(), Ok(1_700_000_000_250_000_000));
                let r = m.record(4).unwrap();
                assert_eq!(r.id, 4);
                assert_eq!(r.geometry.r_max, 20_000.0);
                assert_eq!((r.geometry.start_angle, r.geometry.angle_step), (-1.0, 0.5));
                // In range (inclusive) → mm; below range_min, above range_max, NaN, ±inf → NaN.
                let mm: Vec<Option<f32>> = r
                    .ranges_mm
                    .iter()
                    .map(|v| (!v.is_nan()).then_some(*v))
                    .collect();
                assert_eq!(
                    mm,
                    [
                        Some(1000.0),
                        None,
                        None,
                        Some(20_000.0),
                        None,
                        None,
                        None,
                        None,
                        Some(50.0)
                    ]
                );
            }
        }
    }

    #[test]
    fn truncation_anywhere_is_an_error_naming_the_field() {
        let b = encode(true, "laser", &[1.0, 2.0], &[]);
        assert!(LaserScanMsg::decode(&b).is_ok());
        for n in 0..b.len() {
            let e = LaserScanMsg::decode(&b[..n]).unwrap_err();
            assert!(matches!(e, CdrError::Truncated { .. }), "cut at {n}: {e}");
        }
    }

    #[test]
    fn lengths_beyond_the_data_are_refused_before_allocating() {
        let mut b = encode(true, "", &[1.0], &[]);
        // ranges count (after header 4 + stamp 8 + string 4+1 pad 3 + 7 floats 28 = offset 44).
        let at = 4 + 44;
        b[at..at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
        assert_eq!(
            LaserScanMsg::decode(&b),
            Err(CdrError::Truncated {
                field: "ranges",
                offset: 48
            })
        );
        let mut b = encode(false, "x", &[1.0], &[]);
        b[12..16].copy_from_slice(&0x7fff_ffffu32.to_be_bytes());
        assert!(matches!(
            LaserScanMsg::decode(&b),
            Err(CdrError::Truncated {
                field: "header.frame_id",
                ..
            })
        ));
    }

    #[test]
    fn other_encapsulations_and_bad_strings() {
        let mut b = encode(true, "x", &[1.0], &[]);
        b[1] = 3; // PL_CDR_LE
        assert_eq!(
            LaserScanMsg::decode(&b),
            Err(CdrError::Encapsulation([0, 3]))
        );
        let mut b = encode(true, "x", &[1.0], &[]);
        b[4 + 8 + 4 + 1] = b'y'; // the string's NUL
        assert_eq!(LaserScanMsg::decode(&b), Err(CdrError::BadString));
    }

    #[test]
    fn unusable_scans_are_errors() {
        let m = LaserScanMsg::decode(&encode(true, "", &[], &[])).unwrap();
        assert!(m.record(0).is_err());
        let mut m = LaserScanMsg::decode(&encode(true, "", &[1.0], &[])).unwrap();
        m.angle_increment = 0.0;
        assert!(m.record(0).unwrap_err().contains("unusable geometry"));
        m.angle_increment = 0.5;
        m.range_max = f32::INFINITY;
        assert!(m.record(0).is_err());
        m.range_max = 20.0;
        m.ranges = vec![1.0; MAX_BEAMS + 1];
        assert!(m.record(0).unwrap_err().contains("more than"));
        m.sec = -1;
        assert!(m.stamp_ns().is_err());
    }
}
