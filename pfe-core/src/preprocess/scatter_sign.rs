//! [`at_span`] at a negative σ_r: a negative `scale` puts a residual at a negative bin, which
//! [`count`] does not count (nor [`residual_bins`]), so [`at_span`] takes its fast path
//! ([`count_finite`], which would put it in bin 0) only for a positive finite scale.

use super::*;

/// A wall 2 m ahead, bearings ±45° at 0.5°, every other pair of beams 6 mm nearer and the
/// others 6 mm farther: residuals of about 6 mm at spans 1 and 3, 12 mm at span 2.
fn zigzag_wall() -> [Point; 181] {
    core::array::from_fn(|i| {
        let b = (i as f32 - 90.0) * 0.5f32.to_radians();
        let (s, c) = math::sin_cos(b);
        let r = 2000.0 / c + if i / 2 % 2 == 0 { 6.0 } else { -6.0 };
        Point::new(r * c, r * s)
    })
}

/// At σ_r = 1 mm the 12 mm residuals are counted (12 σ_r: capped at [`MAX_FACTOR`]); at
/// σ_r = −1 mm each lies 96 or 192 bins below the histogram: none counts, no estimate at
/// any span, as the one-pass scatter gives none.
#[test]
fn a_negative_sigma_r_counts_no_residual_below_the_first_bin() {
    let p = zigzag_wall();
    assert_eq!(at_span(&p, 2, 1.0), Some(MAX_FACTOR));
    for span in 1..=3 {
        assert_eq!(at_span(&p, span, -1.0), None, "span {span}");
    }
    assert_eq!(sigma(&p, -1.0), None);
}
