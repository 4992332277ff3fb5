//! The row algebra of the analytic step Jacobians (split from `analytic/mod.rs`):
//! the basic solve of the active set, its equality and sliding rows, and small
//! vector and matrix helpers, and the simulation's inverse-dynamics derivatives
//! and rolling radii the step Jacobians read.

use crate::contact::{ContactPoint, NO_GEOM};
use crate::dynamics::rnea_derivatives;
use crate::model::Shape;
use crate::sim::{SimError, Simulation};
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

/// Column c of Z0 += K[k, c] · column k of H̃⁻¹ over the 2n columns of K
/// (contiguous columns, K's structural zeros skipped); `N`: n when known at
/// compile time, else 0.
#[inline(always)]
pub(super) fn z0_product<const N: usize>(zs: &mut [f64], ms: &[f64], ks: &[f64], n: usize) {
    let n = if N == 0 { n } else { N };
    if zs.len() < 2 * n * n || ms.len() < n * n || ks.len() < 2 * n * n {
        return;
    }
    for c in 0..2 * n {
        let zc = &mut zs[c * n..(c + 1) * n];
        for k in 0..n {
            let x = ks[k + c * n];
            if x != 0.0 {
                for (z, &mi) in zc.iter_mut().zip(&ms[k * n..(k + 1) * n]) {
                    *z += mi * x;
                }
            }
        }
    }
}

/// `dst` ← `src`, reallocating only on a change of length.
pub(super) fn set(dst: &mut DVector<f64>, src: &DVector<f64>) {
    if dst.len() == src.len() {
        dst.copy_from(src);
    } else {
        *dst = src.clone();
    }
}

/// `m` of shape r × c, reallocated only on a change of shape (its entries
/// are left as they were: the caller writes every one it reads, or zeroes).
pub(super) fn shape(m: &mut DMatrix<f64>, r: usize, c: usize) {
    if m.shape() != (r, c) {
        *m = DMatrix::zeros(r, c);
    }
}

impl Simulation {
    /// ∂ID/∂q, ∂ID/∂v at (q, v, a) (tangent space; no external forces): the
    /// analytic [`rnea_derivatives`] (docs/theory.md §"Derivatives"), which
    /// leaves the simulation's kinematics at `q`.
    pub(in crate::sim::derivatives) fn id_derivatives(
        &mut self,
        q: &DVector<f64>,
        v: &DVector<f64>,
        a: &DVector<f64>,
    ) -> Result<(DMatrix<f64>, DMatrix<f64>), SimError> {
        rnea_derivatives(&self.model, &mut self.data, q, v, a, None)?;
        Ok((self.data.dtau_dq.clone(), self.data.dtau_dv.clone()))
    }

    /// The radius of a contact shape that rolls (sphere, capsule): its contact
    /// point is that far below the centre it moves with; 0 for vertices.
    pub(in crate::sim::derivatives) fn rolling_radius(&self, pt: &ContactPoint) -> f64 {
        if pt.other_geom != NO_GEOM {
            // an obstacle's point: a sphere or capsule rolls on it too
            return match self.model.collisions.get(pt.geom).map(|g| &g.shape) {
                Some(Shape::Sphere { radius }) | Some(Shape::Capsule { radius, .. }) => *radius,
                _ => 0.0,
            };
        }
        self.contact
            .as_ref()
            .and_then(|c| c.ground.as_ref())
            .and_then(|g| g.shapes.get(pt.shape))
            .map_or(0.0, |s| s.rolling_radius())
    }
}
