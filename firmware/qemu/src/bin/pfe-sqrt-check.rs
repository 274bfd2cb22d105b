//! pfe-core's square root as shipped for hard-float Arm (the FPU's `vsqrt.f32`) against libm's
//! `sqrtf` (correctly rounded, in software) on mps2-an386 under QEMU: 0, −0, subnormals,
//! normals of every exponent (a stride through all bit patterns), ±inf and NaN. The shipped
//! root is reached through `Prediction::sigma_factor`, `√var_factor`. Exits 0 when every
//! result has libm's bits (any NaN for NaN), else 10 + the number of differences (at most
//! 110). Run by `host-tests/tests/qemu_sqrt.rs`.
#![cfg_attr(target_os = "none", no_std, no_main)]
#![deny(clippy::indexing_slicing)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("pfe-sqrt-check runs on thumbv7em-none-eabihf under QEMU: cargo test -p host-tests --test qemu_sqrt");
}

#[cfg(target_os = "none")]
mod fw {
    use cortex_m_rt::entry;
    use defmt_semihosting as _;
    use firmware_qemu::sys;
    use pfe_core::predict::predict;
    use pfe_core::Point;

    /// Every 16 385th bit pattern (262 144 inputs, all exponents, both signs).
    const STRIDE: u32 = 0x4001;

    const SPECIALS: [f32; 16] = [
        0.0,
        -0.0,
        1e-45,
        -1e-45,
        f32::from_bits(0x007F_FFFF),
        f32::MIN_POSITIVE,
        1.0,
        2.0,
        0.25,
        1.0e30,
        f32::MAX,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        -f32::NAN,
        -1.0,
    ];

    #[entry]
    fn main() -> ! {
        let w = [
            Point::new(1000.0, 0.0),
            Point::new(1000.0, 100.0),
            Point::new(1000.0, 200.0),
        ];
        let Some(mut p) = predict(&w, Point::new(1000.0, 300.0), Point::new(0.0, 0.0)) else {
            sys::exit(sys::EXIT_USAGE)
        };
        let mut bad = 0u32;
        let mut check = |x: f32| {
            p.var_factor = core::hint::black_box(x);
            let got = p.sigma_factor();
            let want = libm::sqrtf(x);
            if got.to_bits() != want.to_bits() && !(got.is_nan() && want.is_nan()) {
                bad += 1;
            }
        };
        for x in SPECIALS {
            check(x);
        }
        let mut bits = 0u32;
        loop {
            check(f32::from_bits(bits));
            match bits.checked_add(STRIDE) {
                Some(b) => bits = b,
                None => break,
            }
        }
        sys::exit(if bad == 0 {
            sys::EXIT_OK
        } else {
            10 + bad.min(100) as i32
        })
    }
}
