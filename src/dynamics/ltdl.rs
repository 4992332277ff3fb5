//! Tree-sparse LTDL factorisation of the joint-space inertia matrix
//! (Featherstone, "Efficient factorization of the joint-space inertia matrix for
//! branched kinematic trees", 2005; RBDA §6.5).
//!
//! For a kinematic tree, `H[i, j] ≠ 0` only when i and j lie on one path to the
//! root. Factorising `H = Lᵀ D L` from the leaves inwards (k = n−1 down to 0)
//! creates no fill outside that pattern: L has the sparsity of H's lower
//! triangle, and the work is O(Σₖ depth(k)²) = O(n·d²) for depth d, instead of
//! O(n³). Row k of L is walked with the parent array λ (`model.dof_parent`).
//!
//! Storage: `L[k, i]` (i an ancestor of k) at `u[(i, k)]`, i.e. the upper triangle
//! of `u` holds Lᵀ, so that every inner loop reads one column of `u`; `D[k]` sits
//! on the diagonal. Only the entries on the tree pattern are read or written.

use crate::spatial::ops::madd;
use crate::spatial::{lit, Scalar};
use nalgebra::{DMatrix, DVector};

const NONE: usize = usize::MAX;
/// The deepest ancestor list [`ltdl`] keeps on the stack (deeper paths walk λ).
const MAX_DEPTH: usize = 128;
/// Up to this many coordinates [`ltdl`] copies H's upper columns whole.
const SMALL: usize = 64;

/// Factorises the symmetric positive-definite `h` (full storage, tree-shaped
/// sparsity given by `lambda`) as `Lᵀ D L` into `u` (layout above). Fails with the
/// coordinate index of the first pivot that is at most 64 ε times its diagonal
/// entry of H, or not finite — the same test as [`super::linalg::cholesky`].
pub fn ltdl<T: Scalar>(h: &DMatrix<T>, lambda: &[usize], u: &mut DMatrix<T>) -> Result<(), usize> {
    factor(h, lambda, u, false, &mut NoHook)
}

/// [`ltdl`]; `placed`: `u`'s upper triangle already holds H's entries on the
/// tree pattern (the CRBA wrote them there, `super::bias_and_crba_factor`),
/// so they are not copied from `h` first (`h`'s diagonal is still read by the
/// pivot test).
pub(crate) fn factor_placed<T: Scalar>(
    h: &DMatrix<T>,
    lambda: &[usize],
    u: &mut DMatrix<T>,
    placed: bool,
) -> Result<(), usize> {
    factor(h, lambda, u, placed, &mut NoHook)
}

/// What runs beside the elimination of each coordinate (leaves inwards):
/// [`ltdl`] runs none, [`ltdl_rows`] eliminates its right-hand sides.
trait Hook<T> {
    /// Coordinate k's pivot D[k] is final, before its elimination.
    fn pivot(&mut self, k: usize, d: T);
    /// After ancestor i's step of k's elimination: L[k, i] = `a`.
    fn step(&mut self, k: usize, i: usize, a: T);
}

/// No work beside the factorisation.
struct NoHook;

impl<T> Hook<T> for NoHook {
    #[inline(always)]
    fn pivot(&mut self, _: usize, _: T) {}
    #[inline(always)]
    fn step(&mut self, _: usize, _: usize, _: T) {}
}

/// The factorisation of [`ltdl`], calling `hook` as each pivot becomes final
/// and after each ancestor's step: one elimination for [`ltdl`] and
/// [`ltdl_rows`], the same operations on the factor in both.
#[inline(always)]
fn factor<T: Scalar, K: Hook<T>>(
    h: &DMatrix<T>,
    lambda: &[usize],
    u: &mut DMatrix<T>,
    placed: bool,
    hook: &mut K,
) -> Result<(), usize> {
    let n = lambda.len();
    let tiny = lit::<T>(64.0 * f64::EPSILON);
    if !placed {
        copy_pattern(h, lambda, u);
    }
    // A chain (λ(k) = k − 1): the same elimination on contiguous column ranges,
    // as axpy sweeps the compiler vectorises.
    if lambda
        .iter()
        .enumerate()
        .all(|(k, &p)| p == k.wrapping_sub(1))
    {
        let us = u.as_mut_slice();
        for k in (0..n).rev() {
            let d = us[k * n + k];
            if !(d > tiny * h[(k, k)].abs()) || !d.is_finite() {
                return Err(k);
            }
            hook.pivot(k, d);
            let dinv = T::one() / d;
            let (left, right) = us.split_at_mut(k * n);
            let colk = &mut right[..k];
            for i in (0..k).rev() {
                let a = colk[i] * dinv;
                let coli = &mut left[i * n..i * n + i + 1];
                for (x, y) in coli.iter_mut().zip(colk[..=i].iter()) {
                    *x = madd(-a, *y, *x);
                }
                colk[i] = a;
                hook.step(k, i, a);
            }
        }
        return Ok(());
    }
    // Slices (column-major, u[(i, k)] at i + k n): the walks below index
    // without nalgebra's per-access checks of both dimensions.
    let us = u.as_mut_slice();
    // k's ancestors, nearest first, listed once per k: the elimination's double
    // loop then reads the list instead of walking λ at every step (a chain of
    // dependent loads), the same operations in the same order
    // Eliminate coordinate k from its ancestors: for i, j on k's path with j
    // ancestor-or-self of i, H[i, j] −= H[k, i] H[k, j] / D[k].
    let mut anc = AncList::new();
    for k in (0..n).rev() {
        let d = us[k + k * n];
        if !(d > tiny * h[(k, k)].abs()) || !d.is_finite() {
            return Err(k);
        }
        hook.pivot(k, d);
        // one division per pivot: L[k, i] = H̃[k, i] · D[k]⁻¹ (a division
        // per entry stalled the updates that wait for it)
        let dinv = T::one() / d;
        let (left, right) = us.split_at_mut(k * n);
        let colk = &mut right[..k];
        if let Some(list) = anc.of(lambda, k) {
            eliminate_list(colk, left, n, list, dinv, |i, a| hook.step(k, i, a));
            continue;
        }
        // deeper than the list: walk λ
        let mut i = lambda[k];
        while i != NONE {
            let a = colk[i] * dinv;
            let mut j = i;
            while j != NONE {
                left[j + i * n] = madd(-a, colk[j], left[j + i * n]);
                j = lambda[j];
            }
            colk[i] = a;
            hook.step(k, i, a);
            i = lambda[i];
        }
    }
    Ok(())
}

/// Coordinate k's ancestors, nearest first, for k = n − 1 down to 0: where
/// λ(k + 1) = k (a chain, most of every tree in depth-first order) k's list is
/// that of k + 1 without its first entry, otherwise λ is walked (a chain of
/// dependent loads) into the buffer.
struct AncList {
    buf: [usize; MAX_DEPTH],
    /// The list is `buf[s..e]`.
    s: usize,
    e: usize,
    /// Whether the list reaches the root (not cut at `MAX_DEPTH`).
    whole: bool,
}

impl AncList {
    fn new() -> Self {
        Self {
            buf: [0; MAX_DEPTH],
            s: 0,
            e: 0,
            whole: false,
        }
    }

    /// k's ancestors (called for k descending), `None` when deeper than the buffer.
    #[inline(always)]
    fn of(&mut self, lambda: &[usize], k: usize) -> Option<&[usize]> {
        if self.whole && self.s < self.e && self.buf[self.s] == k {
            self.s += 1;
        } else {
            let mut len = 0;
            let mut i = lambda[k];
            while i != NONE && len < MAX_DEPTH {
                self.buf[len] = i;
                len += 1;
                i = lambda[i];
            }
            self.s = 0;
            self.e = len;
            self.whole = i == NONE;
        }
        if self.whole {
            Some(&self.buf[self.s..self.e])
        } else {
            None
        }
    }
}

/// Eliminates coordinate k (column `colk` = H̃[0..k, k], pivot reciprocal
/// `dinv`) from its ancestors `anc` (nearest first, the whole path): for i on
/// the path, H̃[j, i] −= L[k, i] H̃[j, k] for j ancestor-or-self of i on it
/// (`left` holds the columns before k), then L[k, i] into `colk[i]`; `each(i,
/// L[k, i])` after each ancestor's step (the right-hand sides of
/// [`ltdl_rows`]). The list ends with the run tl − 1, …, 1, 0 (a free base's six
/// coordinates, and whatever chain continues them): the updates over that tail
/// are contiguous axpys; a free base's six (tl ≥ 6: the rest of the run joins
/// the gathered head) are fixed 6-wide, unrolled. The same operations on the
/// same entries in every branch.
#[inline(always)]
fn eliminate_list<T: Scalar>(
    colk: &mut [T],
    left: &mut [T],
    n: usize,
    anc: &[usize],
    dinv: T,
    mut each: impl FnMut(usize, T),
) {
    let len = anc.len();
    let mut tl = 0;
    while tl < len && anc[len - 1 - tl] == tl {
        tl += 1;
    }
    if tl >= 6 {
        let head = len - 6;
        let k6: [T; 6] = [colk[0], colk[1], colk[2], colk[3], colk[4], colk[5]];
        for (t, &i) in anc[..head].iter().enumerate() {
            let a = colk[i] * dinv;
            let coli = &mut left[i * n..i * n + i + 1];
            for &j in &anc[t..head] {
                coli[j] = madd(-a, colk[j], coli[j]);
            }
            for r in 0..6 {
                coli[r] = madd(-a, k6[r], coli[r]);
            }
            colk[i] = a;
            each(i, a);
        }
        // the base block: H̃[j, i] −= L[k, i] H̃[j, k], j ≤ i < 6
        for i in (0..6).rev() {
            let a = k6[i] * dinv;
            let coli = &mut left[i * n..i * n + 6];
            for r in 0..=i {
                coli[r] = madd(-a, k6[r], coli[r]);
            }
            colk[i] = a;
            each(i, a);
        }
        return;
    }
    let head = len - tl;
    for (t, &i) in anc.iter().enumerate() {
        let a = colk[i] * dinv;
        let coli = &mut left[i * n..i * n + i + 1];
        let run = if t < head {
            for &j in &anc[t..head] {
                coli[j] = madd(-a, colk[j], coli[j]);
            }
            tl
        } else {
            i + 1
        };
        for (x, &y) in coli[..run].iter_mut().zip(&colk[..run]) {
            *x = madd(-a, y, *x);
        }
        colk[i] = a;
        each(i, a);
    }
}

/// H's pattern into `u` (column k: k and its ancestors). On small models the
/// whole upper column `0..=k` (the pattern and H's structural zeros beside it,
/// which nothing reads) as one contiguous copy each: O(n²) moves, cheaper there
/// than the walk of λ with a store per entry.
fn copy_pattern<T: Scalar>(h: &DMatrix<T>, lambda: &[usize], u: &mut DMatrix<T>) {
    let n = lambda.len();
    if n <= SMALL {
        let (hs, us) = (h.as_slice(), u.as_mut_slice());
        for k in 0..n {
            us[k * n..k * n + k + 1].copy_from_slice(&hs[k * n..k * n + k + 1]);
        }
        return;
    }
    for k in 0..n {
        u[(k, k)] = h[(k, k)];
        let mut i = lambda[k];
        while i != NONE {
            u[(i, k)] = h[(i, k)];
            i = lambda[i];
        }
    }
}

/// [`ltdl`] fused with the elimination `Lᵀ⁻¹` of `m` right-hand sides kept
/// coordinate-major (row k, coordinate k of each, at `w[k m..(k + 1) m]`) and
/// of one more, `b`: as coordinate k is eliminated from its ancestors i, so are
/// its rows (`w[i] −= L[k, i] w[k]`, `b[i] −= L[k, i] b[k]`, the steps of
/// [`ltdl_solve_rows`]' first sweep), leaving `L⁻ᵀ w`, `L⁻ᵀ b` and the factor of
/// [`ltdl`] (the same operations on it). `span[k] = (lo, hi)`: row k of `w` is
/// zero outside `lo..hi` before and after the elimination (empty, lo ≥ hi, for
/// a zero row: rows held on two feet are zero on the other leg's coordinates,
/// on the arms' all zero), which the caller knows from the rows' structure
/// (every ancestor's span covering its descendants'); the steps update that
/// span alone. `pivot(k, D[k], lo, w[k][lo..hi], b[k])` sees each final row
/// before its ancestors' updates (leaves inwards). One walk of the tree
/// instead of two (docs/theory.md §"Constrained dynamics", "Solving").
#[allow(clippy::too_many_arguments)]
pub(crate) fn ltdl_rows<T: Scalar>(
    h: &DMatrix<T>,
    lambda: &[usize],
    u: &mut DMatrix<T>,
    m: usize,
    w: &mut [T],
    b: &mut [T],
    span: &[(usize, usize)],
    placed: bool,
    pivot: impl FnMut(usize, T, usize, &[T], T),
) -> Result<(), usize> {
    let mut hook = RowsHook {
        m,
        w,
        b,
        span,
        pivot,
        lo: 0,
        hi: 0,
        bk: T::zero(),
    };
    factor(h, lambda, u, placed, &mut hook)
}

/// [`ltdl_rows`]' right-hand sides, eliminated with the factor.
struct RowsHook<'a, T, P> {
    m: usize,
    w: &'a mut [T],
    b: &'a mut [T],
    /// Each row's nonzero span (`ltdl_rows`).
    span: &'a [(usize, usize)],
    pivot: P,
    /// Row k of `w` is zero outside `lo..hi` (its nonzero span, empty when
    /// the row is zero): its steps update that span only.
    lo: usize,
    hi: usize,
    /// b[k] (final once k's pivot is).
    bk: T,
}

impl<T: Scalar, P: FnMut(usize, T, usize, &[T], T)> Hook<T> for RowsHook<'_, T, P> {
    #[inline(always)]
    fn pivot(&mut self, k: usize, d: T) {
        let m = self.m;
        let wk = &self.w[k * m..(k + 1) * m];
        self.bk = self.b[k];
        let (lo, hi) = self.span[k];
        let (lo, hi) = (lo.min(m), hi.min(m));
        let hi = hi.max(lo);
        (self.lo, self.hi) = (lo, hi);
        (self.pivot)(k, d, lo, &wk[lo..hi], self.bk);
    }

    #[inline(always)]
    fn step(&mut self, k: usize, i: usize, a: T) {
        let (m, lo, hi) = (self.m, self.lo, self.hi);
        if lo < hi {
            let (wa, wr) = self.w.split_at_mut(k * m);
            for (y, &x) in wa[i * m + lo..i * m + hi].iter_mut().zip(&wr[lo..hi]) {
                *y = madd(-a, x, *y);
            }
        }
        self.b[i] = madd(-a, self.bk, self.b[i]);
    }
}

/// Solves `Lᵀ D L x = b` in place with the factor from [`ltdl`]: `Lᵀ y = b`
/// (leaves inwards), `z = D⁻¹ y`, `L x = z` (root outwards). O(Σₖ depth(k)).
pub fn ltdl_solve<T: Scalar>(u: &DMatrix<T>, lambda: &[usize], x: &mut DVector<T>) {
    let n = lambda.len();
    let us = u.as_slice();
    let x = &mut x.as_mut_slice()[..n];
    for i in (0..n).rev() {
        let xi = x[i];
        let ui = &us[i * n..i * n + i];
        let mut j = lambda[i];
        while j != NONE {
            x[j] = madd(-ui[j], xi, x[j]);
            j = lambda[j];
        }
    }
    for i in 0..n {
        x[i] /= us[i + i * n];
    }
    for i in 0..n {
        let mut s = x[i];
        let ui = &us[i * n..i * n + i];
        let mut j = lambda[i];
        while j != NONE {
            s = madd(-ui[j], x[j], s);
            j = lambda[j];
        }
        x[i] = s;
    }
}

/// Solves `Lᵀ D L X = B` in place for `m` right-hand sides stored
/// coordinate-major: row k of X (coordinate k of every right-hand side) at
/// `x[k m..(k + 1) m]`, so that each elimination step of [`ltdl_solve`] is one
/// m-wide axpy. O(m Σₖ depth(k)).
pub fn ltdl_solve_rows<T: Scalar>(u: &DMatrix<T>, lambda: &[usize], m: usize, x: &mut [T]) {
    let n = lambda.len();
    let us = u.as_slice();
    let x = &mut x[..n * m];
    // Lᵀ y = b, leaves inwards: row j −= L[i, j] row i for each ancestor j of i
    for i in (0..n).rev() {
        let (above, rest) = x.split_at_mut(i * m);
        let xi = &rest[..m];
        let mut j = lambda[i];
        while j != NONE {
            let l = us[j + i * n];
            for (y, &s) in above[j * m..(j + 1) * m].iter_mut().zip(xi) {
                *y = madd(-l, s, *y);
            }
            j = lambda[j];
        }
    }
    // z = D⁻¹ y, then L x = z root outwards: row i −= L[i, j] row j
    for i in 0..n {
        let (above, rest) = x.split_at_mut(i * m);
        let xi = &mut rest[..m];
        let dinv = T::one() / us[i + i * n];
        for y in xi.iter_mut() {
            *y *= dinv;
        }
        let mut j = lambda[i];
        while j != NONE {
            let l = us[j + i * n];
            for (y, &s) in xi.iter_mut().zip(&above[j * m..(j + 1) * m]) {
                *y = madd(-l, s, *y);
            }
            j = lambda[j];
        }
    }
}
