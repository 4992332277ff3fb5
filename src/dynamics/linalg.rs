//! Dense symmetric positive-definite factorisation in place (no allocation).

use crate::spatial::ops::madd;
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

/// [`cholesky_solve`] for `w` right-hand sides at once, stored as the rows of
/// the n × w row-contiguous `x` (`x[i w + j]`: entry i of right-hand side j):
/// every elimination step is one contiguous axpy over all of them.
pub fn cholesky_solve_rows<T: Scalar>(l: &DMatrix<T>, w: usize, x: &mut [T]) {
    let n = l.nrows();
    let l = l.as_slice();
    let x = &mut x[..n * w];
    for i in 0..n {
        let (done, rest) = x.split_at_mut(i * w);
        let xi = &mut rest[..w];
        for k in 0..i {
            let s = l[i + k * n];
            for (p, &q) in xi.iter_mut().zip(&done[k * w..(k + 1) * w]) {
                *p = madd(-s, q, *p);
            }
        }
        let d = T::one() / l[i + i * n];
        xi.iter_mut().for_each(|p| *p *= d);
    }
    for i in (0..n).rev() {
        let (head, tail) = x.split_at_mut((i + 1) * w);
        let xi = &mut head[i * w..];
        for k in (i + 1)..n {
            let s = l[k + i * n];
            let o = (k - i - 1) * w;
            for (p, &q) in xi.iter_mut().zip(&tail[o..o + w]) {
                *p = madd(-s, q, *p);
            }
        }
        let d = T::one() / l[i + i * n];
        xi.iter_mut().for_each(|p| *p *= d);
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

/// `A = L D Lᵀ` in place for the symmetric positive semi-definite m × m `a`
/// (row-major, lower triangle read): L, unit lower, below the diagonal, D on
/// it. A pivot left with no more than `drop` of its diagonal marks a row
/// dependent on earlier ones: its D is set to 0 and its column of L to 0, so
/// that [`ldlt_dropping_solve`] gives it x = 0 (a consistent system stays
/// solved on the others). Does nothing when `a` is shorter than m².
pub fn ldlt_dropping(a: &mut [f64], m: usize, drop: f64) {
    if a.len() < m * m {
        return;
    }
    for j in 0..m {
        let diag = a[j * m + j];
        let mut dj = diag;
        for k in 0..j {
            let dk = a[k * m + k];
            if dk != 0.0 {
                let l = a[j * m + k];
                dj -= l * l * dk;
            }
        }
        let dj = if dj > drop * diag && dj > 0.0 {
            dj
        } else {
            0.0
        };
        a[j * m + j] = dj;
        for i in j + 1..m {
            let mut s = a[i * m + j];
            for k in 0..j {
                let dk = a[k * m + k];
                if dk != 0.0 {
                    s -= a[i * m + k] * a[j * m + k] * dk;
                }
            }
            a[i * m + j] = if dj != 0.0 { s / dj } else { 0.0 };
        }
    }
}

/// Solves `L D Lᵀ x = b` in place with the factor of [`ldlt_dropping`]; a
/// dropped row (D = 0) gets x = 0. Does nothing when the lengths do not fit.
pub fn ldlt_dropping_solve(a: &[f64], m: usize, x: &mut [f64]) {
    if a.len() < m * m || x.len() < m {
        return;
    }
    // L z = b, z /= D, Lᵀ x = z
    for i in 0..m {
        let mut s = x[i];
        for k in 0..i {
            s -= a[i * m + k] * x[k];
        }
        x[i] = s;
    }
    for i in 0..m {
        let d = a[i * m + i];
        x[i] = if d != 0.0 { x[i] / d } else { 0.0 };
    }
    for i in (0..m).rev() {
        if a[i * m + i] == 0.0 {
            x[i] = 0.0;
            continue;
        }
        let mut s = x[i];
        for k in i + 1..m {
            s -= a[k * m + i] * x[k];
        }
        x[i] = s;
    }
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

/// `A = L D Lᵀ` of a symmetric positive-definite 6 × 6 matrix (its lower
/// triangle read) with fixed loop bounds the compiler unrolls: L's strict lower
/// triangle (unit diagonal implied) and D⁻¹. `None` when a pivot is at most 64 ε
/// times its diagonal entry, or not finite (as [`cholesky`]).
#[inline(always)]
fn spd6_ldl<T: Scalar>(a: &nalgebra::Matrix6<T>) -> Option<([[T; 6]; 6], [T; 6])> {
    let tiny = lit::<T>(64.0 * f64::EPSILON);
    let mut l = [[T::zero(); 6]; 6];
    let mut dinv = [T::zero(); 6];
    // ld[i][k] = L[i, k] D[k]
    let mut ld = [[T::zero(); 6]; 6];
    for j in 0..6 {
        let mut d = a[(j, j)];
        for k in 0..j {
            d = madd(-l[j][k], ld[j][k], d);
        }
        if !(d > tiny * a[(j, j)].abs()) || !d.is_finite() {
            return None;
        }
        let di = T::one() / d;
        dinv[j] = di;
        for i in (j + 1)..6 {
            let mut s = a[(i, j)];
            for k in 0..j {
                s = madd(-l[i][k], ld[j][k], s);
            }
            ld[i][j] = s;
            l[i][j] = s * di;
        }
    }
    Some((l, dinv))
}

/// The inverse of a symmetric positive-definite 6 × 6 matrix (its lower
/// triangle read) by `L D Lᵀ` with fixed loop bounds the compiler unrolls:
/// `A⁻¹ = L⁻ᵀ D⁻¹ L⁻¹`, about 200 multiply-adds against a generic Cholesky's
/// two triangular solves on six columns. `None` when a pivot is at most 64 ε
/// times its diagonal entry, or not finite (as [`cholesky`]).
#[inline]
pub fn spd6_inverse<T: Scalar>(a: &nalgebra::Matrix6<T>) -> Option<nalgebra::Matrix6<T>> {
    let (l, dinv) = spd6_ldl(a)?;
    // M = L⁻¹ (unit lower triangular), column by column
    let mut m = [[T::zero(); 6]; 6];
    for j in 0..6 {
        m[j][j] = T::one();
        for i in (j + 1)..6 {
            let mut s = -l[i][j];
            for k in (j + 1)..i {
                s = madd(-l[i][k], m[k][j], s);
            }
            m[i][j] = s;
        }
    }
    // A⁻¹[r, c] = Σ_{k ≥ max(r, c)} M[k, r] M[k, c] / D[k]
    let mut x = nalgebra::Matrix6::<T>::zeros();
    for r in 0..6 {
        for c in 0..=r {
            let mut s = T::zero();
            for k in r..6 {
                s = madd(m[k][r] * dinv[k], m[k][c], s);
            }
            x[(r, c)] = s;
            x[(c, r)] = s;
        }
    }
    Some(x)
}

/// Solves `a x = b` for a symmetric positive-definite 6x6 `a` (lower triangle
/// read) by `L D Lᵀ` with fixed loop bounds (as [`spd6_inverse`]); `None` when a
/// pivot is at most 64 ε times its diagonal entry, or not finite.
#[inline]
pub(crate) fn spd6_solve<T: Scalar>(
    a: &nalgebra::Matrix6<T>,
    b: &nalgebra::Vector6<T>,
) -> Option<nalgebra::Vector6<T>> {
    let (l, dinv) = spd6_ldl(a)?;
    Some(ldl6_solve(|i, k| l[i][k], &dinv, b))
}

/// `A = L D Lᵀ` of [`spd6_solve`] for a caller that keeps it: L's strict
/// lower triangle packed by rows (`L[i, k]` at `i (i − 1) / 2 + k`, k < i)
/// and D⁻¹; `None` as [`spd6_solve`].
#[inline]
pub(crate) fn spd6_factor(a: &nalgebra::Matrix6<f64>) -> Option<([f64; 15], [f64; 6])> {
    let (l, dinv) = spd6_ldl(a)?;
    let mut packed = [0.0; 15];
    for i in 1..6 {
        for k in 0..i {
            packed[i * (i - 1) / 2 + k] = l[i][k];
        }
    }
    Some((packed, dinv))
}

/// `x = A⁻¹ b` from `A = L D Lᵀ` (`l(i, k)` = L's entry, k < i; `dinv` = D⁻¹):
/// L y = b, z = D⁻¹ y, Lᵀ x = z, with fixed loop bounds (unrolled).
#[inline(always)]
pub(crate) fn ldl6_solve<T: Scalar>(
    l: impl Fn(usize, usize) -> T,
    dinv: &[T; 6],
    b: &nalgebra::Vector6<T>,
) -> nalgebra::Vector6<T> {
    let mut x = [T::zero(); 6];
    for i in 0..6 {
        let mut s = b[i];
        for k in 0..i {
            s = madd(-l(i, k), x[k], s);
        }
        x[i] = s;
    }
    for i in 0..6 {
        x[i] *= dinv[i];
    }
    for i in (0..6).rev() {
        let mut s = x[i];
        for k in (i + 1)..6 {
            s = madd(-l(k, i), x[k], s);
        }
        x[i] = s;
    }
    nalgebra::Vector6::from_column_slice(&x)
}
