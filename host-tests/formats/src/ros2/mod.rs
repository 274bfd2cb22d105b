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
//! use pfe_formats::ros2;
//! let scans = ros2::read_laser_scans(std::path::Path::new("bag.mcap"), None)?; // the only LaserScan topic
//! for scan in scans {
//!     let scan = scan?;
//!     println!("{} {} {} beams", scan.stamp_ns, scan.frame_id, scan.record.ranges_mm.len());
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod cdr;
mod reader;
mod topics;

pub use cdr::{CdrError, LaserScanMsg};
pub use topics::{choose_topic, laser_topics, topics, topics_in, TopicError, TopicInfo};

use std::cell::Cell;
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;
use std::rc::Rc;

use super::{InputError, Record};
use reader::{byte_error, mcap_error, message_reader, open_file, Counting};

/// Largest MCAP record (or chunk) read, bytes.
pub const MAX_RECORD: usize = 1 << 28;

/// Schema name of the messages read here.
pub const LASER_SCAN: &str = "sensor_msgs/msg/LaserScan";

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

#[cfg(test)]
mod tests;
