//! Analytic first-order derivatives of forward dynamics: ∂q̈/∂q, ∂q̈/∂v and
//! ∂q̈/∂τ = H⁻¹, from those of inverse dynamics at a = q̈ (docs/theory.md
//! §"Derivatives": q̈(q, v, τ) solves ID(q, v, q̈) = τ, so
//! ∂q̈/∂x = −H⁻¹ ∂ID/∂x).

use super::rnea_derivatives::{check_wrenches, rnea_derivatives_pass, LinkWrench};
use super::{check_massless, check_sizes, linalg, ltdl, DynamicsError};
use crate::model::{Data, Model};
use crate::spatial::ops::madd;
use crate::spatial::{Force, Scalar};
use nalgebra::{DMatrix, DVector};

const NONE: usize = usize::MAX;

/// The derivatives of forward dynamics q̈ = FD(q, v, τ) with the wrenches `fext`
/// (docs/theory.md §"Derivatives"): `data.dqdd_dq` = ∂q̈/∂q (tangent space, as
/// [`super::rnea_derivatives`]), `data.dqdd_dv` = ∂q̈/∂v, `data.minv` = H⁻¹ = ∂q̈/∂τ
/// (whole, symmetric; a floating base's first 6 columns are those of its body-frame
/// wrench), `data.qdd` = q̈. Every model: fixed, floating, mimic (the reduced system).
/// Route: q̈ by the engine's forward dynamics; ∂τ/∂q, ∂τ/∂v and H at a = q̈ by
/// [`super::rnea_derivatives`]; H factorised (tree-sparse LTDL, dense Cholesky with
/// mimic joints) and solved against the identity and both Jacobians. Also leaves
/// `data.dtau_dq`, `data.dtau_dv` (at a = q̈) and `data.h`. No allocation.
pub fn aba_derivatives<T: Scalar>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &DVector<T>,
    v: &DVector<T>,
    tau: &DVector<T>,
    fext: Option<&[LinkWrench<T>]>,
) -> Result<(), DynamicsError> {
    check_sizes(model, q, &[("v", v), ("tau", tau)], None)?;
    check_wrenches(model, fext)?;
    check_massless(model)?;
    let fext = fext.filter(|w| !w.is_empty());
    // the wrenches onto their bodies at this q (forward kinematics first)
    let mut fb = std::mem::take(&mut data.deriv_fext);
    if let Some(ws) = fext {
        super::forward_kinematics_pass(model, data, q);
        fb.fill(Force::zero());
        for w in ws {
            super::add_link_wrench(model, data, w.frame, &w.force, &w.torque, &mut fb)?;
        }
    }
    let r =
        super::forward_dynamics(model, data, q, v, tau, fext.map(|_| fb.as_slice())).map(|_| ());
    data.deriv_fext = fb;
    r?;
    // ∂τ/∂q, ∂τ/∂v and H at a = q̈
    let mut a = std::mem::replace(&mut data.deriv_tmp, DVector::zeros(0));
    a.copy_from(&data.qdd);
    rnea_derivatives_pass(model, data, q, v, &a, fext);
    data.deriv_tmp = a;
    // H = Lᵀ D L (tree) or L Lᵀ (mimic)
    if model.has_mimic {
        linalg::cholesky(&data.h, &mut data.chol).map_err(DynamicsError::Singular)?;
    } else {
        ltdl::ltdl(&data.h, &model.dof_parent, &mut data.chol).map_err(DynamicsError::Singular)?;
    }
    let nv = model.nv;
    let Data {
        chol,
        minv,
        dqdd_dq,
        dqdd_dv,
        dtau_dq,
        dtau_dv,
        deriv_scratch: xt,
        ..
    } = data;
    // H⁻¹ = solve(H, 1) (symmetric: its rows are its columns)
    minv.fill(T::zero());
    for k in 0..nv {
        minv[(k, k)] = T::one();
    }
    solve_rows(model, chol, minv.as_mut_slice());
    // ∂q̈/∂x = −solve(H, ∂τ/∂x), on the transpose (H X = B ⇔ Xᵀ H = Bᵀ: every
    // elimination step is one contiguous axpy over all right-hand sides)
    for (out, b) in [(&mut *dqdd_dq, &*dtau_dq), (&mut *dqdd_dv, &*dtau_dv)] {
        b.transpose_to(xt);
        solve_rows(model, chol, xt.as_mut_slice());
        xt.transpose_to(out);
        out.neg_mut();
    }
    Ok(())
}

/// `X ← H⁻¹ X` for X (nv × nv) given by its rows, row i contiguous at
/// `x[i nv..(i + 1) nv]` (a column-major Xᵀ), with the factor in `u`.
fn solve_rows<T: Scalar>(model: &Model<T>, u: &DMatrix<T>, x: &mut [T]) {
    let n = model.nv;
    let us = u.as_slice();
    let x = &mut x[..n * n];
    if model.has_mimic {
        chol_solve_rows(us, n, x);
    } else {
        ltdl_solve_rows(us, &model.dof_parent, x);
    }
}

/// `row_a −= s · row_b` of a row-contiguous n × n matrix (a ≠ b).
#[inline(always)]
fn row_axpy<T: Scalar>(x: &mut [T], n: usize, a: usize, b: usize, s: T) {
    let (ra, rb) = if a < b {
        let (lo, hi) = x.split_at_mut(b * n);
        (&mut lo[a * n..a * n + n], &hi[..n])
    } else {
        let (lo, hi) = x.split_at_mut(a * n);
        (&mut hi[..n], &lo[b * n..b * n + n])
    };
    for (p, &q) in ra.iter_mut().zip(rb) {
        *p = madd(-s, q, *p);
    }
}

/// [`ltdl::ltdl_solve`] for every right-hand side at once (rows of `x`).
fn ltdl_solve_rows<T: Scalar>(u: &[T], lambda: &[usize], x: &mut [T]) {
    let n = lambda.len();
    // Lᵀ y = b, leaves inwards
    for i in (0..n).rev() {
        let mut j = lambda[i];
        while j != NONE {
            row_axpy(x, n, j, i, u[j + i * n]);
            j = lambda[j];
        }
    }
    // z = D⁻¹ y
    for i in 0..n {
        let d = T::one() / u[i + i * n];
        for p in &mut x[i * n..i * n + n] {
            *p *= d;
        }
    }
    // L x = z, root outwards
    for i in 0..n {
        let mut j = lambda[i];
        while j != NONE {
            row_axpy(x, n, i, j, u[j + i * n]);
            j = lambda[j];
        }
    }
}

/// [`linalg::cholesky_solve`] for every right-hand side at once (rows of `x`).
fn chol_solve_rows<T: Scalar>(l: &[T], n: usize, x: &mut [T]) {
    for i in 0..n {
        for k in 0..i {
            row_axpy(x, n, i, k, l[i + k * n]);
        }
        let d = T::one() / l[i + i * n];
        for p in &mut x[i * n..i * n + n] {
            *p *= d;
        }
    }
    for i in (0..n).rev() {
        for k in (i + 1)..n {
            row_axpy(x, n, i, k, l[k + i * n]);
        }
        let d = T::one() / l[i + i * n];
        for p in &mut x[i * n..i * n + n] {
            *p *= d;
        }
    }
}
