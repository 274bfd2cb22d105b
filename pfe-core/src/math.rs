//! The few f32 functions the extractor needs: atan2 from `libm` (exact, default) or
//! `micromath` (fast approximations, feature `micromath`), sine and cosine from an f32 kernel
//! (or micromath), square root and finiteness by FPU arithmetic. Everything else in the crate
//! calls these.

#[cfg(not(feature = "libm"))]
compile_error!("pfe-core needs its `libm` feature (on by default; `micromath` turns it on too)");

#[cfg(feature = "micromath")]
mod imp {
    use micromath::F32Ext;
    pub fn atan2(y: f32, x: f32) -> f32 {
        F32Ext::atan2(y, x)
    }
    pub fn sin_cos(x: f32) -> (f32, f32) {
        (F32Ext::sin(x), F32Ext::cos(x))
    }
}

#[cfg(not(feature = "micromath"))]
mod imp {
    pub fn atan2(y: f32, x: f32) -> f32 {
        libm::atan2f(y, x)
    }
    pub fn sin_cos(x: f32) -> (f32, f32) {
        match super::sin_cos_f32(x) {
            Some(sc) => sc,
            None => super::sin_cos_large(x),
        }
    }
}

pub(crate) use imp::{atan2, sin_cos};

/// `sin x`.
pub(crate) fn sin(x: f32) -> f32 {
    sin_cos(x).0
}

/// `(sin x, cos x)` for |x| ≤ 10⁴ in f32 arithmetic only, within 2·10⁻⁷ of the exact values
/// (`None` beyond, and for NaN or ±inf), bit-identical on every target. libm's `sinf`/`cosf`
/// evaluate in f64, which the Cortex-M4F does in software (about 700 instructions a call;
/// de-skewing calls two per point): this is about 40. Cody–Waite reduction by π/2 in three
/// parts (exact products for |k| < 2¹³), then the minimax polynomials of musl's
/// `__sindf`/`__cosdf` on |r| ≤ π/4. pfe-core's sine and cosine (without `micromath`) and
/// pfe-pose's use it.
///
/// ```
/// let (s, c) = pfe_core::sin_cos_f32(core::f32::consts::FRAC_PI_6).unwrap();
/// assert!((s - 0.5).abs() < 1e-6 && (c - 0.866_025_4).abs() < 1e-6);
/// assert_eq!(pfe_core::sin_cos_f32(f32::NAN), None);
/// ```
#[allow(clippy::excessive_precision)] // the coefficients as published
pub fn sin_cos_f32(x: f32) -> Option<(f32, f32)> {
    const FRAC_2_PI: f32 = core::f32::consts::FRAC_2_PI;
    const P1: f32 = 1.570_312_5; // 8 significant bits
    const P2: f32 = 4.837_512_969_970_703e-4; // 11 significant bits
    const P3: f32 = 7.549_789_954_891_882e-8;
    const S1: f32 = -0.166_666_666_416_265_24;
    const S2: f32 = 0.008_333_329_385_889_463;
    const S3: f32 = -0.000_198_393_348_360_966_32;
    const S4: f32 = 0.000_002_718_311_493_989_822;
    const C0: f32 = -0.499_999_997_251_031;
    const C1: f32 = 0.041_666_623_323_739_06;
    const C2: f32 = -0.001_388_676_377_460_993;
    const C3: f32 = 0.000_024_390_448_796_277_41;
    if !(abs(x) <= 1.0e4) {
        return None;
    }
    let half = if x < 0.0 { -0.5 } else { 0.5 };
    let k = (x * FRAC_2_PI + half) as i32; // round half away from zero; |k| ≤ 6367
    let kf = k as f32;
    let r = ((x - kf * P1) - kf * P2) - kf * P3;
    let z = r * r;
    let s = r + r * z * (S1 + z * (S2 + z * (S3 + z * S4)));
    let w = z * z;
    let c = ((1.0 + z * C0) + w * C1) + (w * z) * (C2 + z * C3);
    Some(match k & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    })
}

/// 2/π: one word of zeros, then its first 256 bits after the binary point.
#[cfg_attr(feature = "micromath", allow(dead_code))]
const FRAC_2_PI_BITS: [u32; 9] = [
    0,
    0xA2F9_836E,
    0x4E44_1529,
    0xFC27_57D1,
    0xF534_DDC0,
    0xDB62_9599,
    0x3C43_9041,
    0xFE51_63AB,
    0xDEBB_C561,
];

/// `(sin x, cos x)` for |x| > 10⁴ (where [`sin_cos_f32`] stops): libm's `sinf` and `cosf`
/// bit for bit on every such f32 (NaN for ±inf and NaN, as libm), in integer arithmetic only.
/// libm reduces by π/2 and evaluates its kernels in f64, which links soft double arithmetic
/// and a 2.5 KB Payne–Hanek routine into the firmware; this reduces exactly (x · 2/π mod 4
/// from a 128-bit window of 2/π's bits: at least 90 bits of the remainder for every f32) and
/// evaluates the same kernel polynomials (musl's `__sindf`/`__cosdf` coefficients) in Q62
/// fixed point, 60 bits where the f64 kernels keep 53: the results round to the same f32 but
/// for three arguments (±), whose libm bits are in a table. The exhaustive test (`sin_cos_large_is_libm_on_every_f32`, ignored: minutes) checks every
/// argument; a test run checks every 1021st.
#[allow(clippy::excessive_precision)] // the coefficients as published
#[cfg_attr(feature = "micromath", allow(dead_code))]
#[allow(clippy::eq_op)] // x − x: libm's NaN for ±inf and NaN.
pub(crate) fn sin_cos_large(x: f32) -> (f32, f32) {
    const PIO2_Q62: u64 = 0x6487_ED51_10B4_611A; // π/2 · 2⁶²
    const Q: f64 = (1u64 << 62) as f64;
    const ONE: i128 = 1 << 62;
    const S1: i128 = (-0.166_666_666_416_265_235_595 * Q) as i128;
    const S2: i128 = (0.008_333_329_385_889_463_175_6 * Q) as i128;
    const S3: i128 = (-0.000_198_393_348_360_966_317_347 * Q) as i128;
    const S4: i128 = (0.000_002_718_311_493_989_821_906_4 * Q) as i128;
    const C0: i128 = (-0.499_999_997_251_031_003_120 * Q) as i128;
    const C1: i128 = (0.041_666_623_323_739_063_189_4 * Q) as i128;
    const C2: i128 = (-0.001_388_676_377_460_992_946_92 * Q) as i128;
    const C3: i128 = (0.000_024_390_448_796_277_409_065_4 * Q) as i128;
    let bits = x.to_bits() & 0x7fff_ffff;
    let biased = bits >> 23;
    if !finite(x) || biased < 140 {
        // sin and cos of ±inf and NaN are NaN (libm's x − x); |x| < 2¹³ is not taken here.
        return (x - x, x - x);
    }
    // The three f32 (of 1.9·10⁹) where libm's f64 kernels round the other way: its bits.
    const LIBM_ROUNDING: [(u32, u32, u32); 3] = [
        (0x5023_64CE, 0x3F4B_09D6, 0xBF1B_EBD0),
        (0x552F_6DFD, 0x3EC9_9426, 0xBF6B_5303),
        (0x7B51_A603, 0xBF74_1C8F, 0x3E9A_36FA),
    ];
    if let Some(&(_, s, c)) = LIBM_ROUNDING.iter().find(|e| e.0 == bits) {
        let s = f32::from_bits(s);
        return (if x < 0.0 { -s } else { s }, f32::from_bits(c));
    }
    // |x| = m · 2^e with e = biased − 150 ≥ −10; the bits of 2/π from 2^−(e−1) on give
    // x · 2/π mod 4 as m · window mod 2¹²⁸, in units of 2⁻¹²⁶.
    let m = u128::from((bits & 0x7f_ffff) | 0x80_0000);
    let from = (biased - 120) as usize;
    let (word, shift) = (from / 32, from % 32);
    let window = match FRAC_2_PI_BITS.get(word..word + 5) {
        Some(&[a, b, c, d, e]) => {
            let top = u128::from(a) << 96 | u128::from(b) << 64 | u128::from(c) << 32;
            (top | u128::from(d)) << shift | u128::from((u64::from(e) << shift) >> 32)
        }
        _ => 0,
    };
    // The nearest quadrant n and the remainder r ∈ [−½, ½) of a quadrant.
    let t = m.wrapping_mul(window).wrapping_add(1 << 125);
    let n = (t >> 126) as u32 & 3;
    let r = (t & ((1 << 126) - 1)) as i128 - (1 << 125);
    let ra = r.unsigned_abs();
    // |r| ≤ 2¹²⁵, so lz ≥ 2; every f32 keeps lz ≤ 36 (its remainder is not that small).
    let lz = ra.leading_zeros().min(64);
    let r64 = ((ra << lz) >> 64) as u64;
    // y = |r| · π/2 = ym · 2^(−60−lz); yq = y · 2⁶², z = y² · 2⁶².
    let ym = ((u128::from(r64) * u128::from(PIO2_Q62)) >> 64) as u64;
    let yq = ym.checked_shr(lz.saturating_sub(2)).unwrap_or(0);
    let z = ((u128::from(yq) * u128::from(yq)) >> 62) as i128;
    let mul = |a: i128, b: i128| (a * b) >> 62;
    let sin_y = ONE + mul(z, S1 + mul(z, S2 + mul(z, S3 + mul(z, S4)))); // sin y / y
    let cos_y = ONE + mul(z, C0 + mul(z, C1 + mul(z, C2 + mul(z, C3))));
    let ps = ((u128::from(ym) * sin_y as u128) >> 64) as u64; // sin y · 2^(58+lz)
    let sa = ps as f32 * f32::from_bits((127 - 58 - lz) << 23);
    let c = cos_y as u64 as f32 * f32::from_bits((127 - 62) << 23);
    let s = if r < 0 { -sa } else { sa };
    let (s, c) = match n {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    };
    (if x < 0.0 { -s } else { s }, c)
}

/// Square root, correctly rounded (IEEE 754): the FPU's `vsqrt.f32` on hard-float Arm (14
/// cycles on a Cortex-M4F, where libm's `sqrtf` is a bit-by-bit software loop of a few hundred
/// instructions), libm's `sqrtf` elsewhere (the SSE instruction on x86-64). Both round
/// correctly, so host and target results stay bit-identical. Negative inputs and NaN give
/// NaN, +inf gives +inf.
#[inline]
pub(crate) fn sqrt(x: f32) -> f32 {
    #[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
    {
        vfp::sqrt(x)
    }
    #[cfg(not(all(target_arch = "arm", target_abi = "eabihf")))]
    {
        libm::sqrtf(x)
    }
}

/// `[√a, √b, √c]`, each [`sqrt`] (the same bits): on hard-float Arm one call of three
/// `vsqrt.f32` (arguments and results in s0–s2), where three calls of [`sqrt`] take six
/// instructions more (a call and a return each).
#[inline]
pub(crate) fn sqrt3(a: f32, b: f32, c: f32) -> [f32; 3] {
    #[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
    {
        vfp::sqrt3(a, b, c)
    }
    #[cfg(not(all(target_arch = "arm", target_abi = "eabihf")))]
    {
        [sqrt(a), sqrt(b), sqrt(c)]
    }
}

/// `[√a, √b]`, each [`sqrt`] (the same bits): on hard-float Arm one call of two `vsqrt.f32`
/// (arguments and results in s0–s1), where two calls of [`sqrt`] take two instructions more.
#[inline]
pub(crate) fn sqrt2(a: f32, b: f32) -> [f32; 2] {
    #[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
    {
        vfp::sqrt2(a, b)
    }
    #[cfg(not(all(target_arch = "arm", target_abi = "eabihf")))]
    {
        [sqrt(a), sqrt(b)]
    }
}

/// [`sqrt`] for loops meant to vectorise: with the `std` feature, std's (LLVM's square root,
/// which it can compute a few lanes at once; libm's is an opaque `sqrtss`), else [`sqrt`]. Both
/// round correctly: the same results. Only there: LLVM also moves its own square roots out of
/// branches, which slowed the walk.
#[inline(always)]
pub(crate) fn sqrt_lanes(x: f32) -> f32 {
    #[cfg(feature = "std")]
    {
        x.sqrt()
    }
    #[cfg(not(feature = "std"))]
    {
        sqrt(x)
    }
}

/// `vsqrt.f32` as a two-instruction function. Stable Rust cannot name an FPU register in
/// inline assembly on thumbv7em (rust-lang/rust#159976: the register classes ask for `vfp2`,
/// which the single-precision FPU lacks) and `core::f32::math::sqrt` is unstable, so the
/// instruction lives in a global assembly function with the C ABI of the eabihf targets
/// (AAPCS-VFP: argument and result in s0).
#[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
#[allow(unsafe_code)]
mod vfp {
    core::arch::global_asm!(
        ".pushsection .text.pfe_core_vsqrt,\"ax\",%progbits",
        ".p2align 2",
        // The smallest FPU with the instruction (module assembly does not see the target's).
        ".fpu fpv4-sp-d16",
        ".global pfe_core_vsqrt",
        ".type pfe_core_vsqrt,%function",
        "pfe_core_vsqrt:",
        "vsqrt.f32 s0, s0",
        "bx lr",
        ".size pfe_core_vsqrt, . - pfe_core_vsqrt",
        ".popsection",
        ".pushsection .text.pfe_core_vsqrt3,\"ax\",%progbits",
        ".p2align 2",
        ".fpu fpv4-sp-d16",
        ".global pfe_core_vsqrt3",
        ".type pfe_core_vsqrt3,%function",
        "pfe_core_vsqrt3:",
        "vsqrt.f32 s0, s0",
        "vsqrt.f32 s1, s1",
        "vsqrt.f32 s2, s2",
        "bx lr",
        ".size pfe_core_vsqrt3, . - pfe_core_vsqrt3",
        ".popsection",
        ".pushsection .text.pfe_core_vsqrt2,\"ax\",%progbits",
        ".p2align 2",
        ".fpu fpv4-sp-d16",
        ".global pfe_core_vsqrt2",
        ".type pfe_core_vsqrt2,%function",
        "pfe_core_vsqrt2:",
        "vsqrt.f32 s0, s0",
        "vsqrt.f32 s1, s1",
        "bx lr",
        ".size pfe_core_vsqrt2, . - pfe_core_vsqrt2",
        ".popsection",
    );

    /// Two f32 (returned in s0–s1, as [`Three`]).
    #[repr(C)]
    struct Two(f32, f32);

    /// Three f32 (AAPCS-VFP returns a homogeneous aggregate of up to four in s0–s3).
    #[repr(C)]
    struct Three(f32, f32, f32);

    extern "C" {
        fn pfe_core_vsqrt(x: f32) -> f32;
        fn pfe_core_vsqrt3(a: f32, b: f32, c: f32) -> Three;
        fn pfe_core_vsqrt2(a: f32, b: f32) -> Two;
    }

    #[inline]
    pub(super) fn sqrt2(a: f32, b: f32) -> [f32; 2] {
        // SAFETY: `pfe_core_vsqrt2` (above) executes two FPU instructions on s0–s1 and
        // returns; it reads and writes no memory and follows the C ABI the declaration names
        // (arguments in s0–s1, the aggregate of two f32 returned in s0–s1).
        let Two(x, y) = unsafe { pfe_core_vsqrt2(a, b) };
        [x, y]
    }

    #[inline]
    pub(super) fn sqrt3(a: f32, b: f32, c: f32) -> [f32; 3] {
        // SAFETY: `pfe_core_vsqrt3` (above) executes three FPU instructions on s0–s2 and
        // returns; it reads and writes no memory and follows the C ABI the declaration names
        // (arguments in s0–s2, the aggregate of three f32 returned in s0–s2).
        let Three(x, y, z) = unsafe { pfe_core_vsqrt3(a, b, c) };
        [x, y, z]
    }

    #[inline]
    pub(super) fn sqrt(x: f32) -> f32 {
        // SAFETY: `pfe_core_vsqrt` (above) executes one FPU instruction on s0 and returns; it
        // reads and writes no memory and follows the C ABI the declaration names.
        unsafe { pfe_core_vsqrt(x) }
    }
}

/// True when `x` is neither infinite nor NaN. `x − x` is exactly 0 for every finite `x` and
/// NaN otherwise: two FPU instructions, where `f32::is_finite` becomes a dozen integer ones
/// on thumbv7em (the hot loops call this once or twice per point).
#[inline]
#[allow(clippy::eq_op)] // x − x is the point: 0 or NaN.
pub(crate) fn finite(x: f32) -> bool {
    x - x == 0.0
}

/// True when every value is finite: `v · 0` is ±0 for a finite `v` and NaN otherwise, so
/// their sum is 0 exactly when all are (one multiply-add a value, no overflow).
#[inline]
pub(crate) fn all_finite(values: &[f32]) -> bool {
    values.iter().fold(0.0f32, |acc, v| acc + v * 0.0) == 0.0
}

/// Absolute value without std: the sign bit cleared (LLVM makes it one `vabs.f32`, where a
/// comparison and a branch take five instructions on thumbv7em).
#[inline]
pub(crate) fn abs(x: f32) -> f32 {
    f32::from_bits(x.to_bits() & 0x7fff_ffff)
}

/// `x` rounded to the nearest whole number, halfway cases away from zero (libm's `roundf`,
/// std's `f32::round`).
#[inline]
pub(crate) fn round(x: f32) -> f32 {
    libm::roundf(x)
}

/// Hypotenuse.
pub(crate) fn hypot(x: f32, y: f32) -> f32 {
    sqrt(x * x + y * y)
}

#[cfg(test)]
mod tests {
    extern crate std;

    #[test]
    fn sin_cos_f32_is_within_2e7_of_exact() -> Result<(), f32> {
        use core::f32::consts::{FRAC_PI_2, FRAC_PI_4};
        let mut worst = 0.0f64;
        let mut x = -1.0e4f32;
        while x <= 9_998.0 {
            for d in [0.0f32, 1e-3, 0.37, FRAC_PI_4, FRAC_PI_2] {
                let v = x + d;
                let (s, c) = super::sin_cos_f32(v).ok_or(v)?;
                let e = f64::from(v);
                worst = worst
                    .max((f64::from(s) - e.sin()).abs())
                    .max((f64::from(c) - e.cos()).abs());
            }
            x += 0.731;
        }
        // Multiples of π/2, where the reduction cancels most.
        for k in -6000..=6000 {
            let v = (f64::from(k) * core::f64::consts::FRAC_PI_2) as f32;
            let (s, c) = super::sin_cos_f32(v).ok_or(v)?;
            let e = f64::from(v);
            worst = worst
                .max((f64::from(s) - e.sin()).abs())
                .max((f64::from(c) - e.cos()).abs());
        }
        assert!(worst < 2e-7, "worst error {worst:e}");
        // Tiny angles keep their relative accuracy: sin x = x.
        assert_eq!(super::sin_cos_f32(1e-20), Some((1e-20, 1.0)));
        assert!(super::sin_cos_f32(f32::NAN).is_none());
        assert!(super::sin_cos_f32(f32::INFINITY).is_none());
        assert!(super::sin_cos_f32(2.0e4).is_none());
        Ok(())
    }

    /// [`super::sin_cos_large`] against libm's `sinf` and `cosf`, bit for bit, on the f32
    /// from 10⁴ (where [`super::sin_cos_f32`] hands over) to the largest, both signs, every
    /// `step`th.
    fn sin_cos_large_is_libm(step: u32) {
        let sign_runs: std::vec::Vec<_> = [0u32, 0x8000_0000]
            .into_iter()
            .map(|sign| {
                std::thread::spawn(move || {
                    let mut b = 1.0e4f32.to_bits() + 1;
                    let mut differ = std::vec::Vec::new();
                    while b <= f32::MAX.to_bits() {
                        let x = f32::from_bits(b | sign);
                        let (s, c) = super::sin_cos_large(x);
                        if (s.to_bits(), c.to_bits())
                            != (libm::sinf(x).to_bits(), libm::cosf(x).to_bits())
                        {
                            differ.push(x);
                        }
                        b = match b.checked_add(step) {
                            Some(next) => next,
                            None => break,
                        };
                    }
                    differ
                })
            })
            .collect();
        for run in sign_runs {
            let differ = run.join().unwrap_or_default();
            assert!(
                differ.is_empty(),
                "{} differ: {:?}",
                differ.len(),
                &differ[..differ.len().min(8)]
            );
        }
    }

    #[test]
    fn sin_cos_large_is_libm_on_every_1021st_f32() {
        sin_cos_large_is_libm(1021);
        for x in [
            1.096_517e10,
            -1.205_543_3e13,
            1.088_557_2e36,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            1.0e4,
            10_000.001,
            f32::MAX,
            f32::MIN,
        ] {
            let (s, c) = super::sin_cos_large(x);
            if x.is_finite() {
                assert_eq!(
                    (s.to_bits(), c.to_bits()),
                    (libm::sinf(x).to_bits(), libm::cosf(x).to_bits()),
                    "{x}"
                );
            } else {
                assert!(s.is_nan() && c.is_nan(), "{x}");
            }
        }
        // Through `sin_cos`: the f32 kernel up to 10⁴, libm's bits beyond.
        for x in [1.0e4f32, 10_000.001, 3.0e5, -7.7e8, 1.0e30] {
            let (s, c) = super::sin_cos(x);
            if x.abs() > 1.0e4 {
                assert_eq!(
                    (s.to_bits(), c.to_bits()),
                    (libm::sinf(x).to_bits(), libm::cosf(x).to_bits()),
                    "{x}"
                );
            } else {
                assert!((f64::from(s) - f64::from(x).sin()).abs() < 2e-7, "{x}");
            }
        }
    }

    /// Every f32 beyond 10⁴: about 1.9·10⁹ arguments, 15 minutes on two threads in release
    /// (`cargo test --release -p pfe-core --lib sin_cos_large_is_libm_on_every_f32 -- --ignored`).
    #[test]
    #[ignore]
    fn sin_cos_large_is_libm_on_every_f32() {
        sin_cos_large_is_libm(1);
    }

    #[test]
    fn finite_agrees_with_the_standard_test() {
        let specials = [
            0.0f32,
            -0.0,
            1.0,
            -1.0,
            f32::MIN_POSITIVE,
            1e-45,
            -1e-45,
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
        ];
        for x in specials {
            assert_eq!(super::finite(x), x.is_finite(), "{x}");
            assert_eq!(super::all_finite(&[1.0, x, -2.5]), x.is_finite(), "{x}");
        }
        let mut bits = 0u32;
        loop {
            let x = f32::from_bits(bits);
            assert_eq!(super::finite(x), x.is_finite(), "{bits:#x}");
            assert_eq!(
                super::all_finite(&[f32::MAX, x, f32::MIN]),
                x.is_finite(),
                "{bits:#x}"
            );
            match bits.checked_add(0x0001_0003) {
                Some(b) => bits = b,
                None => break,
            }
        }
    }

    #[test]
    fn sqrt_is_correctly_rounded_everywhere() {
        let mut x = 1e-38f32;
        while x < 1e38 {
            for k in [1.0f32, 1.3, 1.7, 2.9, 7.1] {
                let v = x * k;
                let exact = (f64::from(v)).sqrt() as f32;
                let got = super::sqrt(v);
                assert_eq!(got.to_bits(), exact.to_bits(), "sqrt({v})");
            }
            x *= 3.7;
        }
        assert_eq!(super::sqrt(0.0), 0.0);
        assert!(super::sqrt(-1.0).is_nan() && super::sqrt(f32::NAN).is_nan());
        assert_eq!(super::sqrt(f32::INFINITY), f32::INFINITY);
    }

    /// Each of the three (and two) roots is the correctly rounded one, whichever place it
    /// takes: normal and subnormal values, zeros, negatives, NaN and infinity.
    #[test]
    fn sqrt3_and_sqrt2_are_correctly_rounded_roots() {
        let exact = |v: f32| (f64::from(v)).sqrt() as f32;
        let bits = |r: [f32; 3]| r.map(f32::to_bits);
        let mut values = std::vec![0.0f32, -0.0, 1e-45, 3e-39, 2.0, 1e38, f32::MAX];
        let mut x = 1e-30f32;
        while x < 1e30 {
            values.extend([x, x * 1.3, x * 2.9]);
            x *= 7.3;
        }
        for (i, &a) in values.iter().enumerate() {
            let (b, c) = (
                values[(i * 7 + 3) % values.len()],
                values[(i * 13 + 5) % values.len()],
            );
            assert_eq!(
                bits(super::sqrt3(a, b, c)),
                bits([exact(a), exact(b), exact(c)]),
                "sqrt3({a}, {b}, {c})"
            );
        }
        for odd in [-1.0, f32::NAN, f32::NEG_INFINITY] {
            for place in 0..3 {
                let mut v = [4.0f32, 9.0, 16.0];
                v[place] = odd;
                let [a, b, c] = v;
                let r = super::sqrt3(a, b, c);
                let want = v.map(|x| {
                    if x == odd || x.is_nan() {
                        f32::NAN
                    } else {
                        exact(x)
                    }
                });
                for (got, want) in r.iter().zip(want) {
                    assert!(got.to_bits() == want.to_bits() || got.is_nan() && want.is_nan());
                }
            }
        }
        assert_eq!(
            super::sqrt3(f32::INFINITY, 0.0, 1.0),
            [f32::INFINITY, 0.0, 1.0]
        );
        for (i, &a) in values.iter().enumerate() {
            let b = values[(i * 11 + 2) % values.len()];
            assert_eq!(
                super::sqrt2(a, b).map(f32::to_bits),
                [exact(a), exact(b)].map(f32::to_bits),
                "sqrt2({a}, {b})"
            );
        }
        let [x, y] = super::sqrt2(f32::NAN, -4.0);
        assert!(x.is_nan() && y.is_nan());
        assert_eq!(super::sqrt2(f32::INFINITY, 9.0), [f32::INFINITY, 3.0]);
    }
}
