//! The messages: `foxglove.LaserScan` of a scan, `foxglove.SceneUpdate` of its features.

use pfe_core::{CircleFeature, Feature, LineFeature, ObjectFeature};
use serde_json::{json, Value};

use pfe_formats::Record;

pub(super) const MM: f64 = 1e-3;

pub(super) fn time(stamp_ns: u64) -> Value {
    json!({ "sec": stamp_ns / 1_000_000_000, "nsec": stamp_ns % 1_000_000_000 })
}

pub(super) fn point(x: f64, y: f64) -> Value {
    json!({ "x": x, "y": y, "z": 0.0 })
}

fn identity_pose() -> Value {
    pose(0.0, 0.0)
}

pub(super) fn pose(x: f64, y: f64) -> Value {
    json!({ "position": point(x, y), "orientation": { "x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0 } })
}

pub(super) fn color(r: f64, g: f64, b: f64, a: f64) -> Value {
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
            Feature::Object(o) => object_entity(stamp_ns, frame_id, k, o),
            f => entity(
                stamp_ns,
                frame_id,
                k,
                &[
                    ("kind", "unknown".into()),
                    ("first", f.first().to_string()),
                    ("last", f.last().to_string()),
                ],
            ),
        })
        .collect();
    json!({
        "deletions": [{ "timestamp": time(stamp_ns), "type": 1, "id": "" }],
        "entities": entities,
    })
}

pub(super) fn line_primitive(kind: u8, points: Vec<Value>, thickness: f64, c: Value) -> Value {
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

pub(super) const LINE_STRIP: u8 = 0;
pub(super) const LINE_LOOP: u8 = 1;

pub(super) fn entity(
    stamp_ns: u64,
    frame_id: &str,
    k: usize,
    metadata: &[(&str, String)],
) -> Value {
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

pub(super) fn line_entity(stamp_ns: u64, frame_id: &str, k: usize, l: &LineFeature) -> Value {
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
pub(super) fn ellipse(cx: f64, cy: f64, a: f64, b: f64, phi: f64, m: usize) -> Vec<Value> {
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

/// A small object: a sphere at its centre as wide as its extent, and its centre's 3σ ellipse.
fn object_entity(stamp_ns: u64, frame_id: &str, k: usize, o: &ObjectFeature) -> Value {
    let (cx, cy, w) = (
        f64::from(o.center.x),
        f64::from(o.center.y),
        f64::from(o.extent),
    );
    let cov = |i: usize, j: usize| f64::from(o.cov[i][j]);
    let (sxx, syy, sxy) = (cov(0, 0), cov(1, 1), 0.5 * (cov(0, 1) + cov(1, 0)));
    let mean = 0.5 * (sxx + syy);
    let dev = (0.25 * (sxx - syy).powi(2) + sxy * sxy).sqrt();
    let (major, minor) = ((mean + dev).max(0.0).sqrt(), (mean - dev).max(0.0).sqrt());
    let phi = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let mut e = entity(
        stamp_ns,
        frame_id,
        k,
        &[
            ("kind", "object".into()),
            ("first", o.first.to_string()),
            ("last", o.last.to_string()),
            ("center_x_mm", o.center.x.to_string()),
            ("center_y_mm", o.center.y.to_string()),
            ("extent_mm", o.extent.to_string()),
        ],
    );
    let size = w.max(20.0) * MM;
    e["spheres"] = json!([{
        "pose": pose(cx * MM, cy * MM),
        "size": { "x": size, "y": size, "z": size },
        "color": color(0.6, 0.2, 0.8, 0.6),
    }]);
    e["lines"] = json!([line_primitive(
        LINE_LOOP,
        ellipse(cx, cy, 3.0 * major, 3.0 * minor, phi, 24),
        0.005,
        color(0.6, 0.2, 0.8, 0.8)
    )]);
    e["texts"] = json!([text(cx * MM, cy * MM, format!("O{k} {:.0} mm", w))]);
    e
}

#[cfg(test)]
mod tests {
    use super::*;
    use pfe_core::Point;

    #[test]
    fn line_band_is_sigma_rho_at_the_foot_of_the_normal() {
        let l = LineFeature::new(
            0,
            9,
            10,
            0.0,
            2000.0,
            1e-4,
            25.0,
            0.0,
            Point { x: 2000.0, y: 0.0 },
            Point {
                x: 2000.0,
                y: 1000.0,
            },
        );
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
