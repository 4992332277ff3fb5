//! The least-norm solve of the constraint rows' operator `K = J_c H⁻¹ J_cᵀ`
//! (symmetric positive semi-definite, m × m), docs/theory.md §"Constrained
//! dynamics", "Redundant rows": a Cholesky factor when K is well inside full
//! rank, else K's eigendecomposition by cyclic Jacobi rotations and the
//! pseudo-inverse `K⁺ = V Λ⁺ Vᵀ`, which gives the least-norm λ of a consistent
//! system. No allocation: every buffer is sized once.

use super::linalg::by_size;
use crate::spatial::ops::madd;
use nalgebra::{DMatrix, DVector};

/// An eigenvalue (or Cholesky pivot) at most this fraction of the largest
/// (of its diagonal entry) marks a dependent row.
const RANK_TOL: f64 = 1e-10;

/// The factor of K and the buffers of its solves.
#[derive(Clone, Debug)]
pub(crate) struct KktFactor {
    /// m × m: the Cholesky factor (lower) or the eigenvectors (columns).
    f: DMatrix<f64>,
    /// m × m: K, rotated to its eigenvalues (eigen route only).
    w: DMatrix<f64>,
    /// The eigenvalues, with 0 where dropped (eigen route only).
    ev: DVector<f64>,
    /// Scratch of size m.
    t: DVector<f64>,
    /// The reciprocals of the Cholesky factor's diagonal (full rank).
    dinv: Vec<f64>,
    /// Whether `f` is a Cholesky factor (K of full rank).
    pub full_rank: bool,
}

impl KktFactor {
    /// Buffers for m rows.
    pub fn new(m: usize) -> Self {
        Self {
            f: DMatrix::zeros(m, m),
            w: DMatrix::zeros(m, m),
            ev: DVector::zeros(m),
            t: DVector::zeros(m),
            dinv: vec![0.0; m],
            full_rank: true,
        }
    }

    /// Factorises K (its lower triangle is read).
    pub fn factor(&mut self, k: &DMatrix<f64>) {
        let m = k.nrows();
        self.full_rank = cholesky(k, &mut self.f, &mut self.dinv);
        if self.full_rank {
            return;
        }
        self.w.copy_from(k);
        for i in 0..m {
            for j in i + 1..m {
                self.w[(i, j)] = self.w[(j, i)];
            }
        }
        jacobi_eigen(&mut self.w, &mut self.f, &mut self.ev);
        // f now holds V (columns), ev the eigenvalues
        let top = self.ev.iter().fold(0.0f64, |a, &x| a.max(x));
        for x in self.ev.iter_mut() {
            // NaN too
            if x.is_nan() || *x <= RANK_TOL * top {
                *x = 0.0;
            }
        }
    }

    /// `x ← K⁺ x` (K⁻¹ x at full rank).
    pub fn solve(&mut self, x: &mut [f64]) {
        let m = self.t.len();
        if self.full_rank {
            let (l, dinv) = (self.f.as_slice(), &self.dinv[..]);
            by_size!(m, N => cholesky_solve_n::<N>(l, dinv, x, m));
            return;
        }
        // V Λ⁺ Vᵀ x
        for j in 0..m {
            let e = self.ev[j];
            self.t[j] = if e > 0.0 {
                (0..m).map(|i| self.f[(i, j)] * x[i]).sum::<f64>() / e
            } else {
                0.0
            };
        }
        for (i, xi) in x.iter_mut().enumerate().take(m) {
            *xi = (0..m).map(|j| self.f[(i, j)] * self.t[j]).sum();
        }
    }

    /// The part of `r` outside K's range (the eigen route's dropped directions),
    /// as a vector in `out` (zero at full rank): J_c q̈ = −γ_c is consistent iff
    /// this is zero.
    pub fn out_of_range(&mut self, r: &[f64], out: &mut [f64]) {
        let m = self.t.len();
        out[..m].fill(0.0);
        if self.full_rank {
            return;
        }
        for j in 0..m {
            if self.ev[j] > 0.0 {
                continue;
            }
            let c: f64 = (0..m).map(|i| self.f[(i, j)] * r[i]).sum();
            for (i, o) in out.iter_mut().enumerate().take(m) {
                *o += c * self.f[(i, j)];
            }
        }
    }
}

impl KktFactor {
    /// `y ← y S` for an n × m `y`, with `K⁺ = S Sᵀ` (docs/theory.md
    /// §"Constrained dynamics", "Derivatives"): `S = L⁻ᵀ` at full rank (the
    /// columns by forward substitution, in place), else `S = V Λ^{+½}` (the
    /// dropped eigenvalues' columns zero; `scratch` n × m).
    pub fn right_half(&self, y: &mut DMatrix<f64>, scratch: &mut DMatrix<f64>) {
        let (n, m) = (y.nrows(), self.t.len());
        if self.full_rank {
            let l = self.f.as_slice();
            let ys = y.as_mut_slice();
            for j in 0..m {
                let (done, rest) = ys.split_at_mut(j * n);
                let yj = &mut rest[..n];
                for k in 0..j {
                    let ljk = l[j + k * m];
                    for (x, &z) in yj.iter_mut().zip(&done[k * n..(k + 1) * n]) {
                        *x = madd(-ljk, z, *x);
                    }
                }
                let d = 1.0 / l[j + j * m];
                yj.iter_mut().for_each(|x| *x *= d);
            }
            return;
        }
        mul_add(scratch, 1.0, y, &self.f, 0.0);
        for j in 0..m {
            let e = self.ev[j];
            let d = if e > 0.0 { 1.0 / e.sqrt() } else { 0.0 };
            for i in 0..n {
                y[(i, j)] = scratch[(i, j)] * d;
            }
        }
    }
}

/// `k = L Lᵀ` into `l` (lower triangle), the reciprocals of L's diagonal into
/// `dinv`; false when a pivot is at most [`RANK_TOL`] of its diagonal entry (or
/// not finite). Column by column (left-looking): column j of L is K's column j
/// below the diagonal less the earlier columns' contiguous axpys, then scaled
/// by one reciprocal.
fn cholesky(k: &DMatrix<f64>, l: &mut DMatrix<f64>, dinv: &mut [f64]) -> bool {
    // the size known at compile time for the common row counts (four 3-D feet,
    // two 6-D soles: 12), so that the short columns' loops unroll; the same
    // operations in the same order at every size
    by_size!(k.nrows(), N => cholesky_n::<N>(k, l, dinv))
}

/// [`cholesky`] with `N` = K's size when known at compile time, else 0.
#[inline(always)]
fn cholesky_n<const N: usize>(k: &DMatrix<f64>, l: &mut DMatrix<f64>, dinv: &mut [f64]) -> bool {
    let m = if N == 0 { k.nrows() } else { N };
    let ks = &k.as_slice()[..m * m];
    let ls = &mut l.as_mut_slice()[..m * m];
    for j in 0..m {
        let (done, rest) = ls.split_at_mut(j * m);
        let colj = &mut rest[j..m];
        colj.copy_from_slice(&ks[j * m + j..(j + 1) * m]);
        for p in 0..j {
            let ljp = done[j + p * m];
            for (x, &y) in colj.iter_mut().zip(&done[p * m + j..(p + 1) * m]) {
                *x = madd(-ljp, y, *x);
            }
        }
        let d = colj[0];
        if d.is_nan() || d <= RANK_TOL * ks[j + j * m].abs() || !d.is_finite() {
            return false;
        }
        let d = d.sqrt();
        let r = 1.0 / d;
        colj[0] = d;
        dinv[j] = r;
        for x in colj[1..].iter_mut() {
            *x *= r;
        }
    }
    true
}

/// `x ← (L Lᵀ)⁻¹ x` from [`cholesky`]'s L (column-major, L[i, k] at i + k m)
/// and the reciprocals of its diagonal; `N` = m when known at compile time, else 0.
#[inline(always)]
fn cholesky_solve_n<const N: usize>(l: &[f64], dinv: &[f64], x: &mut [f64], m: usize) {
    let m = if N == 0 { m } else { N };
    let (l, dinv, x) = (&l[..m * m], &dinv[..m], &mut x[..m]);
    // L y = x
    for k in 0..m {
        let xk = x[k] * dinv[k];
        x[k] = xk;
        for (xi, &lik) in x[k + 1..].iter_mut().zip(&l[k * m + k + 1..(k + 1) * m]) {
            *xi = madd(-lik, xk, *xi);
        }
    }
    // Lᵀ x = y
    for i in (0..m).rev() {
        let col = &l[i * m + i + 1..(i + 1) * m];
        let mut s = x[i];
        for (&a, &b) in col.iter().zip(&x[i + 1..]) {
            s = madd(-a, b, s);
        }
        x[i] = s * dinv[i];
    }
}

/// The eigendecomposition of the symmetric `v` by cyclic Jacobi rotations: `v`
/// is rotated towards its diagonal (the eigenvalues, written to `ev`) and `q`
/// receives the eigenvectors as columns.
fn jacobi_eigen(v: &mut DMatrix<f64>, q: &mut DMatrix<f64>, ev: &mut DVector<f64>) {
    let m = v.nrows();
    q.as_mut_slice().fill(0.0);
    for i in 0..m {
        q[(i, i)] = 1.0;
    }
    for _sweep in 0..64 {
        let mut off = 0.0;
        let mut diag = 0.0;
        for i in 0..m {
            diag += v[(i, i)] * v[(i, i)];
            for j in i + 1..m {
                off += v[(i, j)] * v[(i, j)];
            }
        }
        if off <= 1e-34 * diag || off == 0.0 {
            break;
        }
        for p in 0..m {
            for r in p + 1..m {
                let apr = v[(p, r)];
                if apr == 0.0 {
                    continue;
                }
                // the rotation that zeroes v[p, r]: t = tan φ, the smaller root
                let theta = (v[(r, r)] - v[(p, p)]) / (2.0 * apr);
                let t = if theta >= 0.0 { 1.0 } else { -1.0 }
                    / (theta.abs() + (theta * theta + 1.0).sqrt());
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..m {
                    let (x, y) = (v[(k, p)], v[(k, r)]);
                    v[(k, p)] = c * x - s * y;
                    v[(k, r)] = s * x + c * y;
                }
                for k in 0..m {
                    let (x, y) = (v[(p, k)], v[(r, k)]);
                    v[(p, k)] = c * x - s * y;
                    v[(r, k)] = s * x + c * y;
                }
                for k in 0..m {
                    let (x, y) = (q[(k, p)], q[(k, r)]);
                    q[(k, p)] = c * x - s * y;
                    q[(k, r)] = s * x + c * y;
                }
            }
        }
    }
    for i in 0..m {
        ev[i] = v[(i, i)];
    }
}

/// K += D⁻¹ₖ xᵀ x over K's columns `lo..lo + x.len()` (K[s, r] at s + r m;
/// `x` a row of W = L⁻ᵀ J_cᵀ on its span, zero elsewhere): one axpy a column
/// (vectorised); the entries below the diagonal are overwritten when the
/// callers mirror the upper triangle.
#[inline(always)]
pub(crate) fn add_rank1(k: &mut [f64], m: usize, lo: usize, x: &[f64], dinv: f64) {
    for (r, &xr) in (lo..).zip(x) {
        if xr == 0.0 {
            continue;
        }
        let a = xr * dinv;
        for (y, &xs) in k[r * m + lo..r * m + lo + x.len()].iter_mut().zip(x) {
            *y = madd(a, xs, *y);
        }
    }
}

/// `c ← β c + α a b` for column-major matrices, allocation-free (nalgebra's
/// `gemm` packs through the heap for larger sizes): register tiles of R × 4
/// accumulators (R = 16, 8, 4, 2, 1 down the rows), each column of `a` read once
/// per tile, the sums added to c at the end.
pub(crate) fn mul_add(
    c: &mut DMatrix<f64>,
    alpha: f64,
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    beta: f64,
) {
    debug_assert!(c.ncols() == b.ncols() && b.nrows() == a.ncols());
    let kk = a.ncols();
    gemm(c, alpha, a, b.as_slice(), (1, kk), beta);
}

/// `c ← β c + α a bᵀ` (b is c's columns × a's columns), as [`mul_add`].
pub(crate) fn mul_add_bt(
    c: &mut DMatrix<f64>,
    alpha: f64,
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    beta: f64,
) {
    debug_assert!(c.ncols() == b.nrows() && b.ncols() == a.ncols());
    let n = b.nrows();
    gemm(c, alpha, a, b.as_slice(), (n, 1), beta);
}

/// `c ← β c + α a b` with `b[k, j]` at `b[k s₀ + j s₁]`, `(s₀, s₁) = bs`.
fn gemm(
    c: &mut DMatrix<f64>,
    alpha: f64,
    a: &DMatrix<f64>,
    b: &[f64],
    bs: (usize, usize),
    beta: f64,
) {
    let (m, n, kk) = (a.nrows(), c.ncols(), a.ncols());
    debug_assert!(c.nrows() == m);
    let (a, c) = (a.as_slice(), c.as_mut_slice());
    if beta == 0.0 {
        c.fill(0.0);
    } else if beta != 1.0 {
        c.iter_mut().for_each(|x| *x *= beta);
    }
    let g = Gemm {
        m,
        kk,
        alpha,
        a,
        b,
        bs,
    };
    let mut i0 = 0;
    while i0 + 16 <= m {
        g.panel::<16>(n, c, i0);
        i0 += 16;
    }
    for r in [8, 4, 2, 1] {
        if i0 + r <= m {
            match r {
                8 => g.panel::<8>(n, c, i0),
                4 => g.panel::<4>(n, c, i0),
                2 => g.panel::<2>(n, c, i0),
                _ => g.panel::<1>(n, c, i0),
            }
            i0 += r;
        }
    }
}

/// The operands of one [`mul_add`].
struct Gemm<'a> {
    m: usize,
    kk: usize,
    alpha: f64,
    a: &'a [f64],
    b: &'a [f64],
    bs: (usize, usize),
}

impl Gemm<'_> {
    /// Rows `i0..i0 + R` of every column: blocks of 4, then single columns.
    #[inline(always)]
    fn panel<const R: usize>(&self, n: usize, c: &mut [f64], i0: usize) {
        let mut j0 = 0;
        while j0 + 4 <= n {
            self.tile::<R, 4>(c, i0, j0);
            j0 += 4;
        }
        while j0 < n {
            self.tile::<R, 1>(c, i0, j0);
            j0 += 1;
        }
    }

    /// `c[i0.., j0..] += α Σₖ a[i0.., k] b[k, j0..]`, an R × C tile.
    #[inline(always)]
    fn tile<const R: usize, const C: usize>(&self, c: &mut [f64], i0: usize, j0: usize) {
        let (m, kk, (s0, s1)) = (self.m, self.kk, self.bs);
        let mut acc = [[0.0; R]; C];
        for k in 0..kk {
            let ak = &self.a[k * m + i0..][..R];
            for (q, aq) in acc.iter_mut().enumerate() {
                let bk = self.b[k * s0 + (j0 + q) * s1];
                for r in 0..R {
                    aq[r] = madd(ak[r], bk, aq[r]);
                }
            }
        }
        for q in 0..C {
            let col = &mut c[(j0 + q) * m + i0..(j0 + q) * m + i0 + R];
            for r in 0..R {
                col[r] = madd(self.alpha, acc[q][r], col[r]);
            }
        }
    }
}
