//! Reading a [`Feature`] back from its tagged form (`{"kind": "line", …}`) field by field, in
//! any order, without an allocator (serde's derive for internally tagged enums buffers the
//! fields, which needs one).

use core::fmt;

use serde::Deserialize;

use super::{CircleFeature, Feature, LineFeature};
use crate::geometry::Point;

/// Which feature a tagged form holds.
#[derive(Deserialize)]
#[serde(rename_all = "lowercase")]
enum Kind {
    Line,
    Circle,
}

/// Every field of either feature, with its tag.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Tagged {
    kind: Kind,
    first: u16,
    last: u16,
    points: u16,
    alpha: Option<f32>,
    rho: Option<f32>,
    var_alpha: Option<f32>,
    var_rho: Option<f32>,
    cov_alpha_rho: Option<f32>,
    start: Option<Point>,
    end: Option<Point>,
    center: Option<Point>,
    radius: Option<f32>,
    cov: Option<[[f32; 3]; 3]>,
    start_angle: Option<f32>,
    end_angle: Option<f32>,
}

/// A field the feature's kind needs is missing.
#[derive(Debug)]
pub(super) struct Missing(&'static str);

impl fmt::Display for Missing {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "missing field `{}`", self.0)
    }
}

/// `field` or the error naming it.
fn need<T>(field: Option<T>, name: &'static str) -> Result<T, Missing> {
    field.ok_or(Missing(name))
}

impl TryFrom<Tagged> for Feature {
    type Error = Missing;

    fn try_from(t: Tagged) -> Result<Self, Missing> {
        Ok(match t.kind {
            Kind::Line => Feature::Line(LineFeature {
                first: t.first,
                last: t.last,
                points: t.points,
                alpha: need(t.alpha, "alpha")?,
                rho: need(t.rho, "rho")?,
                var_alpha: need(t.var_alpha, "var_alpha")?,
                var_rho: need(t.var_rho, "var_rho")?,
                cov_alpha_rho: need(t.cov_alpha_rho, "cov_alpha_rho")?,
                start: need(t.start, "start")?,
                end: need(t.end, "end")?,
            }),
            Kind::Circle => Feature::Circle(CircleFeature {
                first: t.first,
                last: t.last,
                points: t.points,
                center: need(t.center, "center")?,
                radius: need(t.radius, "radius")?,
                cov: need(t.cov, "cov")?,
                start_angle: need(t.start_angle, "start_angle")?,
                end_angle: need(t.end_angle, "end_angle")?,
            }),
        })
    }
}
#[cfg(test)]
mod tests {
    extern crate std;
    use super::super::*;
    use std::string::ToString;

    /// A line's JSON: tagged `"kind": "line"`, its fields by name, points as `[x, y]`; and it
    /// reads back as the same feature. A circle reads back too.
    #[test]
    fn features_serialize_as_tagged_json() -> Result<(), serde_json::Error> {
        let line = Feature::Line(LineFeature {
            first: 3,
            last: 12,
            points: 10,
            alpha: 0.5,
            rho: 2000.0,
            var_alpha: 0.25,
            var_rho: 4.0,
            cov_alpha_rho: -1.5,
            start: Point::new(1.0, 2.0),
            end: Point::new(3.0, -4.5),
        });
        let json = serde_json::to_string(&line)?;
        let expected = r#"{"kind":"line","first":3,"last":12,"points":10,"alpha":0.5,"rho":2000.0,"var_alpha":0.25,"var_rho":4.0,"cov_alpha_rho":-1.5,"start":[1.0,2.0],"end":[3.0,-4.5]}"#;
        assert_eq!(json, expected.to_string());
        assert_eq!(serde_json::from_str::<Feature>(&json)?, line);
        let circle = Feature::Circle(CircleFeature {
            first: 20,
            last: 40,
            points: 21,
            center: Point::new(1500.0, -250.0),
            radius: 300.0,
            cov: [[1.0, 0.5, 0.25], [0.5, 2.0, 0.125], [0.25, 0.125, 3.0]],
            start_angle: -0.75,
            end_angle: 0.75,
        });
        let json = serde_json::to_string(&circle)?;
        assert!(
            json.starts_with(r#"{"kind":"circle","first":20,"#),
            "{json}"
        );
        assert!(json.contains(r#""center":[1500.0,-250.0]"#), "{json}");
        assert_eq!(serde_json::from_str::<Feature>(&json)?, circle);
        Ok(())
    }

    /// A line without its `rho` is refused, and the error names the field.
    #[test]
    fn a_missing_field_is_named() {
        let json = r#"{"kind":"line","first":3,"last":12,"points":10,"alpha":0.5,"var_alpha":0.25,"var_rho":4.0,"cov_alpha_rho":-1.5,"start":[1.0,2.0],"end":[3.0,-4.5]}"#;
        let err = serde_json::from_str::<Feature>(json)
            .err()
            .map(|e| e.to_string());
        assert!(
            err.as_deref()
                .is_some_and(|e| e.contains("missing field `rho`")),
            "{err:?}"
        );
    }
}
