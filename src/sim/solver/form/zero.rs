//! [`Former::form_pair`] and [`Former::form_lanes`] on chains of zeros
//! (factor/zeros.rs): where L is zero on the contacts' chains and their rows
//! are plain, no elimination step changes a bit and Y = J·D^-½ entry by
//! entry (docs/theory.md §"Tree-sparse LTDL"). The rows are then formed slot
//! by slot straight from J into Y and the sums, without the gather into
//! lanes and the store back: every value the lanes' form gives, each sum in
//! path order as there (`gather_six`, `store_six`; `gather_rows`,
//! `store_block`).

use super::super::MassFactor;
use super::{add_w, Former};

impl Former<'_> {
    /// Contact r's three rows (`R` = 3) or contacts r's and r + 3's six (`R`
    /// = 6) on N path slots (chains ending at `path[A − 1]` and
    /// `path[N − 1]`, one where A = N) formed where L is zero on the chains
    /// and the rows plain ([`MassFactor::zero_scale`]): Y's R rows, c = J v*,
    /// W's diagonal and each block's off-diagonal entries, each value what
    /// the lanes' form gives (`gather_rows` or `gather_six`, the chain's
    /// scale, `store_block` or `store_six`: the same operations in path
    /// order). False, nothing written, elsewhere.
    #[inline(always)]
    pub(super) fn form_zero<const A: usize, const N: usize, const R: usize>(
        &mut self,
        f: &MassFactor,
        r: usize,
        path: &[usize],
        vfree: &[f64],
    ) -> bool {
        debug_assert!(R == 3 || R == 6);
        let (st, j) = (self.st, self.j);
        let mut rows: [&[f64; N]; R] = [&const { [0.0f64; N] }; R];
        for (i, q) in rows.iter_mut().enumerate() {
            let Some(x) = j.get((r + i) * st..(r + i) * st + N) else {
                return false;
            };
            let Ok(x) = x.try_into() else {
                return false;
            };
            *q = x;
        }
        let Some(path) = path.get(..N).and_then(|p| <&[usize; N]>::try_from(p).ok()) else {
            return false;
        };
        if N > st || path.iter().any(|&d| d >= vfree.len()) {
            return false;
        }
        let Some(s) = f.zero_scale::<A, N, R>(path, &rows) else {
            return false;
        };
        // Y's R rows, N slots each
        let Some(y) = self.y.get_mut(r * st..(r + R) * st) else {
            return false;
        };
        // SAFETY: y is rows r … r + R − 1 of Y, R·st entries; N ≤ st and
        // every path[t] < vfree.len() (tested above)
        let [c, d, o] = unsafe { zero_rows(&rows, &s, path, vfree, (y.as_mut_ptr(), st)) };
        for k in 0..R / 3 {
            let (k, q) = (3 * k, r + 3 * k);
            self.c[q..q + 3].copy_from_slice(&c[k..k + 3]);
            self.w[q..q + 3].copy_from_slice(&d[k..k + 3]);
            self.w_block[q] = [o[k], o[k + 1], o[k + 2]];
        }
        true
    }
}

/// [`Former::form_zero`]'s slot loop on R rows of J (`rows`, on `path`; `s`
/// = D^-½ on it): Y's entries yᵢₜ = jᵢₜ·sₜ written at `y` (row i's slot t
/// at i·st + t), and [c, d, o] returned: c = J v* from 0, W's diagonal
/// Σ yᵢₜ² and each block's off-diagonal sums (y₀y₁, y₀y₂, y₁y₂, …) from −0,
/// each in path order (the gather's and the store's order). A pair's six
/// rows take [`six_lanes`] on x86_64: the same operations, the same bits.
///
/// # Safety
/// `y` points at R·st writable entries, N ≤ st, and every `path[t]` is <
/// `vfree.len()`.
#[inline(always)]
unsafe fn zero_rows<const N: usize, const R: usize>(
    rows: &[&[f64; N]; R],
    s: &[f64; N],
    path: &[usize; N],
    vfree: &[f64],
    (y, st): (*mut f64, usize),
) -> [[f64; R]; 3] {
    #[cfg(target_arch = "x86_64")]
    if let Ok(six) = <&[&[f64; N]; 6]>::try_from(&rows[..]) {
        // SAFETY: the caller's (R = 6)
        let v = unsafe { six_lanes(six, s, path, vfree, (y, st)) };
        return v.map(|q| {
            let mut a = [0.0f64; R];
            a.copy_from_slice(&q[..R]);
            a
        });
    }
    let (mut c, mut d, mut o) = ([0.0f64; R], [-0.0f64; R], [-0.0f64; R]);
    for t in 0..N {
        let x = vfree[path[t]];
        // y = j·D^-½ (the chain's steps change no bit)
        let mut e = [0.0f64; R];
        for i in 0..R {
            let b = rows[i][t];
            c[i] += b * x;
            e[i] = b * s[t];
        }
        add_w(&mut d, &mut o, &e);
        for (i, &e) in e.iter().enumerate() {
            // SAFETY: row i's slot t, i·st + t < R·st (t < N ≤ st: the
            // caller's)
            unsafe { *y.add(i * st + t) = e };
        }
    }
    [c, d, o]
}

/// The slot loop of [`Former::form_zero`] on a pair's six rows (`rows`, J's
/// rows r … r + 5 on `path`; `s` = D^-½ on it): Y's entries yᵢₜ = jᵢₜ·sₜ
/// written at `y` (row i's slot t at i·st + t), and c = J v* from 0, W's
/// diagonal Σ yᵢₜ² and the blocks' off-diagonal sums (y₀y₁, y₀y₂, y₁y₂ and
/// y₃y₄, y₃y₅, y₄y₅) from −0, returned in row order. Rows i and i + 3 share
/// a register (SSE2, x86_64): every lane's operations are the scalar
/// loop's, in path order (the same bits), and each block product is one
/// lane's of a register product.
///
/// # Safety
/// `y` points at 6·st writable entries, N ≤ st, and every `path[t]` is <
/// `vfree.len()`.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn six_lanes<const N: usize>(
    rows: &[&[f64; N]; 6],
    s: &[f64; N],
    path: &[usize; N],
    vfree: &[f64],
    (y, st): (*mut f64, usize),
) -> [[f64; 6]; 3] {
    use std::arch::x86_64::*;
    let mut out = [[0.0f64; 6]; 3];
    // SAFETY: SSE2 is part of x86_64; t < N (each row N long), row i's slot
    // t at i·st + t < 6·st (N ≤ st) and path[t] < vfree.len() (the caller's)
    unsafe {
        // lanes (rows 0 and 3, 1 and 4, 2 and 5): c from 0, W's sums from −0
        let (mut c, mut d, mut o) = (
            [_mm_setzero_pd(); 3],
            [_mm_set1_pd(-0.0); 3],
            [_mm_set1_pd(-0.0); 3],
        );
        for t in 0..N {
            let x = _mm_set1_pd(*vfree.get_unchecked(path[t]));
            let st_ = _mm_set1_pd(s[t]);
            let mut e = [_mm_setzero_pd(); 3];
            for k in 0..3 {
                let b = _mm_loadh_pd(_mm_load_sd(&rows[k][t]), &rows[k + 3][t]);
                c[k] = _mm_add_pd(c[k], _mm_mul_pd(b, x));
                // y = j·D^-½ (the chain's steps change no bit)
                e[k] = _mm_mul_pd(b, st_);
                d[k] = _mm_add_pd(d[k], _mm_mul_pd(e[k], e[k]));
                _mm_storel_pd(y.add(k * st + t), e[k]);
                _mm_storeh_pd(y.add((k + 3) * st + t), e[k]);
            }
            // (y₀y₁, y₃y₄), (y₀y₂, y₃y₅), (y₁y₂, y₄y₅)
            o[0] = _mm_add_pd(o[0], _mm_mul_pd(e[0], e[1]));
            o[1] = _mm_add_pd(o[1], _mm_mul_pd(e[0], e[2]));
            o[2] = _mm_add_pd(o[2], _mm_mul_pd(e[1], e[2]));
        }
        for (q, v) in out.iter_mut().zip([c, d, o]) {
            for k in 0..3 {
                _mm_storel_pd(&mut q[k], v[k]);
                _mm_storeh_pd(&mut q[k + 3], v[k]);
            }
        }
    }
    out
}
