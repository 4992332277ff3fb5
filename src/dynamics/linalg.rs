//! Dense symmetric positive-definite factorisation in place (no allocation).

use crate::spatial::{lit, Scalar};
use nalgebra::{DMatrix, DVector};

/// Factorises the symmetric positive-definite `h` as `L Lᵀ`, writing `L` into the
/// lower triangle of `l` (its upper triangle is left as is). Fails with the pivot
/// index when `h` is not positive definite to working precision (a pivot at most
/// 64 ε times its diagonal entry, or not finite).
pub fn cholesky<T: Scalar>(h: &DMatrix<T>, l: &mut DMatrix<T>) -> Result<(), usize> {
    let n = h.nrows();
    let tiny = lit::<T>(64.0 * f64::EPSILON);
    for j in 0..n {
        let mut d = h[(j, j)];
        for k in 0..j {
            d -= l[(j, k)] * l[(j, k)];
        }
        if !(d > tiny * h[(j, j)].abs()) || !d.is_finite() {
            return Err(j);
        }
        let djj = d.sqrt();
        l[(j, j)] = djj;
        for i in (j + 1)..n {
            let mut s = h[(i, j)];
            for k in 0..j {
                s -= l[(i, k)] * l[(j, k)];
            }
            l[(i, j)] = s / djj;
        }
    }
    Ok(())
}

/// Solves `L Lᵀ x = b` in place, with `L` from [`cholesky`].
pub fn cholesky_solve<T: Scalar>(l: &DMatrix<T>, x: &mut DVector<T>) {
    let n = l.nrows();
    for i in 0..n {
        let mut s = x[i];
        for k in 0..i {
            s -= l[(i, k)] * x[k];
        }
        x[i] = s / l[(i, i)];
    }
    for i in (0..n).rev() {
        let mut s = x[i];
        for k in (i + 1)..n {
            s -= l[(k, i)] * x[k];
        }
        x[i] = s / l[(i, i)];
    }
}

/// `$body` with the constant `$N` set to `$n` for the common sizes of the small
/// dense kernels (their loops then have lengths known at compile time), to 0
/// otherwise (the kernel reads the length at run time).
macro_rules! by_size {
    ($n:expr, $N:ident => $body:expr) => {
        $crate::dynamics::linalg::by_size!(@sizes $n, $N, $body, 6, 7, 8, 9, 12, 18)
    };
    (@sizes $n:expr, $N:ident, $body:expr, $($k:literal),*) => {
        match $n {
            $($k => {
                const $N: usize = $k;
                $body
            })*
            _ => {
                const $N: usize = 0;
                $body
            }
        }
    };
}
pub(crate) use by_size;

/// [`cholesky`] on `f64` (same order; a column scaled by the pivot's reciprocal,
/// so last-bit differences) with the size known at
/// compile time for common sizes and the bounds checked once: the lower
/// triangle of `l` receives L with `h = L Lᵀ`; `h`'s lower triangle is read.
pub fn cholesky_fast(h: &DMatrix<f64>, l: &mut DMatrix<f64>) -> Result<(), usize> {
    let n = h.nrows();
    if h.ncols() != n || l.nrows() != n || l.ncols() != n {
        return cholesky(h, l);
    }
    let (hs, ls) = (h.as_slice(), l.as_mut_slice());
    by_size!(n, N => cholesky_n::<N>(hs, ls, n))
}

#[inline(always)]
fn cholesky_n<const N: usize>(h: &[f64], l: &mut [f64], n: usize) -> Result<(), usize> {
    let n = if N == 0 { n } else { N };
    let (h, l) = (&h[..n * n], &mut l[..n * n]);
    let tiny = 64.0 * f64::EPSILON;
    // SAFETY: all indices are r + n·c with r, c < n; both slices are n·n long.
    unsafe {
        for j in 0..n {
            let hjj = *h.get_unchecked(j * n + j);
            let mut d = hjj;
            for k in 0..j {
                let ljk = *l.get_unchecked(k * n + j);
                d -= ljk * ljk;
            }
            if !(d > tiny * hjj.abs()) || !d.is_finite() {
                return Err(j);
            }
            let djj = d.sqrt();
            *l.get_unchecked_mut(j * n + j) = djj;
            // one division a column (a multiply by the reciprocal below)
            let inv = 1.0 / djj;
            for i in (j + 1)..n {
                let mut s = *h.get_unchecked(j * n + i);
                for k in 0..j {
                    s -= *l.get_unchecked(k * n + i) * *l.get_unchecked(k * n + j);
                }
                *l.get_unchecked_mut(j * n + i) = s * inv;
            }
        }
    }
    Ok(())
}

/// Solves `L Lᵀ x = b` in place, `L` in the lower triangle of the column-major
/// `l` (n × n, from [`cholesky_fast`]), column-oriented so that both passes read
/// contiguous columns. Does nothing when the lengths do not fit.
pub fn chol_solve_slice(l: &[f64], n: usize, x: &mut [f64]) {
    if l.len() < n * n || x.len() < n {
        return;
    }
    by_size!(n, N => {
        chol_forward_n::<N>(l, n, x);
        chol_backward_n::<N>(l, n, x)
    })
}

/// `L x' = x` in place (forward substitution) for the factor of [`chol_solve_slice`].
pub fn chol_forward_slice(l: &[f64], n: usize, x: &mut [f64]) {
    if l.len() < n * n || x.len() < n {
        return;
    }
    by_size!(n, N => chol_forward_n::<N>(l, n, x))
}

/// `Lᵀ x' = x` in place (back substitution) for the factor of [`chol_solve_slice`].
pub fn chol_backward_slice(l: &[f64], n: usize, x: &mut [f64]) {
    if l.len() < n * n || x.len() < n {
        return;
    }
    by_size!(n, N => chol_backward_n::<N>(l, n, x))
}

/// L x' = x in place; `N = 0`: the length `n` at run time. The caller checked
/// `l.len() ≥ n²`, `x.len() ≥ n` (and `N ∈ {0, n}`).
#[inline(always)]
fn chol_forward_n<const N: usize>(l: &[f64], n: usize, x: &mut [f64]) {
    let n = if N == 0 { n } else { N };
    let (l, x) = (&l[..n * n], &mut x[..n]);
    // SAFETY: k, i < n; l is n·n long, x n long.
    unsafe {
        for k in 0..n {
            let xk = *x.get_unchecked(k) / *l.get_unchecked(k * n + k);
            *x.get_unchecked_mut(k) = xk;
            if xk != 0.0 {
                for i in k + 1..n {
                    *x.get_unchecked_mut(i) -= *l.get_unchecked(k * n + i) * xk;
                }
            }
        }
    }
}

/// Lᵀ x' = x in place (back substitution).
#[inline(always)]
fn chol_backward_n<const N: usize>(l: &[f64], n: usize, x: &mut [f64]) {
    let n = if N == 0 { n } else { N };
    let (l, x) = (&l[..n * n], &mut x[..n]);
    // SAFETY: k, i < n; l is n·n long, x n long.
    unsafe {
        for k in (0..n).rev() {
            let mut s = -0.0;
            for i in k + 1..n {
                s += *x.get_unchecked(i) * *l.get_unchecked(k * n + i);
            }
            *x.get_unchecked_mut(k) = (*x.get_unchecked(k) - s) / *l.get_unchecked(k * n + k);
        }
    }
}
