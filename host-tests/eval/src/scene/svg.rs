//! An SVG picture of a simulated scan and its ground truth.

use super::vec2::V2;
use super::{Shape, SimScan};

impl SimScan {
    /// An SVG picture of the scan (scanner at the origin, x up): the scene's primitives in
    /// grey, measured points coloured by ground-truth feature (black: not in a feature),
    /// true marks circled in red.
    pub fn to_svg(&self, size_px: f64) -> String {
        use std::fmt::Write as _;
        let r_max = f64::from(self.geometry.r_max);
        let k = size_px / (2.0 * r_max);
        // Scanner frame (x forward, y left) → screen (right = −y, up = x).
        let px = |p: V2| (size_px / 2.0 - p[1] * k, size_px / 2.0 - p[0] * k);
        let mut s = format!(
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{size_px}" height="{size_px}" viewBox="0 0 {size_px} {size_px}"><rect width="100%" height="100%" fill="white"/>"#
        );
        for sh in &self.shapes {
            match *sh {
                Shape::Segment { a, b } => {
                    let ((x1, y1), (x2, y2)) = (px(a), px(b));
                    let _ = write!(
                        s,
                        r#"<line x1="{x1:.1}" y1="{y1:.1}" x2="{x2:.1}" y2="{y2:.1}" stroke="silver" stroke-width="1"/>"#
                    );
                }
                Shape::Circle { center, radius } => {
                    let (x, y) = px(center);
                    let _ = write!(
                        s,
                        r#"<circle cx="{x:.1}" cy="{y:.1}" r="{:.1}" fill="none" stroke="silver"/>"#,
                        radius * k
                    );
                }
            }
        }
        const COLORS: [&str; 6] = [
            "#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2",
        ];
        let mut color = vec!["black"; self.ranges_mm.len()];
        for (fi, f) in self.truth.iter().enumerate() {
            for c in color.iter_mut().take(f.last + 1).skip(f.first) {
                *c = COLORS[fi % COLORS.len()];
            }
        }
        for (i, p) in self.points().iter().enumerate() {
            if let (Some(p), Some(c)) = (p, color.get(i)) {
                let (x, y) = px([f64::from(p.x), f64::from(p.y)]);
                let _ = write!(s, r#"<circle cx="{x:.1}" cy="{y:.1}" r="1.5" fill="{c}"/>"#);
                if self.true_marks.contains(&i) {
                    let _ = write!(
                        s,
                        r#"<circle cx="{x:.1}" cy="{y:.1}" r="4" fill="none" stroke="red"/>"#
                    );
                }
            }
        }
        let (ox, oy) = px([0.0, 0.0]);
        let _ = write!(
            s,
            r#"<circle cx="{ox:.1}" cy="{oy:.1}" r="4" fill="red"/></svg>"#
        );
        s
    }
}
