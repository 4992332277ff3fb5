//! Cache fetches of memory ahead of its use: one line (`prefetch`: the
//! broad phase's pair table, the pair visit's next items) or a few
//! (`fetch_lines`: the narrow phases' state in heap blocks of its own, a
//! ground shape's record and vertices), fetched a few items ahead of the
//! item being worked.

/// Fetches the cache lines of the `bytes` bytes from `x`'s address into the
/// cache (a hint: it reads nothing into the program and cannot fault,
/// whatever the address).
#[inline(always)]
pub(crate) fn fetch_lines<T: ?Sized>(x: &T, bytes: usize) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        // the lines from the one holding the first byte to the one holding
        // the last: ⌈(p mod 64 + bytes) / 64⌉ from p's line's start
        let p = (x as *const T).cast::<i8>();
        let head = (p as usize) % 64;
        let lines = if bytes == 0 {
            0
        } else {
            (head + bytes).div_ceil(64)
        };
        let line0 = p.wrapping_sub(head);
        for k in 0..lines {
            // SAFETY: a prefetch reads nothing into the program and cannot
            // fault (SSE is part of x86_64); its address is formed with
            // `wrapping_add`, never dereferenced
            unsafe { _mm_prefetch::<_MM_HINT_T0>(line0.wrapping_add(64 * k)) };
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (x, bytes);
}

/// Asks the cache for the line holding `x` (no effect on any result): one
/// line, the broad phase's and the pair visit's fetch ahead.
#[inline(always)]
pub(crate) fn prefetch<T>(x: &T) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        // SAFETY: a prefetch is a hint (it reads nothing into the program
        // and cannot fault); SSE is part of x86_64.
        unsafe { _mm_prefetch::<_MM_HINT_T0>((x as *const T).cast::<i8>()) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = x;
}
