//! # pfe-capi: pfe-core for C
//!
//! pfe-core's extractor, configuration and features behind C functions, built as a static
//! library (`libpfe_capi.a`) with the header `include/pfe.h`, generated from this crate by
//! cbindgen (a test regenerates it and fails when the committed one differs).
//!
//! - The extractor lives in memory the caller provides: a `static pfe_extractor` in C
//!   (`PFE_EXTRACTOR_SIZE` bytes, aligned to `PFE_EXTRACTOR_ALIGN`, in .bss), set up by
//!   [`pfe_extractor_init`]. Nothing is allocated.
//! - Capacities are fixed at build: [`PFE_MAX_READINGS`] (1081) readings and
//!   [`PFE_MAX_FEATURES`] (64) features per scan.
//! - Every error is a return code ([`pfe_status`]: `PFE_OK` = 0, negative errors): NULL or
//!   misaligned pointers, short buffers, an extractor not set up, NaN or out-of-range
//!   arguments and configurations. Nothing panics.
//!
//! The C functions are the only `unsafe` code ([`ffi`]); the conversions and the extractor
//! state are safe code (module `convert`, `#![forbid(unsafe_code)]`).
//!
//! From Rust (the tests do this; C does the same through the header):
//!
//! ```
//! use pfe_capi::*;
//! let mut ex = Box::new(core::mem::MaybeUninit::<pfe_extractor>::zeroed());
//! let (mut g, mut c) = (core::mem::MaybeUninit::uninit(), core::mem::MaybeUninit::uninit());
//! // SAFETY: each pointer is to memory of its type, owned here.
//! unsafe {
//!     assert_eq!(pfe_extractor_init(ex.as_mut_ptr(), PFE_EXTRACTOR_SIZE), pfe_status::PFE_OK);
//!     assert_eq!(pfe_geometry_lms200(180.0, 0.5, g.as_mut_ptr()), pfe_status::PFE_OK);
//!     assert_eq!(pfe_config_default(c.as_mut_ptr()), pfe_status::PFE_OK);
//!     let ranges = [1500.0_f32; 361]; // a round room of radius 1.5 m
//!     let st = pfe_extract_mm(ex.as_mut_ptr(), g.as_ptr(), ranges.as_ptr(), 361, c.as_ptr(),
//!         core::ptr::null());
//!     assert_eq!(st, pfe_status::PFE_OK);
//!     assert_eq!(pfe_feature_count(ex.as_ptr()), 1);
//!     let mut f = core::mem::MaybeUninit::uninit();
//!     assert_eq!(pfe_feature_get(ex.as_ptr(), 0, f.as_mut_ptr()), pfe_status::PFE_OK);
//!     let f = f.assume_init();
//!     assert_eq!(f.kind, pfe_feature_kind::PFE_FEATURE_CIRCLE);
//!     assert!((f.shape.circle.radius - 1500.0).abs() < 0.5);
//! }
//! ```
#![no_std]
#![deny(unsafe_code)]
#![deny(missing_docs)]
// Beyond the workspace lints: no indexing that can panic in the library.
#![deny(clippy::indexing_slicing)]
// The C names, as the header spells them.
#![allow(non_camel_case_types)]

// On a hosted target the static library is linked into a program that has a C runtime: std
// gives it its panic handler (the code below uses `core` only). On bare metal the handler is
// the one below.
#[cfg(not(target_os = "none"))]
extern crate std;

mod convert;
pub mod ffi;
pub mod types;

pub use ffi::*;
pub use types::*;

/// Never called: nothing in pfe-core or here panics (no unwrap, expect, panicking index or
/// arithmetic overflow on any input; their lints are denied). Should it happen anyway, the
/// core stops here rather than return into C with broken state.
#[cfg(target_os = "none")]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo<'_>) -> ! {
    loop {
        core::hint::spin_loop();
    }
}
