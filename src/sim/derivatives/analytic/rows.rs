//! The row algebra of the analytic step Jacobians (split from `analytic/mod.rs`):
//! the basic solve of the active set, its equality and sliding rows, and small
//! vector helpers.

use nalgebra::{DMatrix, DVector, Vector3};

/// M X = R by Gaussian elimination with complete pivoting (M square), stopped
/// at the first pivot below `tol` times the first (the largest entry): the
/// unknowns of the pivots left are 0, a basic solution where R lies in M's range.
pub(in crate::sim::derivatives) fn solve_basic(
    mut a: DMatrix<f64>,
    mut b: DMatrix<f64>,
    tol: f64,
) -> DMatrix<f64> {
    let (m, nc) = (a.nrows(), b.ncols());
    // unknown perm[k] sits in column k
    let mut perm: Vec<usize> = (0..m).collect();
    let (mut rank, mut first) = (0, 0.0);
    for k in 0..m {
        let (mut pi, mut pj, mut pv) = (k, k, 0.0);
        for j in k..m {
            for i in k..m {
                if a[(i, j)].abs() > pv {
                    (pi, pj, pv) = (i, j, a[(i, j)].abs());
                }
            }
        }
        if k == 0 {
            first = pv;
        }
        if pv <= tol * first {
            break;
        }
        a.swap_rows(k, pi);
        b.swap_rows(k, pi);
        a.swap_columns(k, pj);
        perm.swap(k, pj);
        // row i −= (a_ik / a_kk) row k below the pivot
        for i in k + 1..m {
            let f = a[(i, k)] / a[(k, k)];
            if f != 0.0 {
                for j in k..m {
                    a[(i, j)] -= f * a[(k, j)];
                }
                for c in 0..nc {
                    b[(i, c)] -= f * b[(k, c)];
                }
            }
        }
        rank = k + 1;
    }
    // back substitution over the kept pivots, x[perm[k]] = y[k]
    let mut x = DMatrix::zeros(m, nc);
    let mut y = vec![0.0; rank];
    for c in 0..nc {
        for k in (0..rank).rev() {
            let mut t = b[(k, c)];
            for j in k + 1..rank {
                t -= a[(k, j)] * y[j];
            }
            y[k] = t / a[(k, k)];
        }
        for k in 0..rank {
            x[(perm[k], c)] = y[k];
        }
    }
    x
}

/// One equality row δu_r = δb_r of the active set: W_r δλ = δb_r − C'_r, with
/// δb = −J_r δq / h while the row's gap is open (b < 0), else 0.
#[allow(clippy::too_many_arguments)]
pub(super) fn equality_row(
    mm: &mut DMatrix<f64>,
    rr: &mut DMatrix<f64>,
    w: &DMatrix<f64>,
    cq: &DMatrix<f64>,
    jac: &DMatrix<f64>,
    b: f64,
    r: usize,
    n: usize,
    h: f64,
) {
    for k in 0..w.ncols() {
        mm[(r, k)] = w[(r, k)];
    }
    for c in 0..3 * n {
        rr[(r, c)] = -cq[(r, c)];
    }
    if b < 0.0 {
        for c in 0..n {
            rr[(r, c)] -= jac[(r, c)] / h;
        }
    }
}

/// A sliding torsional or rolling pair at rows `r`, `r + 1` (normal row
/// `normal`): λ = −μ λₙ û, linearised as the Coulomb pair's
/// δλ + μ û δλₙ + κ P δu = 0 (κ = μλₙ/‖u‖, P = I − ûûᵀ).
#[allow(clippy::too_many_arguments)]
pub(super) fn spin_sliding(
    mm: &mut DMatrix<f64>,
    rr: &mut DMatrix<f64>,
    w: &DMatrix<f64>,
    cq: &DMatrix<f64>,
    (r, normal): (usize, usize),
    kappa: f64,
    mu: f64,
    uh: [f64; 2],
) {
    for a in 0..2 {
        let ra = r + a;
        mm[(ra, ra)] += 1.0;
        mm[(ra, normal)] += mu * uh[a];
        for b in 0..2 {
            let p = if a == b { 1.0 } else { 0.0 } - uh[a] * uh[b];
            let rb = r + b;
            for k in 0..w.ncols() {
                mm[(ra, k)] += kappa * p * w[(rb, k)];
            }
            for c in 0..cq.ncols() {
                rr[(ra, c)] -= kappa * p * cq[(rb, c)];
            }
        }
    }
}

/// Row i of `a` dotted with row r of `b` (as many columns).
pub(super) fn dot_rows(a: &DMatrix<f64>, i: usize, b: &DMatrix<f64>, r: usize) -> f64 {
    (0..a.ncols()).map(|k| a[(i, k)] * b[(r, k)]).sum()
}

pub(super) fn cq_row_dot(jac: &DMatrix<f64>, r: usize, v: &DVector<f64>) -> f64 {
    jac.row(r).transpose().dot(v)
}

pub(super) fn omega(v: &DVector<f64>) -> Vector3<f64> {
    Vector3::new(v[3], v[4], v[5])
}
pub(super) fn lin(v: &DVector<f64>) -> Vector3<f64> {
    Vector3::new(v[0], v[1], v[2])
}

/// Whether every null vector ν of the active set's matrix M (its SVD, singular
/// values at most `tol` counted as zero) leaves the velocity alone: `Y ν = 0`
/// with Y = H̃⁻¹Jᵀ, to 1e-9 of Y's size. Then every solution δλ of M δλ = R
/// gives the same δv⁺ = Z₀ + Y δλ.
pub(super) fn velocity_determined(
    svd: &nalgebra::SVD<f64, nalgebra::Dyn, nalgebra::Dyn>,
    tol: f64,
    y: &DMatrix<f64>,
) -> bool {
    let Some(vt) = svd.v_t.as_ref() else {
        return false;
    };
    let scale = y.amax().max(1e-300);
    for (k, &s) in svd.singular_values.iter().enumerate() {
        if s > tol {
            continue;
        }
        let nu = vt.row(k).transpose();
        if (y * nu).amax() > 1e-9 * scale {
            return false;
        }
    }
    true
}
