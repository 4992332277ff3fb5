//! L's exact zeros on a lone free body's chain (docs/theory.md §"Tree-sparse
//! LTDL"): a body whose frame sits at its centre of mass on its principal
//! axes (a pile's box, ball or cylinder) has H̃ diagonal, so every entry of
//! L along its chain is ±0, and each step of a row's elimination, y[j] −=
//! l·y[t], subtracts a zero. On rows whose entries are all finite and none
//! is −0, no such step changes a bit (below), and the steps are skipped.
//!
//! Why: with y[t] finite, l·y[t] is ±0; x − (±0) is x for every x ≠ 0, and
//! +0 − (±0) is +0; so a step leaves every entry that is not −0 as it was,
//! and by induction from the leaf in every y[t] a later step reads is still
//! its finite input. (An entry of −0 would turn +0 where the product is −0:
//! those rows, and rows with an entry ±∞ or NaN, take every step.)

use super::MassFactor;

impl MassFactor {
    /// After the factor of dofs `[k0, k1)` (whole trees; `ok`: it succeeded):
    /// marks each dof whose row of L and every ancestor's row are zeros
    /// (either sign). On a model of lone free bodies only (its factor is
    /// made again only when H̃ changes); no dof of any other model is
    /// marked, the scan kept out of a robot's every step.
    pub(super) fn mark_zeros(&mut self, k0: usize, k1: usize, ok: bool) {
        if !self.lone_free {
            return;
        }
        for k in k0..k1.min(self.zero_l.len()) {
            let (s, l) = (self.start[k], self.len[k]);
            // (the last ancestor on k's path is its parent, below k: marked already)
            let parent = l < 2 || self.zero_l.get(self.table[s + l - 2]) == Some(&true);
            let own = self
                .anc
                .get(s..s + l - 1)
                .is_some_and(|a| a.iter().all(|&x| x == 0.0));
            self.zero_l[k] = ok && own && parent;
        }
    }

    /// Whether L is zero on every row of the chain root … `leaf`.
    #[inline(always)]
    pub(super) fn zero_chain(&self, leaf: usize) -> bool {
        self.zero_l.get(leaf) == Some(&true)
    }

    /// D^-½ on `path`, chains ending at `path[A − 1]` and `path[N − 1]` (one
    /// where A = N), where L is zero on both and every row of `rows` is
    /// plain: there each row's elimination changes no bit (above), and Y =
    /// J·D^-½ entry by entry. None elsewhere (the rows take the steps).
    #[inline(always)]
    pub(crate) fn zero_scale<const A: usize, const N: usize, const R: usize>(
        &self,
        path: &[usize],
        rows: &[&[f64; N]; R],
    ) -> Option<[f64; N]> {
        let path: &[usize; N] = path.get(..N)?.try_into().ok()?;
        let zero = A >= 1 && A <= N && self.zero_chain(path[A - 1]) && self.zero_chain(path[N - 1]);
        if !(zero && plain_rows(&rows.map(|r| &r[..]))) {
            return None;
        }
        let mut s = [0.0f64; N];
        for (s, &k) in s.iter_mut().zip(path) {
            *s = *self.inv_sqrt_d.get(k)?;
        }
        Some(s)
    }
}

/// Every entry of `x` finite and none −0: rows whose elimination on a chain
/// of zeros ([`MassFactor::zero_chain`]) changes no bit. (Without SSE4.1 a
/// +0 is refused too: one float compare for both signs.)
///
/// Finite by each lane's sum: a term ±∞ or NaN leaves a sum ±∞ or NaN
/// whatever follows, so a finite sum has finite terms (an overflow only
/// sends the caller the long way). In vector lanes: the test is a few
/// instructions a register, the steps it spares dozens.
#[inline(always)]
pub(super) fn plain(x: &[f64]) -> bool {
    plain_rows(&[x])
}

/// [`plain`] of every row of `rows` at once (one lanes' sum and test for all).
#[inline(always)]
fn plain_rows<const R: usize>(rows: &[&[f64]; R]) -> bool {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
    {
        use std::arch::x86_64::*;
        let (mut sum, mut neg_zero) = ([0.0f64; 4], false);
        // SAFETY: AVX2 is enabled for this build (the cfg); each load is of
        // the four f64 of one chunk
        unsafe {
            let m = _mm256_set1_epi64x(NEG_ZERO);
            let (mut s, mut z) = (_mm256_setzero_pd(), _mm256_setzero_si256());
            for x in rows {
                let mut quads = x.chunks_exact(4);
                for q in &mut quads {
                    let v = _mm256_loadu_pd(q.as_ptr());
                    s = _mm256_add_pd(s, v);
                    z = _mm256_or_si256(z, _mm256_cmpeq_epi64(_mm256_castpd_si256(v), m));
                }
                neg_zero |= tail(&mut sum, quads.remainder());
            }
            let mut a = [0.0f64; 4];
            _mm256_storeu_pd(a.as_mut_ptr(), s);
            neg_zero |= _mm256_movemask_pd(_mm256_castsi256_pd(z)) != 0;
            sum[1] += a[1];
            sum[2] += a[2];
            sum[3] += a[3];
            sum[0] += a[0];
        }
        !neg_zero && sum.iter().all(|s| s.is_finite())
    }
    #[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
    {
        use std::arch::x86_64::*;
        let (mut sum, mut neg_zero) = ([0.0f64; 2], false);
        // SAFETY: SSE2 is every x86_64's (SSE4.1 where the cfg says); each
        // load is of the two f64 of one chunk
        unsafe {
            let (mut s, mut z) = (_mm_setzero_pd(), _mm_setzero_pd());
            for x in rows {
                let mut pairs = x.chunks_exact(2);
                for p in &mut pairs {
                    let v = _mm_loadu_pd(p.as_ptr());
                    s = _mm_add_pd(s, v);
                    #[cfg(target_feature = "sse4.1")]
                    let hit = _mm_castsi128_pd(_mm_cmpeq_epi64(
                        _mm_castpd_si128(v),
                        _mm_set1_epi64x(NEG_ZERO),
                    ));
                    #[cfg(not(target_feature = "sse4.1"))]
                    let hit = _mm_cmpeq_pd(v, _mm_setzero_pd());
                    z = _mm_or_pd(z, hit);
                }
                neg_zero |= tail(&mut sum, pairs.remainder());
            }
            let mut a = [0.0f64; 2];
            _mm_storeu_pd(a.as_mut_ptr(), s);
            neg_zero |= _mm_movemask_pd(z) != 0;
            sum[1] += a[1];
            sum[0] += a[0];
        }
        !neg_zero && sum.iter().all(|s| s.is_finite())
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let mut sum = [0.0f64];
        let neg_zero = rows.iter().fold(false, |n, x| n | tail(&mut sum, x));
        !neg_zero && sum[0].is_finite()
    }
}

/// The bits of −0 (as the lanes' integer compare takes them).
#[cfg(all(
    target_arch = "x86_64",
    any(target_feature = "avx2", target_feature = "sse4.1")
))]
const NEG_ZERO: i64 = i64::MIN;

/// The entries a row's lanes leave, added to `sum[0]`: whether one is −0.
#[inline(always)]
fn tail<const K: usize>(sum: &mut [f64; K], rest: &[f64]) -> bool {
    let mut neg_zero = false;
    for &v in rest {
        sum[0] += v;
        neg_zero |= v.to_bits() == 1 << 63;
    }
    neg_zero
}
