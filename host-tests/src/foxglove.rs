//! Foxglove output: per scan, the scan as `foxglove.LaserScan` on [`SCAN_TOPIC`] and its features
//! as `foxglove.SceneUpdate` on [`FEATURES_TOPIC`], in an MCAP file that Foxglove opens and
//! scrubs through.
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

use std::collections::BTreeMap;
use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter};
use std::path::{Path, PathBuf};

use pfe_core::{CircleFeature, Feature, LineFeature};
use serde_json::{json, Value};

use crate::formats::Record;

/// Topic of the scans (`foxglove.LaserScan`).
pub const SCAN_TOPIC: &str = "/scan";
/// Topic of the features (`foxglove.SceneUpdate`).
pub const FEATURES_TOPIC: &str = "/features";

const MM: f64 = 1e-3;

/// Writes scans and features to a Foxglove MCAP file.
pub struct FoxgloveWriter {
    writer: Option<mcap::Writer<BufWriter<File>>>,
    temp: PathBuf,
    path: PathBuf,
    overwrite: bool,
    scan_channel: u16,
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
        if path.exists() {
            return Err(io::Error::new(
                io::ErrorKind::AlreadyExists,
                format!("{} exists (not overwritten)", path.display()),
            ));
        }
        Self::start(path, false)
    }

    /// Starts `path`, replacing it at `finish` if it exists.
    pub fn create_overwriting(path: &Path) -> io::Result<Self> {
        Self::start(path, true)
    }

    fn start(path: &Path, overwrite: bool) -> io::Result<Self> {
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
            scan_channel: 0,
            scene_channel: 0,
            sequence: 0,
        };
        let mut w = mcap::WriteOptions::new()
            .profile("")
            .create(BufWriter::new(file))
            .map_err(other)?;
        let no_metadata = BTreeMap::new();
        let scan_schema = w
            .add_schema("foxglove.LaserScan", "jsonschema", &laser_scan_schema())
            .map_err(other)?;
        this.scan_channel = w
            .add_channel(scan_schema, SCAN_TOPIC, "json", &no_metadata)
            .map_err(other)?;
        let scene_schema = w
            .add_schema("foxglove.SceneUpdate", "jsonschema", &scene_update_schema())
            .map_err(other)?;
        this.scene_channel = w
            .add_channel(scene_schema, FEATURES_TOPIC, "json", &no_metadata)
            .map_err(other)?;
        this.writer = Some(w);
        Ok(this)
    }

    /// Writes one scan (stamped `stamp_ns`, ns since the epoch, in frame `frame_id`) and its
    /// features.
    pub fn write_scan(
        &mut self,
        stamp_ns: u64,
        frame_id: &str,
        record: &Record,
        features: &[Feature],
    ) -> io::Result<()> {
        let scan = laser_scan(stamp_ns, frame_id, record);
        let scene = scene_update(stamp_ns, frame_id, features);
        let sequence = self.sequence;
        self.sequence = self.sequence.wrapping_add(1);
        for (channel, value) in [(self.scan_channel, scan), (self.scene_channel, scene)] {
            let data = serde_json::to_vec(&value)?;
            self.writer_mut()?
                .write_to_known_channel(
                    &mcap::records::MessageHeader {
                        channel_id: channel,
                        sequence,
                        log_time: stamp_ns,
                        publish_time: stamp_ns,
                    },
                    &data,
                )
                .map_err(other)?;
        }
        Ok(())
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

fn time(stamp_ns: u64) -> Value {
    json!({ "sec": stamp_ns / 1_000_000_000, "nsec": stamp_ns % 1_000_000_000 })
}

fn point(x: f64, y: f64) -> Value {
    json!({ "x": x, "y": y, "z": 0.0 })
}

fn identity_pose() -> Value {
    pose(0.0, 0.0)
}

fn pose(x: f64, y: f64) -> Value {
    json!({ "position": point(x, y), "orientation": { "x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0 } })
}

fn color(r: f64, g: f64, b: f64, a: f64) -> Value {
    json!({ "r": r, "g": g, "b": b, "a": a })
}

/// Range written for a beam with no return, m (see the module's documentation).
pub const NO_RETURN_M: f64 = 0.0;

/// A `foxglove.LaserScan` (ranges in m, [`NO_RETURN_M`] = no return).
pub fn laser_scan(stamp_ns: u64, frame_id: &str, record: &Record) -> Value {
    let g = &record.geometry;
    let n = record.ranges_mm.len();
    let ranges: Vec<f64> = (0..n)
        .map(|i| match (record.point(i), record.ranges_mm.get(i)) {
            (Some(_), Some(&r)) => f64::from(r) * MM,
            _ => NO_RETURN_M,
        })
        .collect();
    json!({
        "timestamp": time(stamp_ns),
        "frame_id": frame_id,
        "pose": identity_pose(),
        "start_angle": g.start_angle,
        "end_angle": g.bearing(n.saturating_sub(1)),
        "ranges": ranges,
        "intensities": [],
    })
}

/// A `foxglove.SceneUpdate`: delete the previous entities, one entity per feature.
pub fn scene_update(stamp_ns: u64, frame_id: &str, features: &[Feature]) -> Value {
    let entities: Vec<Value> = features
        .iter()
        .enumerate()
        .map(|(k, f)| match f {
            Feature::Line(l) => line_entity(stamp_ns, frame_id, k, l),
            Feature::Circle(c) => circle_entity(stamp_ns, frame_id, k, c),
        })
        .collect();
    json!({
        "deletions": [{ "timestamp": time(stamp_ns), "type": 1, "id": "" }],
        "entities": entities,
    })
}

fn line_primitive(kind: u8, points: Vec<Value>, thickness: f64, c: Value) -> Value {
    json!({
        "type": kind,
        "pose": identity_pose(),
        "thickness": thickness,
        "scale_invariant": false,
        "points": points,
        "color": c,
        "colors": [],
        "indices": [],
    })
}

const LINE_STRIP: u8 = 0;
const LINE_LOOP: u8 = 1;

fn entity(stamp_ns: u64, frame_id: &str, k: usize, metadata: &[(&str, String)]) -> Value {
    let metadata: Vec<Value> = metadata
        .iter()
        .map(|(key, value)| json!({ "key": key, "value": value }))
        .collect();
    json!({
        "timestamp": time(stamp_ns),
        "frame_id": frame_id,
        "id": format!("feature-{k}"),
        "lifetime": { "sec": 0, "nsec": 0 },
        "frame_locked": true,
        "metadata": metadata,
        "arrows": [], "cubes": [], "spheres": [], "cylinders": [], "lines": [],
        "triangles": [], "texts": [], "models": [],
    })
}

fn text(x: f64, y: f64, label: String) -> Value {
    json!({
        "pose": pose(x, y),
        "billboard": true,
        "font_size": 14.0,
        "scale_invariant": true,
        "color": color(1.0, 1.0, 1.0, 1.0),
        "text": label,
    })
}

fn line_entity(stamp_ns: u64, frame_id: &str, k: usize, l: &LineFeature) -> Value {
    let (alpha, rho) = (f64::from(l.alpha), f64::from(l.rho));
    let (n, d) = ((alpha.cos(), alpha.sin()), (-alpha.sin(), alpha.cos()));
    let along = |x: f32, y: f32| f64::from(x) * d.0 + f64::from(y) * d.1;
    let sigma = |t: f64| {
        (f64::from(l.var_rho) + t * t * f64::from(l.var_alpha)
            - 2.0 * t * f64::from(l.cov_alpha_rho))
        .max(0.0)
        .sqrt()
    };
    let at = |t: f64, s: f64| {
        point(
            (n.0 * (rho + s) + d.0 * t) * MM,
            (n.1 * (rho + s) + d.1 * t) * MM,
        )
    };
    let (t0, t1) = (along(l.start.x, l.start.y), along(l.end.x, l.end.y));
    let (s0, s1) = (sigma(t0), sigma(t1));
    let segment = vec![
        point(f64::from(l.start.x) * MM, f64::from(l.start.y) * MM),
        point(f64::from(l.end.x) * MM, f64::from(l.end.y) * MM),
    ];
    let band = vec![at(t0, s0), at(t1, s1), at(t1, -s1), at(t0, -s0)];
    let mut e = entity(
        stamp_ns,
        frame_id,
        k,
        &[
            ("kind", "line".into()),
            ("first", l.first.to_string()),
            ("last", l.last.to_string()),
            ("alpha_rad", l.alpha.to_string()),
            ("rho_mm", l.rho.to_string()),
            ("sigma_alpha_rad", l.var_alpha.max(0.0).sqrt().to_string()),
            ("sigma_rho_mm", l.var_rho.max(0.0).sqrt().to_string()),
        ],
    );
    e["lines"] = json!([
        line_primitive(LINE_STRIP, segment, 0.03, color(0.2, 0.6, 1.0, 1.0)),
        line_primitive(LINE_LOOP, band, 0.01, color(0.2, 0.6, 1.0, 0.5)),
    ]);
    let mid = (
        f64::from(l.start.x + l.end.x) * 0.5 * MM,
        f64::from(l.start.y + l.end.y) * 0.5 * MM,
    );
    e["texts"] = json!([text(
        mid.0,
        mid.1,
        format!(
            "L{k} ρ {:.3} m α {:.1}° σρ {:.1} mm",
            rho * MM,
            alpha.to_degrees(),
            f64::from(l.var_rho).max(0.0).sqrt()
        )
    )]);
    e
}

/// `m` points around an ellipse centred at (cx, cy) mm with axes `a`, `b` mm, `a` at angle `phi`.
fn ellipse(cx: f64, cy: f64, a: f64, b: f64, phi: f64, m: usize) -> Vec<Value> {
    (0..m)
        .map(|i| {
            let t = std::f64::consts::TAU * i as f64 / m as f64;
            let (u, v) = (a * t.cos(), b * t.sin());
            point(
                (cx + u * phi.cos() - v * phi.sin()) * MM,
                (cy + u * phi.sin() + v * phi.cos()) * MM,
            )
        })
        .collect()
}

fn circle_entity(stamp_ns: u64, frame_id: &str, k: usize, c: &CircleFeature) -> Value {
    let (cx, cy, r) = (
        f64::from(c.center.x),
        f64::from(c.center.y),
        f64::from(c.radius),
    );
    let cov = |i: usize, j: usize| f64::from(c.cov[i][j]);
    let sigma_r = cov(2, 2).max(0.0).sqrt();
    // Centre covariance: eigenvalues and the major axis' direction.
    let (sxx, syy, sxy) = (cov(0, 0), cov(1, 1), cov(0, 1));
    let mean = 0.5 * (sxx + syy);
    let dev = (0.25 * (sxx - syy).powi(2) + sxy * sxy).sqrt();
    let (major, minor) = ((mean + dev).max(0.0).sqrt(), (mean - dev).max(0.0).sqrt());
    let phi = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let mut e = entity(
        stamp_ns,
        frame_id,
        k,
        &[
            ("kind", "circle".into()),
            ("first", c.first.to_string()),
            ("last", c.last.to_string()),
            ("center_x_mm", c.center.x.to_string()),
            ("center_y_mm", c.center.y.to_string()),
            ("radius_mm", c.radius.to_string()),
            ("sigma_radius_mm", sigma_r.to_string()),
        ],
    );
    e["cylinders"] = json!([{
        "pose": pose(cx * MM, cy * MM),
        "size": { "x": 2.0 * r * MM, "y": 2.0 * r * MM, "z": 0.01 },
        "bottom_scale": 1.0,
        "top_scale": 1.0,
        "color": color(1.0, 0.6, 0.1, 0.3),
    }]);
    let orange = |a| color(1.0, 0.6, 0.1, a);
    e["lines"] = json!([
        line_primitive(LINE_LOOP, ellipse(cx, cy, r, r, 0.0, 48), 0.02, orange(1.0)),
        line_primitive(
            LINE_LOOP,
            ellipse(cx, cy, r + sigma_r, r + sigma_r, 0.0, 48),
            0.005,
            orange(0.5)
        ),
        line_primitive(
            LINE_LOOP,
            ellipse(
                cx,
                cy,
                (r - sigma_r).max(0.0),
                (r - sigma_r).max(0.0),
                0.0,
                48
            ),
            0.005,
            orange(0.5)
        ),
        line_primitive(
            LINE_LOOP,
            ellipse(cx, cy, major, minor, phi, 24),
            0.005,
            orange(0.8)
        ),
    ]);
    e["texts"] = json!([text(
        cx * MM,
        (cy + r) * MM,
        format!("C{k} r {:.0} mm σr {:.1} mm", r, sigma_r)
    )]);
    e
}

fn number() -> Value {
    json!({ "type": "number" })
}

fn object(title: Option<&str>, properties: Value) -> Value {
    let mut o = json!({ "type": "object", "properties": properties });
    if let Some(t) = title {
        o["title"] = json!(t);
    }
    o
}

fn array(items: Value) -> Value {
    json!({ "type": "array", "items": items })
}

fn time_schema() -> Value {
    object(
        Some("time"),
        json!({ "sec": { "type": "integer" }, "nsec": { "type": "integer" } }),
    )
}

fn vector3_schema() -> Value {
    object(
        Some("foxglove.Vector3"),
        json!({ "x": number(), "y": number(), "z": number() }),
    )
}

fn pose_schema() -> Value {
    object(
        Some("foxglove.Pose"),
        json!({
            "position": vector3_schema(),
            "orientation": object(
                Some("foxglove.Quaternion"),
                json!({ "x": number(), "y": number(), "z": number(), "w": number() }),
            ),
        }),
    )
}

fn color_schema() -> Value {
    object(
        Some("foxglove.Color"),
        json!({ "r": number(), "g": number(), "b": number(), "a": number() }),
    )
}

fn laser_scan_schema() -> Vec<u8> {
    let mut s = object(
        Some("foxglove.LaserScan"),
        json!({
            "timestamp": time_schema(),
            "frame_id": { "type": "string" },
            "pose": pose_schema(),
            "start_angle": number(),
            "end_angle": number(),
            "ranges": array(number()),
            "intensities": array(number()),
        }),
    );
    s["description"] = json!("A single scan from a planar laser range-finder");
    s.to_string().into_bytes()
}

fn scene_update_schema() -> Vec<u8> {
    let line = object(
        Some("foxglove.LinePrimitive"),
        json!({
            "type": { "type": "integer", "description": "0 LINE_STRIP, 1 LINE_LOOP, 2 LINE_LIST" },
            "pose": pose_schema(),
            "thickness": number(),
            "scale_invariant": { "type": "boolean" },
            "points": array(vector3_schema()),
            "color": color_schema(),
            "colors": array(color_schema()),
            "indices": array(json!({ "type": "integer" })),
        }),
    );
    let cylinder = object(
        Some("foxglove.CylinderPrimitive"),
        json!({
            "pose": pose_schema(),
            "size": vector3_schema(),
            "bottom_scale": number(),
            "top_scale": number(),
            "color": color_schema(),
        }),
    );
    let text = object(
        Some("foxglove.TextPrimitive"),
        json!({
            "pose": pose_schema(),
            "billboard": { "type": "boolean" },
            "font_size": number(),
            "scale_invariant": { "type": "boolean" },
            "color": color_schema(),
            "text": { "type": "string" },
        }),
    );
    let entity = object(
        Some("foxglove.SceneEntity"),
        json!({
            "timestamp": time_schema(),
            "frame_id": { "type": "string" },
            "id": { "type": "string" },
            "lifetime": object(Some("duration"), json!({ "sec": { "type": "integer" }, "nsec": { "type": "integer" } })),
            "frame_locked": { "type": "boolean" },
            "metadata": array(object(
                Some("foxglove.KeyValuePair"),
                json!({ "key": { "type": "string" }, "value": { "type": "string" } }),
            )),
            "arrows": array(json!({})),
            "cubes": array(json!({})),
            "spheres": array(json!({})),
            "cylinders": array(cylinder),
            "lines": array(line),
            "triangles": array(json!({})),
            "texts": array(text),
            "models": array(json!({})),
        }),
    );
    let deletion = object(
        Some("foxglove.SceneEntityDeletion"),
        json!({
            "timestamp": time_schema(),
            "type": { "type": "integer", "description": "0 MATCHING_ID, 1 ALL" },
            "id": { "type": "string" },
        }),
    );
    let mut s = object(
        Some("foxglove.SceneUpdate"),
        json!({ "deletions": array(deletion), "entities": array(entity) }),
    );
    s["description"] = json!("An update to the entities displayed in a 3D scene");
    s.to_string().into_bytes()
}

#[cfg(test)]
mod tests {
    use super::*;
    use pfe_core::{Point, ScanGeometry};

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

    #[test]
    fn line_band_is_sigma_rho_at_the_foot_of_the_normal() {
        let l = LineFeature {
            first: 0,
            last: 9,
            points: 10,
            alpha: 0.0,
            rho: 2000.0,
            var_alpha: 1e-4,
            var_rho: 25.0,
            cov_alpha_rho: 0.0,
            start: Point { x: 2000.0, y: 0.0 },
            end: Point {
                x: 2000.0,
                y: 1000.0,
            },
        };
        let e = line_entity(5, "laser", 3, &l);
        let band = &e["lines"][1]["points"];
        // At t = 0: ±5 mm; at t = 1000 mm: ±sqrt(25 + 100) mm.
        assert!((band[0]["x"].as_f64().unwrap() - 2.005).abs() < 1e-9);
        assert!((band[3]["x"].as_f64().unwrap() - 1.995).abs() < 1e-9);
        let s1 = (125f64).sqrt() * 1e-3;
        assert!((band[1]["x"].as_f64().unwrap() - (2.0 + s1)).abs() < 1e-9);
        assert_eq!(e["id"], "feature-3");
    }
}
