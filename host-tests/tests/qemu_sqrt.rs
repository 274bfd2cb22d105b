//! The square root pfe-core ships for hard-float Arm (`vsqrt.f32`, which the host never runs)
//! checked on the target: `pfe-sqrt-check` under QEMU (mps2-an386, Cortex-M4F) compares it
//! bit for bit with libm's `sqrtf` over 0, −0, subnormals, a stride through every exponent,
//! ±inf and NaN. Skipped (listed) without QEMU or the thumbv7em target; CI has both.

use host_tests::qemu;
use pfe_testkit::skip::{skip, Need};

use std::path::PathBuf;
use std::time::{Duration, Instant};

#[test]
fn arm_sqrt_matches_libm_bit_for_bit() {
    if std::env::var_os("PFE_SKIP_QEMU").is_some() {
        skip(
            "qemu_sqrt",
            "PFE_SKIP_QEMU is set (cargo xtask test --quick)",
            Need::Optional,
        );
        return;
    }
    if !qemu::have("qemu-system-arm") || !qemu::have_target() {
        skip(
            "qemu_sqrt",
            "qemu-system-arm or the thumbv7em-none-eabihf target is missing",
            Need::InCi,
        );
        return;
    }
    let dir = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| qemu::root().join("target"))
        .join("sqrt-firmware");
    let elf = qemu::build_firmware(
        "pfe-sqrt-check",
        &[],
        &[("CARGO_PROFILE_RELEASE_OPT_LEVEL", qemu::FIRMWARE_OPT_LEVEL)],
        &dir,
    )
    .unwrap();
    // The shipped root is the FPU instruction: the ELF contains the function.
    let bytes = std::fs::read(&elf).unwrap();
    assert!(
        bytes.windows(14).any(|w| w == b"pfe_core_vsqrt"),
        "no pfe_core_vsqrt in {}",
        elf.display()
    );
    let mut cmd = qemu::qemu_command(&elf, "null", "null", &[], false);
    let t0 = Instant::now();
    let mut child = cmd.spawn().unwrap();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if t0.elapsed() > Duration::from_secs(300) {
            child.kill().ok();
            panic!("pfe-sqrt-check did not finish in 300 s");
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    assert_eq!(
        status.code(),
        Some(0),
        "pfe-sqrt-check: {status} (10 + n: n results differ from libm's sqrtf)"
    );
}
