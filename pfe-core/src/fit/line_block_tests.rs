//! `fit::line`'s covariance in blocks against its one-point-at-a-time form.

use super::*;

/// The covariance from a slice, in blocks, is the iterator's one point at a time bit for
/// bit, for every length around the block's, a point at the scanner, one not finite, and
/// the scanner at the origin or elsewhere.
#[test]
fn covariance_in_blocks_is_the_one_by_one_sum() {
    let mut pts: heapless::Vec<Point, 40> = (0..40)
        .map(|i| {
            let t = i as f32;
            Point::new(500.0 + 37.0 * t, 1200.0 - 11.0 * t + 3.0 * (0.9 * t).sin())
        })
        .collect();
    let Ok(line) = fit_line(&pts) else {
        panic!("no line")
    };
    if let Some(p) = pts.get_mut(7) {
        *p = Point::new(0.0, 0.0);
    }
    if let Some(p) = pts.get_mut(30) {
        *p = Point::new(f32::NAN, 5.0);
    }
    for origin in [Point::new(0.0, 0.0), Point::new(-40.0, 25.0)] {
        for n in 0..=pts.len() {
            let p = pts.get(..n).unwrap_or(&[]);
            let a = line.covariance_range_of(p, origin, 10.0);
            let b = line.covariance_range(p.iter().copied(), origin, 10.0);
            for (x, y) in [
                (a.var_alpha, b.var_alpha),
                (a.var_rho, b.var_rho),
                (a.cov_alpha_rho, b.cov_alpha_rho),
            ] {
                assert_eq!(x.to_bits(), y.to_bits(), "{n} points from {origin:?}");
            }
        }
    }
}
