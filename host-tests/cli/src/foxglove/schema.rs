//! The JSON Schemas of the messages and the channels that carry them.

use serde_json::{json, Value};

use super::{FEATURES_TOPIC, SCAN_TOPIC};

pub(super) fn number() -> Value {
    json!({ "type": "number" })
}

pub(super) fn object(title: Option<&str>, properties: Value) -> Value {
    let mut o = json!({ "type": "object", "properties": properties });
    if let Some(t) = title {
        o["title"] = json!(t);
    }
    o
}

pub(super) fn array(items: Value) -> Value {
    json!({ "type": "array", "items": items })
}

pub(super) fn time_schema() -> Value {
    object(
        Some("time"),
        json!({ "sec": { "type": "integer" }, "nsec": { "type": "integer" } }),
    )
}

pub(super) fn vector3_schema() -> Value {
    object(
        Some("foxglove.Vector3"),
        json!({ "x": number(), "y": number(), "z": number() }),
    )
}

pub(super) fn pose_schema() -> Value {
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

pub(super) fn color_schema() -> Value {
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

pub(super) fn scene_update_schema() -> Vec<u8> {
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

/// Encoding of every message (`json`).
pub const MESSAGE_ENCODING: &str = "json";
/// Encoding of every schema (`jsonschema`).
pub const SCHEMA_ENCODING: &str = "jsonschema";

/// A channel: a topic, its schema's name and its JSON Schema (messages are JSON).
#[derive(Clone, Copy, Debug)]
pub struct Channel {
    /// Topic name.
    pub topic: &'static str,
    /// Schema name (Foxglove picks its panel by it).
    pub schema_name: &'static str,
    schema: fn() -> Vec<u8>,
}

impl Channel {
    /// A channel on `topic` with the JSON Schema `schema` named `schema_name`.
    pub(super) const fn new(
        topic: &'static str,
        schema_name: &'static str,
        schema: fn() -> Vec<u8>,
    ) -> Self {
        Channel {
            topic,
            schema_name,
            schema,
        }
    }

    /// The JSON Schema, UTF-8.
    pub fn schema(&self) -> Vec<u8> {
        (self.schema)()
    }
}

/// The scans: `foxglove.LaserScan` on [`SCAN_TOPIC`].
pub const SCAN: Channel = Channel {
    topic: SCAN_TOPIC,
    schema_name: "foxglove.LaserScan",
    schema: laser_scan_schema,
};

/// The features: `foxglove.SceneUpdate` on [`FEATURES_TOPIC`].
pub const FEATURES: Channel = Channel {
    topic: FEATURES_TOPIC,
    schema_name: "foxglove.SceneUpdate",
    schema: scene_update_schema,
};
