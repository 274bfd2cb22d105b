//! `pfe`: run the extractor on recorded scans (being written).
fn main() {}
