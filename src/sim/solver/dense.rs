//! The subspace step's dense LDLᵀ of W_FF (subspace.rs, stress.rs): the
//! operations of [`crate::dynamics::linalg::ldlt_dropping`] on the same
//! numbers in the same order (each entry the same bits), laid out for a
//! small m: four rows' sums carried side by side (independent chains, so
//! that one does not wait on another's latency; two a register on x86_64,
//! each lane the scalar operations), no test on a dropped pivot in the inner
//! loops, and raw indices with the bounds checked once a call (a column has
//! few rows and few terms at these m: per-column bookkeeping, not the
//! products, was most of the cost).
//!
//! Why the test can go: a pivot dropped at column k (D = 0) leaves its column
//! of L exactly +0 below the diagonal, so every term lᵢₖ lⱼₖ dₖ of a later
//! entry is (+0 · +0) · (+0) = +0, and x − (+0) is x for every x (−0, NaN and
//! ±∞ included): skipping the term and subtracting it agree bit for bit.

use crate::dynamics::linalg;

/// Most rows taken here (more: the library's loop, `ld` = m and `from` = 0
/// only).
const CAP: usize = 64;
const _: () = assert!(super::SUBSPACE_MAX <= CAP);

/// [`linalg::ldlt_dropping`] (the lower triangle of the m × m `a`, row i at
/// `a[i * ld..]`, factored as L D Lᵀ, a pivot below `drop` of its diagonal
/// dropped), the same bits, its rows before `from` taken as factored already.
///
/// Row i of the factor (its L entries and pivot) depends on the rows ≤ i of
/// the matrix only, and each entry is the same sum in the same order whatever
/// follows: the factor of a leading block is the leading block of the factor.
/// So rows appended to a factored block (`from` its size) are factored here
/// to the bits a factor from scratch gives them (docs/theory.md §"Constraint
/// solve": the subspace step's free rows kept across a solve's tries).
pub(crate) fn ldlt_dropping(a: &mut [f64], ld: usize, m: usize, from: usize, drop: f64) {
    let from = from.min(m);
    if m > CAP || ld < m || a.len() < m * ld {
        if ld == m && from == 0 {
            linalg::ldlt_dropping(a, m, drop);
        }
        return;
    }
    // the pivots (dₖ, k < m: each written at its column before any read,
    // so not cleared first)
    let mut d = [std::mem::MaybeUninit::<f64>::uninit(); CAP];
    // SAFETY: every index read or written below is i·ld + k with i < m and
    // k ≤ j < m, at most (m − 1)·ld + m − 1 < m·ld ≤ a.len() (checked above);
    // d's indices are < m ≤ CAP, dⱼ written at column j before the columns
    // after it read it
    let a = a.as_mut_ptr();
    unsafe {
        fixed(
            m,
            #[inline(always)]
            |m| factor(a, ld, m, from, drop, &mut d),
        )
    }
}

/// `f(m)`, with m a constant in the arms of the small m most tries have (one
/// or two contacts: 3 to 6 rows; two contacts and one or two sliding
/// ones' normals: 7 and 8; three or four contacts: 9 to 12), so that `f`'s
/// loops, inlined there, lose
/// their per-column set-up: the same operations in the same order.
#[inline(always)]
fn fixed<R>(m: usize, mut f: impl FnMut(usize) -> R) -> R {
    match m {
        3 => f(3),
        4 => f(4),
        5 => f(5),
        6 => f(6),
        7 => f(7),
        8 => f(8),
        9 => f(9),
        10 => f(10),
        11 => f(11),
        12 => f(12),
        _ => f(m),
    }
}

/// [`ldlt_dropping`]'s loops on `a` (m rows of `ld`, the first `from`
/// factored), column by column: column j's pivot (rows from `from` on),
/// then its entries in the rows below it that are not factored yet, lᵢⱼ =
/// (aᵢⱼ − Σₖ lᵢₖ lⱼₖ dₖ) / dⱼ over k < j in order, four rows' sums side by side
/// (two a register: each lane the scalar operations), +0 for a dropped pivot
/// (the library's `s / dⱼ` not taken: no sum then).
///
/// # Safety
/// `a` must hold m · ld entries, ld ≥ m, from ≤ m ≤ CAP. `d` need not be
/// initialised: dⱼ is written at column j, before any read of it.
#[inline(always)]
unsafe fn factor(
    a: *mut f64,
    ld: usize,
    m: usize,
    from: usize,
    drop: f64,
    d: &mut [std::mem::MaybeUninit<f64>; CAP],
) {
    // SAFETY: the caller's contract (every index within a and d; d[k] read
    // for k < j only, written at column k)
    unsafe {
        let d = d.as_mut_ptr().cast::<f64>();
        for j in 0..m {
            let rj = a.add(j * ld);
            let dj = if j < from {
                *rj.add(j)
            } else {
                // the pivot: its sum over k < j in order, two terms a step
                let diag = *rj.add(j);
                let mut s = diag;
                let mut k = 0;
                while k + 1 < j {
                    let (l0, l1) = (*rj.add(k), *rj.add(k + 1));
                    s -= l0 * l0 * *d.add(k);
                    s -= l1 * l1 * *d.add(k + 1);
                    k += 2;
                }
                if k < j {
                    let l = *rj.add(k);
                    s -= l * l * *d.add(k);
                }
                let dj = if s > drop * diag && s > 0.0 { s } else { 0.0 };
                *rj.add(j) = dj;
                dj
            };
            *d.add(j) = dj;
            let mut i = if j < from { from } else { j + 1 };
            if dj == 0.0 {
                while i < m {
                    *a.add(i * ld + j) = 0.0;
                    i += 1;
                }
                continue;
            }
            #[cfg(target_arch = "x86_64")]
            {
                use std::arch::x86_64::*;
                // SSE2 is part of x86_64
                let dd = _mm_set1_pd(dj);
                while i + 4 <= m {
                    let r0 = a.add(i * ld);
                    let (r1, r2, r3) = (r0.add(ld), r0.add(2 * ld), r0.add(3 * ld));
                    let mut s01 = _mm_set_pd(*r1.add(j), *r0.add(j));
                    let mut s23 = _mm_set_pd(*r3.add(j), *r2.add(j));
                    for k in 0..j {
                        let lk = _mm_set1_pd(*rj.add(k));
                        let dk = _mm_set1_pd(*d.add(k));
                        let x01 = _mm_set_pd(*r1.add(k), *r0.add(k));
                        let x23 = _mm_set_pd(*r3.add(k), *r2.add(k));
                        s01 = _mm_sub_pd(s01, _mm_mul_pd(_mm_mul_pd(x01, lk), dk));
                        s23 = _mm_sub_pd(s23, _mm_mul_pd(_mm_mul_pd(x23, lk), dk));
                    }
                    let (l01, l23) = (_mm_div_pd(s01, dd), _mm_div_pd(s23, dd));
                    _mm_storel_pd(r0.add(j), l01);
                    _mm_storeh_pd(r1.add(j), l01);
                    _mm_storel_pd(r2.add(j), l23);
                    _mm_storeh_pd(r3.add(j), l23);
                    i += 4;
                }
                if i + 2 <= m {
                    let r0 = a.add(i * ld);
                    let r1 = r0.add(ld);
                    let mut s01 = _mm_set_pd(*r1.add(j), *r0.add(j));
                    for k in 0..j {
                        let lk = _mm_set1_pd(*rj.add(k));
                        let dk = _mm_set1_pd(*d.add(k));
                        let x01 = _mm_set_pd(*r1.add(k), *r0.add(k));
                        s01 = _mm_sub_pd(s01, _mm_mul_pd(_mm_mul_pd(x01, lk), dk));
                    }
                    let l01 = _mm_div_pd(s01, dd);
                    _mm_storel_pd(r0.add(j), l01);
                    _mm_storeh_pd(r1.add(j), l01);
                    i += 2;
                }
            }
            #[cfg(not(target_arch = "x86_64"))]
            while i + 4 <= m {
                let r0 = a.add(i * ld);
                let (r1, r2, r3) = (r0.add(ld), r0.add(2 * ld), r0.add(3 * ld));
                let (mut s0, mut s1, mut s2, mut s3) =
                    (*r0.add(j), *r1.add(j), *r2.add(j), *r3.add(j));
                for k in 0..j {
                    let (lk, dk) = (*rj.add(k), *d.add(k));
                    s0 -= *r0.add(k) * lk * dk;
                    s1 -= *r1.add(k) * lk * dk;
                    s2 -= *r2.add(k) * lk * dk;
                    s3 -= *r3.add(k) * lk * dk;
                }
                *r0.add(j) = s0 / dj;
                *r1.add(j) = s1 / dj;
                *r2.add(j) = s2 / dj;
                *r3.add(j) = s3 / dj;
                i += 4;
            }
            while i < m {
                let ri = a.add(i * ld);
                let mut s = *ri.add(j);
                for k in 0..j {
                    s -= *ri.add(k) * *rj.add(k) * *d.add(k);
                }
                *ri.add(j) = s / dj;
                i += 1;
            }
        }
    }
}

/// [`linalg::ldlt_dropping_solve`] (L D Lᵀ x = b in place, the factor of
/// [`ldlt_dropping`] in the lower triangle of the m × m `a`, row i at
/// `a[i * ld..]`, a dropped pivot's x set to 0), the same operations in the
/// same order on each entry, without the index checks of the library's loops
/// and with fewer loop steps (two rows' sums a step forward, two terms a step
/// back).
pub(crate) fn ldlt_dropping_solve(a: &[f64], ld: usize, m: usize, x: &mut [f64]) {
    if m == 0 || ld < m || a.len() < (m - 1) * ld + m || x.len() < m {
        return;
    }
    // SAFETY: every index read or written below is i·ld + k (i, k < m) in `a`,
    // at most (m − 1)·ld + m − 1 < a.len(), and i < m ≤ x.len() in `x`
    let (a, x) = (a.as_ptr(), x.as_mut_ptr());
    unsafe {
        fixed(
            m,
            #[inline(always)]
            |m| solve(a, ld, m, x),
        )
    }
}

/// [`ldlt_dropping_solve`]'s two passes on `x` (m entries) with the factor
/// `a` (m rows of `ld`).
///
/// # Safety
/// `a` must hold (m − 1)·ld + m entries, ld ≥ m ≥ 1, and `x` m entries.
#[inline(always)]
unsafe fn solve(a: *const f64, ld: usize, m: usize, x: *mut f64) {
    // SAFETY: the caller's contract (every index i·ld + k, i, k < m, in `a`,
    // and i < m in `x`)
    unsafe {
        // L z = b: row i's sum over k < i in order, rows i and i + 1 side
        // by side (two chains) over k < i, then row i + 1's term k = i
        let mut i = 1;
        while i + 1 < m {
            let (r0, r1) = (a.add(i * ld), a.add((i + 1) * ld));
            let (mut s0, mut s1) = (*x.add(i), *x.add(i + 1));
            for k in 0..i {
                let xk = *x.add(k);
                s0 -= *r0.add(k) * xk;
                s1 -= *r1.add(k) * xk;
            }
            *x.add(i) = s0;
            s1 -= *r1.add(i) * s0;
            *x.add(i + 1) = s1;
            i += 2;
        }
        if i < m {
            let row = a.add(i * ld);
            let mut s = *x.add(i);
            for k in 0..i {
                s -= *row.add(k) * *x.add(k);
            }
            *x.add(i) = s;
        }
        // z /= D, then Lᵀ x = z: entry i's zᵢ/dᵢ, less its sum over k > i in
        // order, down column i of L (each xₖ, k > i, final by then: the same
        // operations on each entry as the two passes one after the other)
        for i in (0..m).rev() {
            let d = *a.add(i * ld + i);
            if d == 0.0 {
                *x.add(i) = 0.0;
                continue;
            }
            let mut s = *x.add(i) / d;
            let mut k = i + 1;
            while k + 1 < m {
                s -= *a.add(k * ld + i) * *x.add(k);
                s -= *a.add((k + 1) * ld + i) * *x.add(k + 1);
                k += 2;
            }
            if k < m {
                s -= *a.add(k * ld + i) * *x.add(k);
            }
            *x.add(i) = s;
        }
    }
}
