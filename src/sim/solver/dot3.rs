//! The sweeps' dots of a contact's three rows of y along its path (pgs.rs,
//! subspace.rs, wff.rs): each row's sum the scalar loop's, the same
//! products and sums in the same order, rows 0 and 1 side by side in two
//! SSE2 lanes (x86_64) and row 2 alone.

use super::kernels::{Dofs, Path, Runs};

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
/// loop `u += y x` from `u = s0`), along the [`Path`] of `p`: a free body's
/// path (6 dofs: a ground contact's) and two free bodies' (12: a pair's)
/// as [`Runs`], a loop of that fixed length unrolled whole reading x as
/// slices (no index loads); the same sums in the same order.
///
/// # Safety
/// Each of `ys` is at least `p`'s length, and every index of `p` is
/// < `x.len()` (a row's path: dof indices < nv).
#[inline(always)]
pub(super) unsafe fn dot3_from(s0: [f64; 3], ys: [&[f64]; 3], p: &[usize], x: &[f64]) -> [f64; 3] {
    debug_assert!(ys.iter().all(|y| y.len() >= p.len()));
    // SAFETY: the caller's
    unsafe { dot3_path(s0, ys.map(|y| y.as_ptr()), Path::of(p), x) }
}

/// [`dot3_from`] over a [`Path`], the rows' entries at `ys`.
///
/// # Safety
/// Each of `ys` points at the path's length of entries; every dof of the
/// path is < `x.len()`.
#[inline(always)]
unsafe fn dot3_path(s0: [f64; 3], ys: [*const f64; 3], p: Path, x: &[f64]) -> [f64; 3] {
    // SAFETY: n entries at each of ys (the caller's)
    let cut = |n: usize| ys.map(|y| unsafe { std::slice::from_raw_parts(y, n) });
    // SAFETY: the caller's
    unsafe {
        match p {
            Path::One(d) => dot3_run::<Runs<1>>(s0, cut(6), d, x, 6),
            Path::Two(d) => dot3_run::<Runs<2>>(s0, cut(12), d, x, 12),
            Path::Any(q) => dot3_run(s0, cut(q.len()), q, x, q.len()),
        }
    }
}

/// [`dot3`] of the contact whose three rows of y begin at `y[o..]`, `st`
/// apart (one pointer and the stride, not three pointers: the sweeps'
/// registers), along its path `p` ([`Path::of`], the one its update takes),
/// each the same sum.
///
/// # Safety
/// `o + 2·st + p's length ≤ y.len()`, and every dof of `p` is < `x.len()`.
#[inline(always)]
pub(super) unsafe fn dot3_at(y: &[f64], o: usize, st: usize, p: Path, x: &[f64]) -> [f64; 3] {
    // SAFETY: the caller's (rows o.., o + st.., o + 2·st.., the path's
    // length each)
    unsafe {
        let b = y.as_ptr().add(o);
        dot3_path([0.0; 3], [b, b.add(st), b.add(2 * st)], p, x)
    }
}

/// [`dot3_from`]'s loop over the first `n` slots of the path's dofs `p`
/// (gathered, or [`Runs`]: read at their known offsets).
///
/// # Safety
/// n ≤ every slice's length and the path's, and its dofs are < `x.len()`.
#[inline(always)]
unsafe fn dot3_run<D: Dofs>(s0: [f64; 3], ys: [&[f64]; 3], p: D, x: &[f64], n: usize) -> [f64; 3] {
    let [y0, y1, y2] = ys;
    debug_assert!(n <= y0.len().min(y1.len()).min(y2.len()));
    // SAFETY: t < n ≤ the path's length (the caller's)
    debug_assert!((0..n).all(|t| unsafe { p.at(t) } < x.len()));
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
                let xk = *x.get_unchecked(p.at(t));
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
            // SAFETY: t < n ≤ the path's length (the caller's)
            let xk = x[unsafe { p.at(t) }];
            s[0] += y0[t] * xk;
            s[1] += y1[t] * xk;
            s[2] += y2[t] * xk;
        }
        s
    }
}
