//! The sweeps' dots of a contact's three rows of y along its path (pgs.rs,
//! subspace.rs, wff.rs): each row's sum the scalar loop's, the same
//! products and sums in the same order, rows 0 and 1 side by side in two
//! SSE2 lanes (x86_64) and row 2 alone.

use super::kernels::at_path_len;

/// Σₜ yᵢₜ x[pₜ] for a contact's three rows of y (`ys`, `Rows::y`), each a
/// sum from 0 in path order. ([`dot3_from`] from +0: the same sums, +0 + a
/// = a for every a.)
///
/// # Safety
/// Every index of `p` is < `x.len()` (a row's path: dof indices < nv).
#[inline(always)]
pub(super) unsafe fn dot3(ys: [&[f64]; 3], p: &[usize], x: &[f64]) -> [f64; 3] {
    // SAFETY: the caller's
    unsafe { dot3_from([0.0; 3], ys, p, x) }
}

/// s0ᵢ + Σₜ yᵢₜ x[pₜ] for a contact's three rows (as [`dot3`], each sum
/// started from its `s0` instead of 0: ((s0 + y₀x) + y₁x) + …, the scalar
/// loop `u += y x` from `u = s0`). A free body's path (6 dofs: a ground
/// contact's) and two free bodies' (12: a pair's) run a loop of that fixed
/// length, unrolled whole (no loop bookkeeping): the same sums in the same
/// order.
///
/// # Safety
/// Every index of `p` is < `x.len()` (a row's path: dof indices < nv).
#[inline(always)]
pub(super) unsafe fn dot3_from(s0: [f64; 3], ys: [&[f64]; 3], p: &[usize], x: &[f64]) -> [f64; 3] {
    let [y0, y1, y2] = ys;
    let n = p.len().min(y0.len()).min(y1.len()).min(y2.len());
    // SAFETY: the caller's
    at_path_len!(n; y0, y1, y2, p => unsafe { dot3_run(s0, [y0, y1, y2], p, x, n) })
}

/// [`dot3`] of the contact whose three rows of y begin at `y[o..]`, `st`
/// apart (one pointer and the stride, not three pointers: the sweeps'
/// registers), each the same sum.
///
/// # Safety
/// `o + 2·st + p.len() ≤ y.len()`, and every index of `p` is < `x.len()`.
#[inline(always)]
pub(super) unsafe fn dot3_at(y: &[f64], o: usize, st: usize, p: &[usize], x: &[f64]) -> [f64; 3] {
    let n = p.len();
    // SAFETY: the caller's (rows o.., o + st.., o + 2·st.., n entries each)
    let (y0, y1, y2) = unsafe {
        let b = y.as_ptr().add(o);
        (
            std::slice::from_raw_parts(b, n),
            std::slice::from_raw_parts(b.add(st), n),
            std::slice::from_raw_parts(b.add(2 * st), n),
        )
    };
    // SAFETY: the caller's
    unsafe { dot3([y0, y1, y2], p, x) }
}

/// [`dot3_from`]'s loop over the first `n` slots.
///
/// # Safety
/// n ≤ every slice's length, and `p[..n]`'s indices are < `x.len()`.
#[inline(always)]
unsafe fn dot3_run(s0: [f64; 3], ys: [&[f64]; 3], p: &[usize], x: &[f64], n: usize) -> [f64; 3] {
    let [y0, y1, y2] = ys;
    debug_assert!(n <= p.len().min(y0.len()).min(y1.len()).min(y2.len()));
    debug_assert!(p[..n].iter().all(|&k| k < x.len()));
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::*;
        let mut s = s0;
        // SAFETY: SSE2 is part of x86_64; t < n ≤ every slice's length, and
        // every p[t] < x.len() (the caller's)
        unsafe {
            let mut a01 = _mm_loadu_pd(s.as_ptr());
            let mut a2 = s[2];
            for t in 0..n {
                let xk = *x.get_unchecked(*p.get_unchecked(t));
                let y01 = _mm_loadh_pd(_mm_load_sd(y0.as_ptr().add(t)), y1.as_ptr().add(t));
                a01 = _mm_add_pd(a01, _mm_mul_pd(y01, _mm_set1_pd(xk)));
                a2 += *y2.get_unchecked(t) * xk;
            }
            _mm_storeu_pd(s.as_mut_ptr(), a01);
            s[2] = a2;
        }
        s
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let mut s = s0;
        for t in 0..n {
            let xk = x[p[t]];
            s[0] += y0[t] * xk;
            s[1] += y1[t] * xk;
            s[2] += y2[t] * xk;
        }
        s
    }
}
