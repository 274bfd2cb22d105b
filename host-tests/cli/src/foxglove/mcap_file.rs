//! [`FoxgloveWriter`]: scans and features into an MCAP file.

use std::collections::BTreeMap;
use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter};
use std::path::{Path, PathBuf};

use pfe_core::Feature;

use super::scene::{laser_scan, scene_update};
use super::schema::{Channel, FEATURES, MESSAGE_ENCODING, SCAN, SCHEMA_ENCODING};
use pfe_formats::Record;

/// Writes scans and features to a Foxglove MCAP file.
pub struct FoxgloveWriter {
    writer: Option<mcap::Writer<BufWriter<File>>>,
    temp: PathBuf,
    path: PathBuf,
    overwrite: bool,
    scan_channel: Option<u16>,
    scene_channel: u16,
    sequence: u32,
}

fn other(e: mcap::McapError) -> io::Error {
    match e {
        mcap::McapError::Io(e) => e,
        e => io::Error::other(e),
    }
}

impl FoxgloveWriter {
    /// Starts `path`; fails with `AlreadyExists` if it exists (checked again at `finish`).
    pub fn create(path: &Path) -> io::Result<Self> {
        Self::start(path, false, true)
    }

    /// Starts `path`, replacing it at `finish` if it exists.
    pub fn create_overwriting(path: &Path) -> io::Result<Self> {
        Self::start(path, true, true)
    }

    /// Starts `path` with the features channel only (for [`Self::write_features`]: `pfe
    /// listen`'s frames carry no ranges); an existing file is replaced only if `overwrite`.
    pub fn create_features_only(path: &Path, overwrite: bool) -> io::Result<Self> {
        Self::start(path, overwrite, false)
    }

    fn start(path: &Path, overwrite: bool, scans: bool) -> io::Result<Self> {
        if !overwrite && path.exists() {
            return Err(io::Error::new(
                io::ErrorKind::AlreadyExists,
                format!("{} exists (not overwritten)", path.display()),
            ));
        }
        let name = path
            .file_name()
            .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "no file name"))?;
        let mut temp_name = std::ffi::OsString::from(".");
        temp_name.push(name);
        temp_name.push(format!(".{}.partial", std::process::id()));
        let temp = path.with_file_name(temp_name);
        let file = OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&temp)?;
        let mut this = Self {
            writer: None,
            temp,
            path: path.to_path_buf(),
            overwrite,
            scan_channel: None,
            scene_channel: 0,
            sequence: 0,
        };
        let mut w = mcap::WriteOptions::new()
            .profile("")
            .create(BufWriter::new(file))
            .map_err(other)?;
        let mut add = |c: &Channel| -> io::Result<u16> {
            let schema = w
                .add_schema(c.schema_name, SCHEMA_ENCODING, &c.schema())
                .map_err(other)?;
            w.add_channel(schema, c.topic, MESSAGE_ENCODING, &BTreeMap::new())
                .map_err(other)
        };
        if scans {
            this.scan_channel = Some(add(&SCAN)?);
        }
        this.scene_channel = add(&FEATURES)?;
        this.writer = Some(w);
        Ok(this)
    }

    /// Writes one scan (stamped `stamp_ns`, ns since the epoch, in frame `frame_id`) and its
    /// features; fails on a writer made by [`Self::create_features_only`].
    pub fn write_scan(
        &mut self,
        stamp_ns: u64,
        frame_id: &str,
        record: &Record,
        features: &[Feature],
    ) -> io::Result<()> {
        let scan_channel = self
            .scan_channel
            .ok_or_else(|| io::Error::other("this file has no scan channel"))?;
        let scan = serde_json::to_vec(&laser_scan(stamp_ns, frame_id, record))?;
        let scene = serde_json::to_vec(&scene_update(stamp_ns, frame_id, features))?;
        let sequence = self.next_sequence();
        self.write(scan_channel, sequence, stamp_ns, stamp_ns, &scan)?;
        self.write(self.scene_channel, sequence, stamp_ns, stamp_ns, &scene)
    }

    /// Writes the features of one scan stamped `stamp_ns` (the message's timestamp and the
    /// record's publish time), received at `log_time_ns` (its log time), both ns since the
    /// epoch.
    pub fn write_features(
        &mut self,
        log_time_ns: u64,
        stamp_ns: u64,
        frame_id: &str,
        features: &[Feature],
    ) -> io::Result<()> {
        let scene = serde_json::to_vec(&scene_update(stamp_ns, frame_id, features))?;
        let sequence = self.next_sequence();
        self.write(self.scene_channel, sequence, log_time_ns, stamp_ns, &scene)
    }

    /// Adds channel `c` (e.g. [`super::odometry::POSE`]); returns its id for
    /// [`Self::write_message`].
    pub fn add_channel(&mut self, c: &Channel) -> io::Result<u16> {
        let w = self.writer_mut()?;
        let schema = w
            .add_schema(c.schema_name, SCHEMA_ENCODING, &c.schema())
            .map_err(other)?;
        w.add_channel(schema, c.topic, MESSAGE_ENCODING, &BTreeMap::new())
            .map_err(other)
    }

    /// Writes `message` on a channel of [`Self::add_channel`], stamped `stamp_ns` (log and
    /// publish time), with the sequence number of the last scan written (it belongs to it).
    pub fn write_message(
        &mut self,
        channel: u16,
        stamp_ns: u64,
        message: &serde_json::Value,
    ) -> io::Result<()> {
        let data = serde_json::to_vec(message)?;
        let sequence = self.sequence.wrapping_sub(1);
        self.write(channel, sequence, stamp_ns, stamp_ns, &data)
    }

    fn next_sequence(&mut self) -> u32 {
        let s = self.sequence;
        self.sequence = s.wrapping_add(1);
        s
    }

    fn write(
        &mut self,
        channel_id: u16,
        sequence: u32,
        log_time: u64,
        publish_time: u64,
        data: &[u8],
    ) -> io::Result<()> {
        self.writer_mut()?
            .write_to_known_channel(
                &mcap::records::MessageHeader {
                    channel_id,
                    sequence,
                    log_time,
                    publish_time,
                },
                data,
            )
            .map_err(other)
    }

    fn writer_mut(&mut self) -> io::Result<&mut mcap::Writer<BufWriter<File>>> {
        self.writer
            .as_mut()
            .ok_or_else(|| io::Error::other("writer already finished"))
    }

    /// Completes the file (summary, footer) and moves it to its name; returns the path.
    pub fn finish(mut self) -> io::Result<PathBuf> {
        let mut w = self
            .writer
            .take()
            .ok_or_else(|| io::Error::other("writer already finished"))?;
        w.finish().map_err(other)?;
        let file = w
            .into_inner()
            .into_inner()
            .map_err(io::IntoInnerError::into_error)?;
        file.sync_all()?;
        drop(file);
        if self.overwrite {
            fs::rename(&self.temp, &self.path)?;
        } else {
            // A hard link fails if the name exists (atomically); where links are unsupported,
            // fall back to a checked rename.
            match fs::hard_link(&self.temp, &self.path) {
                Ok(()) => fs::remove_file(&self.temp)?,
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists => {
                    return Err(io::Error::new(
                        io::ErrorKind::AlreadyExists,
                        format!(
                            "{} appeared while writing (not overwritten)",
                            self.path.display()
                        ),
                    ))
                }
                Err(_) if !self.path.exists() => fs::rename(&self.temp, &self.path)?,
                Err(e) => return Err(e),
            }
        }
        Ok(self.path.clone())
    }
}

impl Drop for FoxgloveWriter {
    fn drop(&mut self) {
        // Unfinished (error, early return) or finished but not moved: no partial file left.
        self.writer = None;
        let _ = fs::remove_file(&self.temp);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pfe_core::ScanGeometry;

    fn scratch(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("pfe-fox-{tag}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        d
    }

    fn record() -> Record {
        Record {
            id: 0,
            geometry: ScanGeometry::LMS200_180_050,
            ranges_mm: vec![1000.0; 361],
            time: None,
            pose: None,
            sweeps: None,
        }
    }

    #[test]
    fn never_replaces_an_existing_file_unless_asked() {
        let d = scratch("exists");
        let path = d.join("out.mcap");
        fs::write(&path, b"mine").unwrap();
        assert_eq!(
            FoxgloveWriter::create(&path).err().map(|e| e.kind()),
            Some(io::ErrorKind::AlreadyExists)
        );
        assert_eq!(fs::read(&path).unwrap(), b"mine");
        // Appearing while writing: still not replaced, and no temporary file left.
        let other = d.join("late.mcap");
        let mut w = FoxgloveWriter::create(&other).unwrap();
        w.write_scan(1, "laser", &record(), &[]).unwrap();
        fs::write(&other, b"late").unwrap();
        assert!(w.finish().is_err());
        assert_eq!(fs::read(&other).unwrap(), b"late");
        let mut w = FoxgloveWriter::create_overwriting(&path).unwrap();
        w.write_scan(1, "laser", &record(), &[]).unwrap();
        w.finish().unwrap();
        assert!(fs::read(&path).unwrap().starts_with(mcap::MAGIC));
        // Dropped unfinished: nothing under the name, no temporary file.
        let dropped = d.join("dropped.mcap");
        drop(FoxgloveWriter::create(&dropped).unwrap());
        assert!(!dropped.exists());
        let mut left: Vec<_> = fs::read_dir(&d)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        left.sort();
        assert_eq!(left, ["late.mcap", "out.mcap"]);
        fs::remove_dir_all(&d).unwrap();
    }
}
