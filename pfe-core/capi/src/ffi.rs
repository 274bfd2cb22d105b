//! The C functions: the only `unsafe` of the crate. Each turns the caller's pointers into
//! references or slices after checking what can be checked (NULL, alignment, lengths, the
//! extractor's set-up mark) and hands them to the safe code of `crate::convert`.
//!
//! What cannot be checked is the caller's part of the contract, stated in each function's
//! `# Safety`: a non-NULL pointer points to memory of its type (or `n` elements) that stays
//! valid for the call, and no other call uses the same extractor at the same time.

#![allow(unsafe_code)]
#![deny(unsafe_op_in_unsafe_fn)]

use core::ffi::c_char;
use core::mem::{align_of, size_of};
use core::ptr;

use pfe_core::{Config, Scan, ScanGeometry};

use crate::convert::{self, State, MAGIC};
use crate::types::pfe_status::{self, *};
use crate::types::*;

/// `Ok(())` or the status, as the functions' early returns.
type Result<T> = core::result::Result<T, pfe_status>;

/// The status of `r`.
fn status(r: Result<pfe_status>) -> pfe_status {
    r.unwrap_or_else(|e| e)
}

/// `p` when it is non-NULL and aligned for `T`.
fn check<T>(p: *const T) -> Result<*const T> {
    if p.is_null() {
        Err(PFE_ERR_NULL)
    } else if !p.is_aligned() {
        Err(PFE_ERR_MISALIGNED)
    } else {
        Ok(p)
    }
}

/// The state in the extractor memory `ex`, when it is non-NULL, aligned and set up.
///
/// # Safety
/// `ex`, when non-NULL, points to `PFE_EXTRACTOR_SIZE` bytes the caller owns for the call's
/// duration, which no one else accesses meanwhile, and which are zero or were set up by
/// [`pfe_extractor_init`].
unsafe fn state<'a>(ex: *const pfe_extractor) -> Result<&'a State> {
    let p = check(ex.cast::<State>())?;
    // SAFETY: `p` is non-NULL and aligned; it points to at least size_of::<State>() bytes
    // (the caller's contract; PFE_EXTRACTOR_SIZE is checked to be at least that). The mark
    // is a plain u32 at offset 0 (State is repr(C)): any bytes are a value.
    let magic = unsafe { ptr::addr_of!((*p).magic).read() };
    if magic != MAGIC {
        return Err(PFE_ERR_NOT_INITIALIZED);
    }
    // SAFETY: the mark is only written by `pfe_extractor_init`, after a whole `State`:
    // these bytes are one.
    Ok(unsafe { &*p })
}

/// [`state`], mutable.
///
/// # Safety
/// As [`state`].
unsafe fn state_mut<'a>(ex: *mut pfe_extractor) -> Result<&'a mut State> {
    // SAFETY: as `state` (which checks `ex`); the caller's exclusive use of `ex` for the call
    // makes the reference unique.
    unsafe {
        state(ex)?;
        Ok(&mut *ex.cast::<State>())
    }
}

/// `*p` as a reference, when `p` is non-NULL and aligned.
///
/// # Safety
/// `p`, when non-NULL, points to a `T` that stays valid for the call.
unsafe fn input<'a, T>(p: *const T) -> Result<&'a T> {
    let p = check(p)?;
    // SAFETY: non-NULL and aligned; valid by the caller's contract. `T` is one of the C input
    // types, whose fields are integers and floats: any bytes are a value.
    Ok(unsafe { &*p })
}

/// Writes `v` to `out`, when `out` is non-NULL and aligned.
///
/// # Safety
/// `out`, when non-NULL, points to memory for a `T` the caller owns for the call.
unsafe fn output<T>(out: *mut T, v: T) -> pfe_status {
    match check(out.cast_const()) {
        // SAFETY: non-NULL and aligned; writable by the caller's contract. `T` is Copy (plain
        // C data): nothing is dropped.
        Ok(_) => unsafe {
            out.write(v);
            PFE_OK
        },
        Err(e) => e,
    }
}

/// `n` elements at `p` as a slice (`p` may be NULL when `n` is 0); `n` is at most
/// `PFE_MAX_READINGS`, checked before.
///
/// # Safety
/// `p`, when non-NULL, points to `n` initialised elements that stay valid and unchanged for
/// the call.
unsafe fn readings<'a, T>(p: *const T, n: usize) -> Result<&'a [T]> {
    if n == 0 {
        return Ok(&[]);
    }
    let p = check(p)?;
    // SAFETY: non-NULL, aligned, `n` elements by the caller's contract; n ≤ PFE_MAX_READINGS
    // so the byte length is far below isize::MAX.
    Ok(unsafe { core::slice::from_raw_parts(p, n) })
}

/// Bytes the extractor uses on this target (at most `PFE_EXTRACTOR_SIZE`).
#[no_mangle]
pub extern "C" fn pfe_extractor_size() -> usize {
    size_of::<State>()
}

/// Alignment the extractor needs on this target (at most `PFE_EXTRACTOR_ALIGN`).
#[no_mangle]
pub extern "C" fn pfe_extractor_align() -> usize {
    align_of::<State>()
}

/// Sets up an extractor in `mem`, `size` bytes (at least `pfe_extractor_size()`, aligned to
/// `pfe_extractor_align()`): declare `static pfe_extractor mem;` and pass `&mem, sizeof mem`.
/// Nothing is allocated. May be called again to reset it.
///
/// Errors: `PFE_ERR_NULL`, `PFE_ERR_MISALIGNED`, `PFE_ERR_BUFFER_TOO_SMALL`.
///
/// # Safety
/// `mem`, when non-NULL, points to `size` writable bytes the caller owns, used by no other
/// call meanwhile.
#[no_mangle]
pub unsafe extern "C" fn pfe_extractor_init(mem: *mut pfe_extractor, size: usize) -> pfe_status {
    let p = mem.cast::<State>();
    if let Err(e) = check(p.cast_const()) {
        return e;
    }
    if size < size_of::<State>() {
        return PFE_ERR_BUFFER_TOO_SMALL;
    }
    // SAFETY: non-NULL, aligned, at least size_of::<State>() writable bytes (checked, and the
    // caller's contract); whatever was there is plain bytes, nothing to drop. Zero bytes are
    // `State::new()` but for its mark: pfe-core's `Extractor::new()` is all zero bytes (so
    // that a `static` extractor goes to .bss; tests/in_place.rs checks it). Zeroing in place
    // rather than writing `State::new()` keeps the 31 KiB value off the stack (the compiler
    // builds it there first, more than many a microcontroller's stack).
    unsafe {
        p.write_bytes(0, 1);
        ptr::addr_of_mut!((*p).magic).write(MAGIC);
    }
    PFE_OK
}

/// Fills `out` with pfe's default mode (the best measured configuration; `scrutiny` on when
/// the library is built with it, which is the default).
///
/// # Safety
/// `out`, when non-NULL, points to a writable `pfe_config`.
#[no_mangle]
pub unsafe extern "C" fn pfe_config_default(out: *mut pfe_config) -> pfe_status {
    let c = Config::default_config().with_scrutiny(cfg!(feature = "scrutiny"));
    // SAFETY: the caller's contract, checked by `output`.
    unsafe { output(out, convert::config_to_c(&c)) }
}

/// Fills `out` with the paper's method, faithfully (Np 3, d_0 50 mm, λ 2, check step,
/// d_f 20 mm, Kåsa fit).
///
/// # Safety
/// `out`, when non-NULL, points to a writable `pfe_config`.
#[no_mangle]
pub unsafe extern "C" fn pfe_config_paper(out: *mut pfe_config) -> pfe_status {
    // SAFETY: the caller's contract, checked by `output`.
    unsafe { output(out, convert::config_to_c(&Config::paper())) }
}

/// `PFE_OK` when `config` is usable, else `PFE_ERR_INVALID_CONFIG` (or `PFE_ERR_NULL`).
///
/// # Safety
/// `config`, when non-NULL, points to a `pfe_config`.
#[no_mangle]
pub unsafe extern "C" fn pfe_config_check(config: *const pfe_config) -> pfe_status {
    // SAFETY: the caller's contract, checked by `input`.
    let r = unsafe { input(config) }.and_then(convert::config_from_c);
    status(r.map(|_| PFE_OK))
}

/// Fills `out` with the options of a plain scan: one sweep, the input's own quantum, no
/// motion (what NULL options mean).
///
/// # Safety
/// `out`, when non-NULL, points to a writable `pfe_scan_options`.
#[no_mangle]
pub unsafe extern "C" fn pfe_scan_options_default(out: *mut pfe_scan_options) -> pfe_status {
    // SAFETY: the caller's contract, checked by `output`.
    unsafe { output(out, convert::DEFAULT_OPTIONS) }
}

/// Fills `out` with the geometry of a SICK LMS200 variant (field of view and resolution in
/// degrees, centred on x, 8 m mode: r_max 8000 mm).
///
/// Errors: `PFE_ERR_NULL`, `PFE_ERR_INVALID_GEOMETRY` (a field or resolution that is not
/// finite, or a resolution of 0).
///
/// # Safety
/// `out`, when non-NULL, points to a writable `pfe_geometry`.
#[no_mangle]
pub unsafe extern "C" fn pfe_geometry_lms200(
    field_deg: f32,
    resolution_deg: f32,
    out: *mut pfe_geometry,
) -> pfe_status {
    let g = ScanGeometry::lms200(field_deg, resolution_deg);
    if !g.is_valid() {
        return PFE_ERR_INVALID_GEOMETRY;
    }
    // SAFETY: the caller's contract, checked by `output`.
    unsafe { output(out, convert::geometry_to_c(&g)) }
}

/// Extracts the features of a scan of `n` ranges in mm (NaN, ±inf, ≤ 0 and > r_max are no
/// return). `options` may be NULL (`pfe_scan_options_default`).
///
/// Returns `PFE_OK`, or `PFE_ERR_FEATURE_CAPACITY` with the first `PFE_MAX_FEATURES`
/// features readable, or an error with no features: `PFE_ERR_NULL`, `PFE_ERR_MISALIGNED`,
/// `PFE_ERR_NOT_INITIALIZED`, `PFE_ERR_TOO_MANY_READINGS`, `PFE_ERR_INVALID_GEOMETRY`,
/// `PFE_ERR_INVALID_CONFIG`, `PFE_ERR_INVALID_ARGUMENT`.
///
/// # Safety
/// `ex` as for `pfe_extractor_init`; `geometry`, `config` and `options`, when non-NULL, point
/// to their types; `ranges`, when non-NULL, to `n` floats; all unchanged during the call.
#[no_mangle]
pub unsafe extern "C" fn pfe_extract_mm(
    ex: *mut pfe_extractor,
    geometry: *const pfe_geometry,
    ranges: *const f32,
    n: usize,
    config: *const pfe_config,
    options: *const pfe_scan_options,
) -> pfe_status {
    // SAFETY: the caller's contract (checked as far as it can be inside).
    status(unsafe { extract_mm(ex, geometry, ranges, n, config, options) })
}

/// [`pfe_extract_mm`] with early returns.
///
/// # Safety
/// As [`pfe_extract_mm`].
unsafe fn extract_mm(
    ex: *mut pfe_extractor,
    geometry: *const pfe_geometry,
    ranges: *const f32,
    n: usize,
    config: *const pfe_config,
    options: *const pfe_scan_options,
) -> Result<pfe_status> {
    // SAFETY: the caller's contract, checked by `state_mut`.
    let state = unsafe { state_mut(ex) }?;
    state.current = 0;
    // SAFETY: the caller's contract, checked by `inputs`.
    let (g, c, o) = unsafe { inputs(geometry, config, options) }?;
    // SAFETY: the caller's contract, checked by `readings`.
    let ranges = unsafe { readings(ranges, capacity(n)?) }?;
    let scan = convert::with_options(Scan::from_mm(g, ranges), &o)?;
    Ok(state.extract(&scan, &c))
}

/// Extracts the features of a scan of `n` raw LMS range codes in the 8 m / 80 m modes
/// (0 and the reserved codes above 8182 are no return), `unit_mm` mm per code (1 in mm mode,
/// 10 in cm mode; also the readings' quantum unless `options` gives one). `options` may be
/// NULL. Returns as `pfe_extract_mm`; a `unit_mm` that is NaN, infinite or ≤ 0 is
/// `PFE_ERR_INVALID_ARGUMENT`.
///
/// # Safety
/// As `pfe_extract_mm`, with `codes`, when non-NULL, pointing to `n` `uint16_t`.
#[no_mangle]
pub unsafe extern "C" fn pfe_extract_lms(
    ex: *mut pfe_extractor,
    geometry: *const pfe_geometry,
    codes: *const u16,
    n: usize,
    unit_mm: f32,
    config: *const pfe_config,
    options: *const pfe_scan_options,
) -> pfe_status {
    // SAFETY: the caller's contract (checked as far as it can be inside).
    status(unsafe { extract_lms(ex, geometry, codes, n, unit_mm, config, options) })
}

/// [`pfe_extract_lms`] with early returns.
///
/// # Safety
/// As [`pfe_extract_lms`].
unsafe fn extract_lms(
    ex: *mut pfe_extractor,
    geometry: *const pfe_geometry,
    codes: *const u16,
    n: usize,
    unit_mm: f32,
    config: *const pfe_config,
    options: *const pfe_scan_options,
) -> Result<pfe_status> {
    // SAFETY: the caller's contract, checked by `state_mut`.
    let state = unsafe { state_mut(ex) }?;
    state.current = 0;
    // SAFETY: the caller's contract, checked by `inputs`.
    let (g, c, o) = unsafe { inputs(geometry, config, options) }?;
    if !convert::unit_ok(unit_mm) {
        return Err(PFE_ERR_INVALID_ARGUMENT);
    }
    // SAFETY: the caller's contract, checked by `readings`.
    let codes = unsafe { readings(codes, capacity(n)?) }?;
    let scan = convert::with_options(Scan::from_lms(g, codes, unit_mm), &o)?;
    Ok(state.extract(&scan, &c))
}

/// `n` when the extractor holds that many readings.
fn capacity(n: usize) -> Result<usize> {
    match n <= PFE_MAX_READINGS {
        true => Ok(n),
        false => Err(PFE_ERR_TOO_MANY_READINGS),
    }
}

/// The geometry, configuration and options of an extraction, converted.
///
/// # Safety
/// As `pfe_extract_mm`'s for these three.
unsafe fn inputs(
    geometry: *const pfe_geometry,
    config: *const pfe_config,
    options: *const pfe_scan_options,
) -> Result<(ScanGeometry, Config, pfe_scan_options)> {
    // SAFETY: the caller's contract, checked by `input`.
    let g = convert::geometry_from_c(unsafe { input(geometry) }?);
    // SAFETY: as above.
    let c = convert::config_from_c(unsafe { input(config) }?)?;
    let o = match options.is_null() {
        true => convert::DEFAULT_OPTIONS,
        // SAFETY: as above.
        false => *unsafe { input(options) }?,
    };
    Ok((g, c, o))
}

/// Features of the last extraction (0 after a refused call), or a negative `pfe_status`
/// (`PFE_ERR_NULL`, `PFE_ERR_MISALIGNED`, `PFE_ERR_NOT_INITIALIZED`).
///
/// # Safety
/// `ex` as for `pfe_extractor_init`.
#[no_mangle]
pub unsafe extern "C" fn pfe_feature_count(ex: *const pfe_extractor) -> i32 {
    // SAFETY: the caller's contract, checked by `state`.
    match unsafe { state(ex) } {
        // At most PFE_MAX_FEATURES.
        Ok(s) => i32::try_from(s.features().len()).unwrap_or(i32::MAX),
        Err(e) => e as i32,
    }
}

/// Copies feature `i` (in scan order) of the last extraction to `out`.
///
/// Errors: `PFE_ERR_NULL`, `PFE_ERR_MISALIGNED`, `PFE_ERR_NOT_INITIALIZED`, `PFE_ERR_INDEX`.
///
/// # Safety
/// `ex` as for `pfe_extractor_init`; `out`, when non-NULL, points to a writable `pfe_feature`.
#[no_mangle]
pub unsafe extern "C" fn pfe_feature_get(
    ex: *const pfe_extractor,
    i: usize,
    out: *mut pfe_feature,
) -> pfe_status {
    // SAFETY: the caller's contract, checked by `state`.
    let f = match unsafe { state(ex) } {
        Ok(s) => s.features().get(i).and_then(convert::feature_to_c),
        Err(e) => return e,
    };
    match f {
        // SAFETY: the caller's contract, checked by `output`.
        Some(f) => unsafe { output(out, f) },
        None if out.is_null() => PFE_ERR_NULL,
        None => PFE_ERR_INDEX,
    }
}

/// Copies the statistics of the last extraction to `out` (zero after a refused call);
/// `dropped` counts the features past `PFE_MAX_FEATURES`.
///
/// # Safety
/// `ex` as for `pfe_extractor_init`; `out`, when non-NULL, points to a writable `pfe_stats`.
#[no_mangle]
pub unsafe extern "C" fn pfe_stats_get(
    ex: *const pfe_extractor,
    out: *mut pfe_stats,
) -> pfe_status {
    // SAFETY: the caller's contract, checked by `state` and `output`.
    unsafe {
        match state(ex) {
            Ok(s) => output(out, s.stats()),
            Err(e) => e,
        }
    }
}

/// The mark points of the last extraction (first and last beam of every segment, increasing):
/// writes up to `cap` of them to `out` and their number to `*count`. With `out` NULL and
/// `cap` 0 it only counts them. Returns `PFE_ERR_BUFFER_TOO_SMALL` when `out` is given and
/// `cap` is less than the number (the first `cap` are written).
///
/// # Safety
/// `ex` as for `pfe_extractor_init`; `out`, when non-NULL, points to `cap` writable
/// `uint16_t`; `count`, when non-NULL, to a writable `size_t`.
#[no_mangle]
pub unsafe extern "C" fn pfe_marks(
    ex: *const pfe_extractor,
    out: *mut u16,
    cap: usize,
    count: *mut usize,
) -> pfe_status {
    // SAFETY: the caller's contract (checked as far as it can be inside).
    status(unsafe { marks(ex, out, cap, count) })
}

/// [`pfe_marks`] with early returns.
///
/// # Safety
/// As [`pfe_marks`].
unsafe fn marks(
    ex: *const pfe_extractor,
    out: *mut u16,
    cap: usize,
    count: *mut usize,
) -> Result<pfe_status> {
    // SAFETY: the caller's contract, checked by `state`.
    let s = unsafe { state(ex) }?;
    check(count.cast_const())?;
    let buf: &mut [u16] = match cap {
        0 => &mut [],
        _ => {
            check(out.cast_const())?;
            // SAFETY: non-NULL, aligned, `cap` writable elements (the caller's contract).
            // Marks are at most PFE_MAX_READINGS: no more of `out` is needed.
            unsafe { core::slice::from_raw_parts_mut(out, cap.min(PFE_MAX_READINGS)) }
        }
    };
    let n = s.marks(buf);
    // SAFETY: checked above; writable by the caller's contract.
    unsafe { count.write(n) };
    // A query (NULL, 0) is answered; otherwise marks that did not fit are an error.
    Ok(match n <= cap || (cap == 0 && out.is_null()) {
        true => PFE_OK,
        false => PFE_ERR_BUFFER_TOO_SMALL,
    })
}

/// A static, NUL-terminated description of a status code (any `int`).
#[no_mangle]
pub extern "C" fn pfe_status_str(status: i32) -> *const c_char {
    convert::status_text(status).as_ptr()
}
