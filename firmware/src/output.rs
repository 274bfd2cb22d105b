//! Features on the wire: postcard + COBS frames with a checksum.
