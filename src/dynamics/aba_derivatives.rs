//! Analytic first-order derivatives of forward dynamics: ∂q̈/∂q, ∂q̈/∂v and
//! ∂q̈/∂τ = H⁻¹, from those of inverse dynamics at a = q̈ (docs/theory.md
//! §"Derivatives": q̈(q, v, τ) solves ID(q, v, q̈) = τ, so
//! ∂q̈/∂x = −H⁻¹ ∂ID/∂x; H⁻¹ from the world-frame ABA of `minv.rs`, "Inverse of
//! H"; the products over ∂ID/∂x's tree pattern, "The products").

use super::rnea_derivatives::{
    check_wrenches, rnea_derivatives_pass, rnea_derivatives_pass_after_minv,
    rnea_derivatives_pass_diagonal, LinkWrench,
};
use super::{check_massless, check_sizes, minv, DynamicsError};
use crate::model::{Data, JointKind, Model};
use crate::spatial::ops::madd;
use crate::spatial::{Force, Scalar};
use nalgebra::{DMatrix, DVector, Vector3};

/// The derivatives of forward dynamics q̈ = FD(q, v, τ) with the wrenches `fext`
/// (docs/theory.md §"Derivatives"): `data.dqdd_dq` = ∂q̈/∂q (tangent space, as
/// [`super::rnea_derivatives`]), `data.dqdd_dv` = ∂q̈/∂v, `data.minv` = H⁻¹ = ∂q̈/∂τ
/// (whole, symmetric; a floating base's first 6 columns are those of its body-frame
/// wrench), `data.qdd` = q̈. Every model: fixed, floating, mimic (the reduced system).
/// Route (docs/theory.md §"Derivatives", "Forward dynamics"): q̈ and H⁻¹ by the
/// articulated-body recursion in world coordinates ("Inverse of H", O(n·nv));
/// ∂τ/∂q, ∂τ/∂v at a = q̈ by [`super::rnea_derivatives`]; ∂q̈/∂x = −H⁻¹ ∂τ/∂x by
/// register-tiled products that read only ∂τ/∂x's tree pattern, or on long chains
/// from ∂τ/∂x's low-rank parts in O(nv²) ("The products", `data.deriv_low_rank`).
/// With mimic joints: q̈ by the engine's forward dynamics, H by the derivative
/// sweep, dense Cholesky solves against the identity and both Jacobians. A free
/// root without wrenches: its columns of ∂q̈/∂q and linear-velocity columns of
/// ∂q̈/∂v in closed form (docs/theory.md §"Derivatives: a free root's columns").
/// Also leaves `data.dtau_dq`, `data.dtau_dv` (at a = q̈; with a free root and no
/// wrenches, except those nine columns, left as they were) — but on the low-rank
/// route (`data.deriv_low_rank`) only their blocks of each joint's own rows and
/// columns, the other entries left as they were (call
/// [`super::rnea_derivatives`] for ∂τ/∂x whole); `data.h` only with mimic
/// joints. No allocation.
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
        super::forward_kinematics_unkeyed(model, data, q);
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
        // A free root (body 1, coordinates 0..6) without wrenches: its columns of
        // ∂q̈/∂q and its linear-velocity columns of ∂q̈/∂v are known in closed form
        // (`free_root_columns`); ∂τ/∂x's are not formed for them.
        let free_root = fext.is_none() && !data.deriv_low_rank && free_root(model);
        // ∂τ/∂q, ∂τ/∂v at a = q̈ (for the low-rank products only each joint's
        // own block, and the per-column vectors)
        let mut a = std::mem::replace(&mut data.deriv_tmp, DVector::zeros(0));
        a.copy_from(&data.qdd);
        if data.deriv_low_rank {
            rnea_derivatives_pass_diagonal(model, data, q, v, &a, fext);
        } else {
            rnea_derivatives_pass_after_minv(model, data, q, v, &a, fext, free_root);
        }
        data.deriv_tmp = a;
        if data.deriv_low_rank {
            // ∂q̈/∂x = −H⁻¹ ∂τ/∂x from ∂τ/∂x's low-rank parts (long chains)
            super::aba_low_rank::neg_mul_low_rank(model, data, fext.is_some());
            return Ok(());
        }
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
        let starts = if free_root { [6, 3] } else { [0, 0] };
        neg_mul_tree(minv, [dtau_dq, dtau_dv], [dqdd_dq, dqdd_dv], &pat, starts);
        if free_root {
            free_root_columns(model, data, v);
        }
        return Ok(());
    }
    // mimic joints: q̈ through H's factor (dense, or tree-sparse where the
    // followers keep the tree pattern, `super::dense_factor`), which stays in
    // data.chol for the solves below
    let r =
        super::forward_dynamics(model, data, q, v, tau, fext.map(|_| fb.as_slice())).map(|_| ());
    data.deriv_fext = fb;
    r?;
    // ∂τ/∂q, ∂τ/∂v at a = q̈
    let mut a = std::mem::replace(&mut data.deriv_tmp, DVector::zeros(0));
    a.copy_from(&data.qdd);
    rnea_derivatives_pass(model, data, q, v, &a, fext);
    data.deriv_tmp = a;
    let nv = model.nv;
    let empty = || DMatrix::zeros(0, 0);
    let mut minv = std::mem::replace(&mut data.minv, empty());
    let mut xt = std::mem::replace(&mut data.deriv_scratch, empty());
    // H⁻¹ = solve(H, 1) (symmetric: its rows are its columns)
    minv.as_mut_slice().fill(T::zero());
    for k in 0..nv {
        minv[(k, k)] = T::one();
    }
    super::factor_solve_rows(model, data, nv, minv.as_mut_slice());
    // ∂q̈/∂x = −solve(H, ∂τ/∂x), on the transpose (H X = B ⇔ Xᵀ H = Bᵀ: every
    // elimination step is one contiguous axpy over all right-hand sides)
    for which in 0..2 {
        let (b, out) = if which == 0 {
            (&data.dtau_dq, &mut data.dqdd_dq)
        } else {
            (&data.dtau_dv, &mut data.dqdd_dv)
        };
        b.transpose_to(&mut xt);
        let mut o = std::mem::replace(out, empty());
        super::factor_solve_rows(model, data, nv, xt.as_mut_slice());
        xt.transpose_to(&mut o);
        o.neg_mut();
        if which == 0 {
            data.dqdd_dq = o;
        } else {
            data.dqdd_dv = o;
        }
    }
    data.minv = minv;
    data.deriv_scratch = xt;
    Ok(())
}

/// Whether body 1 is a root on a free joint at coordinates 0..6.
fn free_root<T: Scalar>(model: &Model<T>) -> bool {
    model.nbodies > 1
        && model.parent[1] == 0
        && model.joints[1].iv == 0
        && matches!(model.joints[1].kind, JointKind::Free)
}

/// A free root's columns of ∂q̈/∂q and its linear-velocity columns of ∂q̈/∂v,
/// without wrenches (docs/theory.md §"Derivatives", "A free root"): moving or
/// turning the whole tree, or adding a uniform velocity, changes no joint's q̈
/// (a body in free fall in a uniform field); the root's own body-frame
/// acceleration has gravity `Rᵀg` in its linear part, and `−ω × v` from its
/// velocity. So `∂q̈/∂q[:, 0..3] = 0`, `∂q̈/∂q[:, 3..6] = [(Rᵀg)×; 0]` and
/// `∂q̈/∂v[:, 0..3] = [−ω×; 0]` (R, ω: the root's world rotation and body
/// angular velocity).
fn free_root_columns<T: Scalar>(model: &Model<T>, data: &mut Data<T>, v: &DVector<T>) {
    let n = model.nv;
    let u = data.o_m_i[1].rot.tr_mul(&model.gravity);
    let w = Vector3::new(v[3], v[4], v[5]);
    let (xq, xv) = (data.dqdd_dq.as_mut_slice(), data.dqdd_dv.as_mut_slice());
    xq[..6 * n].fill(T::zero());
    xv[..3 * n].fill(T::zero());
    // column k of a×: a × eₖ
    for k in 0..3 {
        let mut e = Vector3::zeros();
        e[k] = T::one();
        let (cu, cw) = (u.cross(&e), w.cross(&e));
        for r in 0..3 {
            xq[r + (3 + k) * n] = cu[r];
            xv[r + k * n] = -cw[r];
        }
    }
}

/// Where the columns of ∂τ/∂x (tree-shaped: entry (r, c) only for r, c on one
/// root path) can be non-zero: rows `[c, dof_end[c])` (c's subtree) and c's
/// ancestors, the runs `runs[run0[c]..run0[c + 1]]`. The derivative sweep never
/// writes the other entries, which stay the zeros of `Data::new`.
pub(super) struct TreePattern<'a> {
    pub(super) dof_end: &'a [usize],
    pub(super) runs: &'a [(usize, usize)],
    pub(super) run0: &'a [usize],
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
pub(super) fn neg_mul_tree<T: Scalar>(
    a: &DMatrix<T>,
    bs: [&DMatrix<T>; 2],
    xs: [&mut DMatrix<T>; 2],
    pat: &TreePattern,
    starts: [usize; 2],
) {
    let n = a.nrows();
    let a = a.as_slice();
    let bs = [bs[0].as_slice(), bs[1].as_slice()];
    let [x0, x1] = xs;
    let mut xs = [x0.as_mut_slice(), x1.as_mut_slice()];
    // panels of 2 MR rows, then MR, the last one ending at n (overlapping rows get
    // the same sums again); one panel of n rows for 4 ≤ n < MR, single rows below
    if n >= MR {
        let mut i0 = 0;
        while i0 + 2 * MR <= n {
            panel::<T, { 2 * MR }>(n, a, bs, &mut xs, i0, pat, starts);
            i0 += 2 * MR;
        }
        while i0 < n {
            i0 = i0.min(n - MR);
            panel::<T, MR>(n, a, bs, &mut xs, i0, pat, starts);
            i0 += MR;
        }
    } else if n >= 4 {
        // one panel of all n rows (the same sums as two overlapping ones of 4)
        match n {
            5 => panel::<T, 5>(n, a, bs, &mut xs, 0, pat, starts),
            6 => panel::<T, 6>(n, a, bs, &mut xs, 0, pat, starts),
            7 => panel::<T, 7>(n, a, bs, &mut xs, 0, pat, starts),
            _ => panel::<T, 4>(n, a, bs, &mut xs, 0, pat, starts),
        }
    } else {
        for i0 in 0..n {
            panel::<T, 1>(n, a, bs, &mut xs, i0, pat, starts);
        }
    }
}

/// Rows `i0..i0 + R` of both products, product k from column `starts[k]` on:
/// blocks of NR columns, the last one ending at n (overlapping its
/// predecessor); single columns where fewer than NR are left.
#[inline(always)]
fn panel<T: Scalar, const R: usize>(
    n: usize,
    a: &[T],
    bs: [&[T]; 2],
    xs: &mut [&mut [T]; 2],
    i0: usize,
    pat: &TreePattern,
    starts: [usize; 2],
) {
    for ((b, x), s) in bs.iter().zip(xs.iter_mut()).zip(starts) {
        if n - s < NR {
            for j in s..n {
                let anc = &pat.runs[pat.run0[j]..pat.run0[j + 1]];
                let own = (j, pat.dof_end[j].max(j + 1));
                tile::<T, R, 1>(n, a, b, x, i0, j, anc, own);
            }
            continue;
        }
        let mut j0 = s;
        loop {
            let anc = &pat.runs[pat.run0[j0]..pat.run0[j0 + 1]];
            let end = pat.dof_end[j0..j0 + NR]
                .iter()
                .fold(j0 + NR, |e, &d| e.max(d));
            tile::<T, R, NR>(n, a, b, x, i0, j0, anc, (j0, end));
            if j0 + NR == n {
                break;
            }
            j0 = (j0 + NR).min(n - NR);
        }
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
    // filled in a loop (`array::from_fn` was an out-of-line call)
    let mut bcols: [&[T]; C] = [&[]; C];
    for (c, bc) in bcols.iter_mut().enumerate() {
        *bc = &b[(j0 + c) * n..(j0 + c + 1) * n];
    }
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
