//! The bag's bytes: opening, streaming its messages while counting what was read, and errors
//! located at a byte offset.

use std::cell::Cell;
use std::fs::File;
use std::io::{self, BufReader, Read};
use std::path::Path;
use std::rc::Rc;

use mcap::sans_io::LinearReaderOptions;

use super::MAX_RECORD;
use crate::{InputError, Location};

pub(super) fn open_file(path: &Path) -> Result<BufReader<File>, InputError> {
    File::open(path)
        .map(|f| BufReader::with_capacity(1 << 16, f))
        .map_err(|e| byte_error(0, format!("cannot open {}: {e}", path.display())))
}

pub(super) fn message_reader<R: Read>(
    input: R,
) -> (mcap::io::MessageReader<Counting<R>>, Rc<Cell<u64>>) {
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
pub(super) struct Counting<R> {
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

pub(super) fn byte_error(at: u64, message: impl Into<String>) -> InputError {
    InputError {
        location: Location::Byte(at),
        message: message.into(),
    }
}

pub(super) fn mcap_error(at: u64, e: mcap::McapError) -> InputError {
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
