//! Analytic first-order derivatives of forward dynamics: ∂q̈/∂q, ∂q̈/∂v and
//! ∂q̈/∂τ = H⁻¹, from those of inverse dynamics at a = q̈ (docs/theory.md
//! §"Derivatives": q̈(q, v, τ) solves ID(q, v, q̈) = τ, so
//! ∂q̈/∂x = −H⁻¹ ∂ID/∂x; H⁻¹ from the world-frame ABA of `minv.rs`, "Inverse of
//! H"; the products over ∂ID/∂x's tree pattern, "The products").

use super::rnea_derivatives::{check_wrenches, rnea_derivatives_pass, LinkWrench};
use super::{check_massless, check_sizes, linalg, minv, DynamicsError};
use crate::model::{Data, Model};
use crate::spatial::ops::madd;
use crate::spatial::{Force, Scalar};
use nalgebra::{DMatrix, DVector};

/// The derivatives of forward dynamics q̈ = FD(q, v, τ) with the wrenches `fext`
/// (docs/theory.md §"Derivatives"): `data.dqdd_dq` = ∂q̈/∂q (tangent space, as
/// [`super::rnea_derivatives`]), `data.dqdd_dv` = ∂q̈/∂v, `data.minv` = H⁻¹ = ∂q̈/∂τ
/// (whole, symmetric; a floating base's first 6 columns are those of its body-frame
/// wrench), `data.qdd` = q̈. Every model: fixed, floating, mimic (the reduced system).
/// Route (docs/theory.md §"Derivatives", "Forward dynamics"): q̈ and H⁻¹ by the
/// articulated-body recursion in world coordinates ("Inverse of H", O(n·nv));
/// ∂τ/∂q, ∂τ/∂v at a = q̈ by [`super::rnea_derivatives`]; ∂q̈/∂x = −H⁻¹ ∂τ/∂x by
/// register-tiled products that read only ∂τ/∂x's tree pattern ("The products").
/// With mimic joints: q̈ by the engine's forward dynamics, H by the derivative
/// sweep, dense Cholesky solves against the identity and both Jacobians. Also
/// leaves `data.dtau_dq`, `data.dtau_dv` (at a = q̈) and `data.h`. No allocation.
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
    if !model.has_mimic {
        // q̈ and H⁻¹ by the world-frame ABA (docs/theory.md §"Derivatives",
        // "Inverse of H")
        let r = minv::minv_pass(model, data, q, v, tau, fext.map(|_| fb.as_slice()));
        data.deriv_fext = fb;
        r?;
        // ∂τ/∂q, ∂τ/∂v at a = q̈
        let mut a = std::mem::replace(&mut data.deriv_tmp, DVector::zeros(0));
        a.copy_from(&data.qdd);
        rnea_derivatives_pass(model, data, q, v, &a, fext);
        data.deriv_tmp = a;
        // ∂q̈/∂x = −H⁻¹ ∂τ/∂x over ∂τ/∂x's tree pattern
        let Data {
            minv,
            dqdd_dq,
            dqdd_dv,
            dtau_dq,
            dtau_dv,
            deriv_dof_end: dof_end,
            deriv_anc_runs: runs,
            deriv_anc_run0: run0,
            ..
        } = data;
        let pat = TreePattern {
            dof_end,
            runs,
            run0,
        };
        neg_mul_tree(minv, [dtau_dq, dtau_dv], [dqdd_dq, dqdd_dv], &pat);
        return Ok(());
    }
    // mimic joints: the reduced H is not tree-shaped, the dense route
    let r =
        super::forward_dynamics(model, data, q, v, tau, fext.map(|_| fb.as_slice())).map(|_| ());
    data.deriv_fext = fb;
    r?;
    // ∂τ/∂q, ∂τ/∂v and H at a = q̈
    let mut a = std::mem::replace(&mut data.deriv_tmp, DVector::zeros(0));
    a.copy_from(&data.qdd);
    rnea_derivatives_pass(model, data, q, v, &a, fext);
    data.deriv_tmp = a;
    // H = L Lᵀ
    linalg::cholesky(&data.h, &mut data.chol).map_err(DynamicsError::Singular)?;
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
    chol_solve_rows(chol.as_slice(), nv, minv.as_mut_slice());
    // ∂q̈/∂x = −solve(H, ∂τ/∂x), on the transpose (H X = B ⇔ Xᵀ H = Bᵀ: every
    // elimination step is one contiguous axpy over all right-hand sides)
    for (out, b) in [(&mut *dqdd_dq, &*dtau_dq), (&mut *dqdd_dv, &*dtau_dv)] {
        b.transpose_to(xt);
        chol_solve_rows(chol.as_slice(), nv, xt.as_mut_slice());
        xt.transpose_to(out);
        out.neg_mut();
    }
    Ok(())
}

/// Where the columns of ∂τ/∂x (tree-shaped: entry (r, c) only for r, c on one
/// root path) can be non-zero: rows `[c, dof_end[c])` (c's subtree) and c's
/// ancestors, the runs `runs[run0[c]..run0[c + 1]]`. The derivative sweep never
/// writes the other entries, which stay the zeros of `Data::new`.
struct TreePattern<'a> {
    dof_end: &'a [usize],
    runs: &'a [(usize, usize)],
    run0: &'a [usize],
}

/// Rows of a register tile.
const MR: usize = 8;
/// Columns of a register tile.
const NR: usize = 4;

/// `xₘ = −a bₘ` for a dense n × n `a` and the `bₘ` with the tree pattern `pat`
/// (column-major): every column block reads only the rows of `bₘ` where its
/// columns can be non-zero. In depth-first order the ancestors of columns
/// c₀ < c < c₀ + NR lie among c₀'s ancestors and [c₀, c), their subtrees below
/// the block's largest subtree end: one row set for the block. Register tiles of
/// R × NR accumulators; a panel of R rows of `a` stays in cache across every
/// column block of both products.
fn neg_mul_tree<T: Scalar>(
    a: &DMatrix<T>,
    bs: [&DMatrix<T>; 2],
    xs: [&mut DMatrix<T>; 2],
    pat: &TreePattern,
) {
    let n = a.nrows();
    let a = a.as_slice();
    let bs = bs.map(|b| b.as_slice());
    let [x0, x1] = xs;
    let mut xs = [x0.as_mut_slice(), x1.as_mut_slice()];
    // panels of 2 MR rows, then MR, the last one ending at n (overlapping rows get
    // the same sums again); 4 or single rows below MR
    if n >= MR {
        let mut i0 = 0;
        while i0 + 2 * MR <= n {
            panel::<T, { 2 * MR }>(n, a, bs, &mut xs, i0, pat);
            i0 += 2 * MR;
        }
        while i0 < n {
            i0 = i0.min(n - MR);
            panel::<T, MR>(n, a, bs, &mut xs, i0, pat);
            i0 += MR;
        }
    } else if n >= 4 {
        panel::<T, 4>(n, a, bs, &mut xs, 0, pat);
        panel::<T, 4>(n, a, bs, &mut xs, n - 4, pat);
    } else {
        for i0 in 0..n {
            panel::<T, 1>(n, a, bs, &mut xs, i0, pat);
        }
    }
}

/// Rows `i0..i0 + R` of both products: blocks of NR columns, the last one ending
/// at n (overlapping its predecessor); single columns below NR.
#[inline(always)]
fn panel<T: Scalar, const R: usize>(
    n: usize,
    a: &[T],
    bs: [&[T]; 2],
    xs: &mut [&mut [T]; 2],
    i0: usize,
    pat: &TreePattern,
) {
    if n < NR {
        for j in 0..n {
            let anc = &pat.runs[pat.run0[j]..pat.run0[j + 1]];
            let own = (j, pat.dof_end[j].max(j + 1));
            for (b, x) in bs.iter().zip(xs.iter_mut()) {
                tile::<T, R, 1>(n, a, b, x, i0, j, anc, own);
            }
        }
        return;
    }
    let mut j0 = 0;
    loop {
        let anc = &pat.runs[pat.run0[j0]..pat.run0[j0 + 1]];
        let end = pat.dof_end[j0..j0 + NR]
            .iter()
            .fold(j0 + NR, |e, &d| e.max(d));
        for (b, x) in bs.iter().zip(xs.iter_mut()) {
            tile::<T, R, NR>(n, a, b, x, i0, j0, anc, (j0, end));
        }
        if j0 + NR == n {
            break;
        }
        j0 = (j0 + NR).min(n - NR);
    }
}

/// One R × C tile of `x = −a b`: `x[i0.., j0..] = −Σ_k a[i0.., k] b[k, j0..]`
/// over the row runs of b.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn tile<T: Scalar, const R: usize, const C: usize>(
    n: usize,
    a: &[T],
    b: &[T],
    x: &mut [T],
    i0: usize,
    j0: usize,
    anc: &[(usize, usize)],
    own: (usize, usize),
) {
    let mut acc = [[T::zero(); R]; C];
    let bcols: [&[T]; C] = std::array::from_fn(|c| &b[(j0 + c) * n..(j0 + c + 1) * n]);
    for &(lo, hi) in anc.iter().chain(std::iter::once(&own)) {
        for k in lo..hi {
            let ak = &a[k * n + i0..k * n + i0 + R];
            for c in 0..C {
                let bk = bcols[c][k];
                for r in 0..R {
                    acc[c][r] = madd(ak[r], bk, acc[c][r]);
                }
            }
        }
    }
    for c in 0..C {
        let col = &mut x[(j0 + c) * n + i0..(j0 + c) * n + i0 + R];
        for r in 0..R {
            col[r] = -acc[c][r];
        }
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
