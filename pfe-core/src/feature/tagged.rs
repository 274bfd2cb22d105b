//! Reading a [`Feature`] back from its tagged form (`{"kind": "line", …}`) field by field, in
//! any order, without an allocator (serde's derive for internally tagged enums buffers the
//! fields, which needs one).

use core::fmt;

use serde::Deserialize;

use super::{CircleFeature, Feature, LineFeature, ObjectFeature};
use crate::geometry::Point;

/// Which feature a tagged form holds.
#[derive(Deserialize)]
#[serde(rename_all = "lowercase")]
enum Kind {
    Line,
    Circle,
    Object,
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
    cov: Option<Cov>,
    extent: Option<f32>,
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
                cov: need(t.cov.and_then(Cov::three), "cov")?,
                start_angle: need(t.start_angle, "start_angle")?,
                end_angle: need(t.end_angle, "end_angle")?,
            }),
            Kind::Object => Feature::Object(ObjectFeature {
                first: t.first,
                last: t.last,
                points: t.points,
                center: need(t.center, "center")?,
                cov: need(t.cov.and_then(Cov::two), "cov")?,
                extent: need(t.extent, "extent")?,
            }),
        })
    }
}

/// A covariance matrix of 2×2 (an object's centre) or 3×3 (a circle's centre and radius), read
/// without an allocator.
struct Cov {
    rows: [[f32; 3]; 3],
    /// Rows read, and the length of each (all equal).
    n: usize,
}

impl Cov {
    fn three(self) -> Option<[[f32; 3]; 3]> {
        (self.n == 3).then_some(self.rows)
    }

    fn two(self) -> Option<[[f32; 2]; 2]> {
        let [[a, b, _], [c, d, _], _] = self.rows;
        (self.n == 2).then_some([[a, b], [c, d]])
    }
}

/// One row of [`Cov`]: up to three numbers and how many.
#[derive(Clone, Copy, Default)]
struct Row([f32; 3], usize);

/// Reads up to three items of a sequence with `item`, refusing more.
fn up_to_three<'de, A, T: Copy + Default>(
    mut seq: A,
    mut item: impl FnMut(&mut A) -> Result<Option<T>, A::Error>,
) -> Result<([T; 3], usize), A::Error>
where
    A: serde::de::SeqAccess<'de>,
{
    let mut out = [T::default(); 3];
    let mut n = 0;
    while let Some(v) = item(&mut seq)? {
        let slot = out
            .get_mut(n)
            .ok_or_else(|| serde::de::Error::invalid_length(n + 1, &"2 or 3"))?;
        *slot = v;
        n += 1;
    }
    Ok((out, n))
}

impl<'de> Deserialize<'de> for Row {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = Row;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a row of 2 or 3 numbers")
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, seq: A) -> Result<Row, A::Error> {
                let (v, n) = up_to_three(seq, |s| s.next_element::<f32>())?;
                Ok(Row(v, n))
            }
        }
        d.deserialize_seq(V)
    }
}

impl<'de> Deserialize<'de> for Cov {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = Cov;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a 2×2 or 3×3 matrix")
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, seq: A) -> Result<Cov, A::Error> {
                let (rows, n) = up_to_three(seq, |s| s.next_element::<Row>())?;
                if !rows.iter().take(n).all(|r| r.1 == n) {
                    return Err(serde::de::Error::custom("the matrix is not square"));
                }
                Ok(Cov {
                    rows: rows.map(|r| r.0),
                    n,
                })
            }
        }
        d.deserialize_seq(V)
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
        let object = Feature::Object(ObjectFeature::new(
            5,
            8,
            4,
            Point::new(900.0, 25.0),
            [[16.0, 2.0], [2.0, 9.0]],
            40.0,
        ));
        let json = serde_json::to_string(&object)?;
        let expected = r#"{"kind":"object","first":5,"last":8,"points":4,"center":[900.0,25.0],"cov":[[16.0,2.0],[2.0,9.0]],"extent":40.0}"#;
        assert_eq!(json, expected.to_string());
        assert_eq!(serde_json::from_str::<Feature>(&json)?, object);
        // A circle's 3×3 covariance is no object's, nor a ragged one anyone's.
        let wrong = expected.replace("[[16.0,2.0],[2.0,9.0]]", "[[1,0,0],[0,1,0],[0,0,1]]");
        assert!(serde_json::from_str::<Feature>(&wrong).is_err());
        let ragged = expected.replace("[[16.0,2.0],[2.0,9.0]]", "[[1,0],[0,1,2]]");
        assert!(serde_json::from_str::<Feature>(&ragged).is_err());
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
