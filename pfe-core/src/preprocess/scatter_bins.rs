//! [`residual_bins`]' bins against the histogram's definition: `|e| · scale` truncated, and
//! residuals beyond the last bin ([`BINS`] − 1, 32 σ_r) counted in it.

use super::*;

/// The bins of the middle of five points on the wall x = 3000 mm (beams 50 mm apart), the
/// middle one `off` mm beyond it along its beam (the bearing 0): both chords (of its
/// neighbours, and of the points two beams away) lie on the wall, so both residuals are `off`.
fn bins_of(off: f32, sigma_r: f32) -> (u16, u16) {
    let wall = |y: f32| Point::new(3000.0, y);
    let points = [
        wall(-100.0),
        wall(-50.0),
        Point::new(3000.0 + off, 0.0),
        wall(50.0),
        wall(100.0),
    ];
    let (mut one, mut two) = ([NONE; 1], [NONE; 1]);
    residual_bins(&points, PER_SIGMA / sigma_r, (&mut one, &mut two));
    (one[0], two[0])
}

#[test]
fn a_residual_falls_in_the_bin_of_its_sixteenths_of_sigma() {
    // 10.5 mm at σ_r = 5 mm: 33.6 sixteenths of σ_r.
    assert_eq!(bins_of(10.5, 5.0), (33, 33));
    assert_eq!(bins_of(-10.5, 5.0), (33, 33));
}

#[test]
fn a_residual_beyond_32_sigma_counts_in_the_last_bin() {
    let last = (BINS - 1) as u16;
    // 32.03 σ_r (bin 512.5), 40 σ_r and 2 000 σ_r.
    for off in [160.15f32, 200.0, 10_000.0] {
        assert_eq!(bins_of(off, 5.0), (last, last), "{off} mm");
    }
}
