//! The grid a recording's ranges lie on (`pfe_core::Scan::quantum`).

/// The grid the valid readings (finite, > 0, ≤ `r_max`) of one scan lie on, mm: the coarsest
/// of 1, 2, 5, 10, 20, 25, 50 and 100 mm that divides every one of them, when all are whole
/// mm (to 0.05 mm: logs in m read through f32) and at least 20 of them, of at least 5
/// distinct values, tell; otherwise 0 (unknown). The extractor counts the rounding's
/// variance q²/12 as systematic (`pfe_core::Scan::quantum`). pfe-core's
/// [`Ranges::grid`](pfe_core::Ranges::grid), which the firmware runs on the scanner's codes.
///
/// ```
/// use pfe_formats::range_quantum;
/// let grid: Vec<f32> = (0..181).map(|i| 1000.0 + 50.0 * (i % 7) as f32).collect();
/// assert_eq!(range_quantum(&grid, 80_000.0), 50.0);
/// let cm: Vec<f32> = (0..181).map(|i| 2000.0 + 10.0 * i as f32).collect();
/// assert_eq!(range_quantum(&cm, 80_000.0), 10.0);
/// let fine: Vec<f32> = (0..181).map(|i| 2000.0 + 0.37 * i as f32).collect();
/// assert_eq!(range_quantum(&fine, 80_000.0), 0.0);
/// ```
pub fn range_quantum(ranges_mm: &[f32], r_max: f32) -> f32 {
    pfe_core::Ranges::Mm(ranges_mm).grid(r_max)
}

#[cfg(test)]
mod tests {
    use super::range_quantum;

    /// 40 readings on a grid of `q` mm (9 distinct values), starting at `at` mm.
    fn grid(q: f32, at: f32) -> Vec<f32> {
        (0..40).map(|i| at + q * (i % 9) as f32).collect()
    }

    #[test]
    fn the_coarsest_grid_that_divides_every_reading() {
        for q in [1.0, 2.0, 5.0, 10.0, 20.0, 25.0, 50.0, 100.0] {
            assert_eq!(range_quantum(&grid(q, 2000.0), 80_000.0), q, "{q}");
        }
        // 30 mm is no grid of the list: its readings are whole tens.
        assert_eq!(range_quantum(&grid(30.0, 2010.0), 80_000.0), 10.0);
        // Logs in m read through f32: 2.35 m.
        let metres: Vec<f32> = grid(50.0, 2350.0)
            .iter()
            .map(|r| (r / 1000.0) * 1000.0)
            .collect();
        assert_eq!(range_quantum(&metres, 80_000.0), 50.0);
    }

    #[test]
    fn no_returns_and_readings_past_the_range_do_not_tell() {
        let mut r = grid(50.0, 2000.0);
        r.extend([f32::NAN, 0.0, -30.0, f32::INFINITY, 81_910.0, 51_140.0]);
        assert_eq!(range_quantum(&r, 50_000.0), 50.0);
        // Within the range, 51 140 mm is on the 10 mm grid only.
        assert_eq!(range_quantum(&r, 80_000.0), 10.0);
    }

    #[test]
    fn too_little_or_unrounded_data_is_unknown() {
        let r = grid(50.0, 2000.0);
        assert_eq!(range_quantum(&r[..19], 80_000.0), 0.0);
        assert_eq!(range_quantum(&r[..20], 80_000.0), 50.0);
        // 20 readings of 4 distinct values: a wall of equal ranges tells no grid.
        let few: Vec<f32> = (0..40).map(|i| 2000.0 + 50.0 * (i % 4) as f32).collect();
        assert_eq!(range_quantum(&few, 80_000.0), 0.0);
        let mut off = grid(10.0, 2000.0);
        off[7] += 0.3;
        assert_eq!(range_quantum(&off, 80_000.0), 0.0);
        off[7] = 2000.04;
        assert_eq!(range_quantum(&off, 80_000.0), 10.0);
        assert_eq!(range_quantum(&[], 80_000.0), 0.0);
    }
}
