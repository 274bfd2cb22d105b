//! A ROS 2 bag read through [`scans`](super::scans) (stdin, or a format guess): the bag is
//! buffered in memory, since finding its LaserScan topic needs seeking. The CLI reads files by
//! path with [`ros2::read_laser_scans`], streaming.

use std::io::{BufRead, Cursor, Read};

use super::{ros2, InputError, Location, Scans};

/// The scans of the only LaserScan topic of the bag in `input`; input that does not start with
/// the MCAP magic bytes is refused before anything else is read.
pub fn records(mut input: Box<dyn BufRead>) -> Scans {
    let fail = |message: String| -> Scans {
        Box::new(std::iter::once(Err(InputError {
            location: Location::Byte(0),
            message,
        })))
    };
    match input.fill_buf() {
        Ok(head) if is_mcap(head) => {}
        Ok(_) => return fail("not an MCAP file (bad magic bytes)".into()),
        Err(e) => return fail(format!("cannot read: {e}")),
    }
    let mut bytes = Vec::new();
    if let Err(e) = input.read_to_end(&mut bytes) {
        return fail(format!("cannot read: {e}"));
    }
    match ros2::open_laser_scans(Cursor::new(bytes), None) {
        Ok(scans) => Box::new(scans.map(|s| s.map(|s| s.record))),
        Err(ros2::TopicError::Input(e)) => Box::new(std::iter::once(Err(e))),
        Err(e) => fail(e.to_string()),
    }
}

/// True when `head` starts with the MCAP magic bytes (`0x89 "MCAP0\r\n"`).
pub fn is_mcap(head: &[u8]) -> bool {
    head.starts_with(mcap::MAGIC)
}
