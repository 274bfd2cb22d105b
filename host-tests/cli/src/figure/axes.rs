//! The plot's extent and axis ticks.

/// Axis-aligned bounds in mm.
#[derive(Clone, Copy, Debug)]
pub(super) struct Bounds {
    pub(super) x0: f64,
    pub(super) x1: f64,
    pub(super) y0: f64,
    pub(super) y1: f64,
}

impl Bounds {
    pub(super) fn add(&mut self, x: f64, y: f64) {
        if x.is_finite() && y.is_finite() {
            self.x0 = self.x0.min(x);
            self.x1 = self.x1.max(x);
            self.y0 = self.y0.min(y);
            self.y1 = self.y1.max(y);
        }
    }
}

/// A "nice" tick step (1, 2 or 5 × 10^k) giving about `target` ticks over `span`.
pub(super) fn tick_step(span: f64, target: f64) -> f64 {
    let raw = (span / target).max(1e-9);
    let mag = 10f64.powf(raw.log10().floor());
    let f = raw / mag;
    let nice = if f < 1.5 {
        1.0
    } else if f < 3.5 {
        2.0
    } else if f < 7.5 {
        5.0
    } else {
        10.0
    };
    nice * mag
}

/// Tick label for `v` mm with step `step` mm, in m when `metres`.
pub(super) fn tick_label(v: f64, step: f64, metres: bool) -> String {
    // Snap to the step so that rounding never prints "-0".
    let v = (v / step).round() * step + 0.0;
    if metres {
        let decimals = if step >= 1000.0 {
            0
        } else if step >= 100.0 {
            1
        } else {
            2
        };
        let t = format!("{:.*}", decimals, v / 1000.0);
        if t.trim_start_matches(['-', '0', '.']).is_empty() {
            "0".to_string()
        } else {
            t
        }
    } else {
        let t = format!("{v:.0}");
        if t == "-0" {
            "0".to_string()
        } else {
            t
        }
    }
}
