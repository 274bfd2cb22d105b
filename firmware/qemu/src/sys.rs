//! Semihosting (QEMU: `-semihosting-config enable=on,target=native`): exit codes, command
//! line arguments, a statistics line on stderr, and the stack high-water mark.

/// Exit code of a normal end.
pub const EXIT_OK: i32 = 0;
/// Exit code after a panic.
pub const EXIT_PANIC: i32 = 101;
/// Exit code after a hard fault.
pub const EXIT_FAULT: i32 = 102;
/// Exit code when the scanner link failed for good.
pub const EXIT_LINK: i32 = 3;
/// Exit code when the output link failed.
pub const EXIT_OUTPUT: i32 = 4;
/// Exit code for bad arguments or missing built-in data.
pub const EXIT_USAGE: i32 = 2;

/// Ends the program (QEMU exits with `code`, via SYS_EXIT_EXTENDED).
pub fn exit(code: i32) -> ! {
    semihosting::process::exit(code)
}

/// Applies `f` to the `i`-th argument after the program name (QEMU:
/// `-semihosting-config enable=on,target=native,arg=prog,arg=10`).
fn with_arg<R>(i: usize, f: impl FnOnce(&str) -> Option<R>) -> Option<R> {
    let args = semihosting::experimental::env::args::<128>().ok()?;
    let mut it = &args;
    let s = it.nth(1 + i)?.ok()?;
    f(s)
}

/// The `i`-th argument after the program name, parsed as a number.
pub fn arg_u32(i: usize) -> Option<u32> {
    with_arg(i, |s| s.parse().ok())
}

/// The `i`-th argument after the program name equals `word`.
pub fn arg_is(i: usize, word: &str) -> bool {
    with_arg(i, |s| (s == word).then_some(())).is_some()
}

/// Writes `prefix` and ` key=value` for each of `stats` as one line to semihosting stderr
/// (QEMU's stderr; defmt has stdout), e.g. `rx: ring_full=0 peak=731`. No `core::fmt`.
pub fn eprint_stats(prefix: &str, stats: &[(&str, u32)]) {
    use semihosting::io::Write as _;
    let Ok(mut err) = semihosting::io::stderr() else {
        return;
    };
    let mut line = [0u8; 256];
    let mut n = 0;
    let mut put = |bytes: &[u8]| {
        for &b in bytes {
            if let Some(slot) = line.get_mut(n) {
                *slot = b;
                n += 1;
            }
        }
    };
    put(prefix.as_bytes());
    for (key, value) in stats {
        put(b" ");
        put(key.as_bytes());
        put(b"=");
        let mut digits = [0u8; 10];
        let mut v = *value;
        let mut k = digits.len();
        loop {
            k -= 1;
            if let Some(d) = digits.get_mut(k) {
                *d = b'0' + (v % 10) as u8;
            }
            v /= 10;
            if v == 0 || k == 0 {
                break;
            }
        }
        put(digits.get(k..).unwrap_or(&[]));
    }
    put(b"\n");
    let _ = err.write_all(line.get(..n).unwrap_or(&[]));
}

/// Bytes of stack ever used (from cortex-m-rt's `paint-stack` fill value) and the stack size.
pub fn stack_usage() -> (u32, u32) {
    extern "C" {
        static _stack_start: u32;
        static _stack_end: u32;
    }
    #[allow(unsafe_code)]
    // SAFETY: the linker symbols' addresses bound the stack region, which is RAM; reads of
    // painted words below the live stack pointer race with nothing (single core, no DMA).
    unsafe {
        let top = core::ptr::addr_of!(_stack_start) as usize;
        let bottom = core::ptr::addr_of!(_stack_end) as usize;
        let mut p = bottom;
        while p < top && core::ptr::read_volatile(p as *const u32) == cortex_m_rt::STACK_PAINT_VALUE
        {
            p += 4;
        }
        ((top - p) as u32, (top - bottom) as u32)
    }
}
