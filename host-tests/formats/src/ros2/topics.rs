//! The topics of a bag and the choice of the LaserScan topic to read.

use std::collections::BTreeMap;
use std::fmt;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

use mcap::sans_io::summary_reader::{SummaryReadEvent, SummaryReader, SummaryReaderOptions};

use super::reader::{byte_error, mcap_error, message_reader, open_file};
use super::{InputError, LASER_SCAN, MAX_RECORD};

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
