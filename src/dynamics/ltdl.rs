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

/// Factorises the symmetric positive-definite `h` (full storage, tree-shaped
/// sparsity given by `lambda`) as `Lᵀ D L` into `u` (layout above). Fails with the
/// coordinate index of the first pivot that is at most 64 ε times its diagonal
/// entry of H, or not finite — the same test as [`super::linalg::cholesky`].
pub fn ltdl<T: Scalar>(h: &DMatrix<T>, lambda: &[usize], u: &mut DMatrix<T>) -> Result<(), usize> {
    let n = lambda.len();
    let tiny = lit::<T>(64.0 * f64::EPSILON);
    // Copy the pattern of H (column k: k and its ancestors).
    for k in 0..n {
        u[(k, k)] = h[(k, k)];
        let mut i = lambda[k];
        while i != NONE {
            u[(i, k)] = h[(i, k)];
            i = lambda[i];
        }
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
            let (left, right) = us.split_at_mut(k * n);
            let colk = &mut right[..k];
            for i in (0..k).rev() {
                let a = colk[i] / d;
                let coli = &mut left[i * n..i * n + i + 1];
                for (x, y) in coli.iter_mut().zip(colk[..=i].iter()) {
                    *x = madd(-a, *y, *x);
                }
                colk[i] = a;
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
    let mut anc = [0usize; MAX_DEPTH];
    for k in (0..n).rev() {
        let d = us[k + k * n];
        if !(d > tiny * h[(k, k)].abs()) || !d.is_finite() {
            return Err(k);
        }
        let mut len = 0;
        let mut i = lambda[k];
        while i != NONE && len < MAX_DEPTH {
            anc[len] = i;
            len += 1;
            i = lambda[i];
        }
        if i == NONE {
            let anc = &anc[..len];
            // the list ends with the run tl − 1, …, 1, 0 (a free base's six
            // coordinates, and whatever chain continues them): the updates
            // over that tail are one contiguous axpy (the same operations on
            // the same entries as the gather over the list)
            let mut tl = 0;
            while tl < len && anc[len - 1 - tl] == tl {
                tl += 1;
            }
            let head = len - tl;
            let (left, right) = us.split_at_mut(k * n);
            let colk = &mut right[..k];
            for (t, &i) in anc.iter().enumerate() {
                let a = colk[i] / d;
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
            }
            continue;
        }
        // deeper than the list: walk λ
        let mut i = lambda[k];
        while i != NONE {
            let a = us[i + k * n] / d;
            let mut j = i;
            while j != NONE {
                let hkj = us[j + k * n];
                us[j + i * n] = madd(-a, hkj, us[j + i * n]);
                j = lambda[j];
            }
            us[i + k * n] = a;
            i = lambda[i];
        }
    }
    Ok(())
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
