//! Foxglove output: per scan, the scan as `foxglove.LaserScan` on [`SCAN_TOPIC`] and its features
//! as `foxglove.SceneUpdate` on [`FEATURES_TOPIC`], in an MCAP file that Foxglove opens and
//! scrubs through ([`FoxgloveWriter`]), or live over Foxglove's WebSocket protocol
//! ([`FoxgloveServer`]). `pfe listen`'s frames carry no ranges, so it writes and serves the
//! features only.
//!
//! Messages are JSON with hand-written JSON Schemas (Foxglove reads `json`/`jsonschema`
//! channels by the schema's name); lengths are in metres, as Foxglove expects. Each
//! SceneUpdate first deletes the previous scan's entities, then draws one entity per feature
//! (id `feature-K`, metadata `kind`, `first`, `last` and the parameters in pfe's units):
//! - a line: its segment (`lines[0]`, from `start` to `end`), and its ±1σ band (`lines[1]`, a
//!   closed loop offset across the line by σ(t)² = σ_ρ² + t²σ_α² − 2t·cov(α, ρ), t the position
//!   along the line from the foot of the normal);
//! - a circle: a flat cylinder (`cylinders[0]`, diameter 2r), its outline (`lines[0]`), the
//!   r ± σ_r rings (`lines[1]`, `lines[2]`) and the centre's 1σ ellipse (`lines[3]`);
//! - a text label (`texts[0]`).
//!
//! No-return beams are [`NO_RETURN_M`] (0 m) in the LaserScan's `ranges`: JSON has no NaN or
//! ±inf, `null` breaks the schema's `float64[]`, and `foxglove.LaserScan` carries no
//! `range_min`/`range_max` (Foxglove's 3D panel takes them as ±∞ for this schema and draws every
//! finite range), so no value hides a beam; 0 puts it at the sensor's origin, under its frame
//! axes, rather than on a phantom arc beyond the maximum range, and 0 is "no return" in LMS and
//! URG data alike.
//!
//! The file is written under a temporary name beside `path` and renamed at [`FoxgloveWriter::finish`],
//! so an interrupted run leaves no half-written file under the name asked for; an existing
//! file is replaced only by [`FoxgloveWriter::create_overwriting`].

mod mcap_file;
pub mod odometry;
mod scene;
mod schema;
mod ws;

pub use mcap_file::FoxgloveWriter;
pub use scene::{laser_scan, scene_update, NO_RETURN_M};
pub use schema::{Channel, FEATURES, SCAN};
pub use ws::FoxgloveServer;

/// Topic of the scans (`foxglove.LaserScan`).
pub const SCAN_TOPIC: &str = "/scan";
/// Topic of the features (`foxglove.SceneUpdate`).
pub const FEATURES_TOPIC: &str = "/features";
