//! Analytic first-order derivatives of forward dynamics: ∂q̈/∂q, ∂q̈/∂v and
//! ∂q̈/∂τ = H⁻¹, from those of inverse dynamics at a = q̈ (docs/theory.md
//! §"Derivatives": q̈(q, v, τ) solves ID(q, v, q̈) = τ, so
//! ∂q̈/∂x = −H⁻¹ ∂ID/∂x; H⁻¹ from the world-frame ABA of `minv.rs`, "Inverse of
//! H"; the products over ∂ID/∂x's tree pattern, "The products").

use super::rnea_derivatives::{
    check_wrenches, rnea_derivatives_pass, rnea_derivatives_pass_after_minv, LinkWrench,
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
/// wrenches, except those nine columns, left as they were); `data.h` only with
/// mimic joints. No allocation.
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
        // A free root (body 1, coordinates 0..6) without wrenches: its columns of
        // ∂q̈/∂q and its linear-velocity columns of ∂q̈/∂v are known in closed form
        // (`free_root_columns`); ∂τ/∂x's are not formed for them.
        let free_root = fext.is_none() && !data.deriv_low_rank && free_root(model);
        // ∂τ/∂q, ∂τ/∂v at a = q̈
        let mut a = std::mem::replace(&mut data.deriv_tmp, DVector::zeros(0));
        a.copy_from(&data.qdd);
        rnea_derivatives_pass_after_minv(model, data, q, v, &a, fext, free_root);
        data.deriv_tmp = a;
        if data.deriv_low_rank {
            // ∂q̈/∂x = −H⁻¹ ∂τ/∂x from ∂τ/∂x's low-rank parts (long chains)
            neg_mul_low_rank(model, data, fext.is_some());
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

/// `(xq, xv) += Σₖ cols[k n..(k + 1) n] (cq[k], cv[k])` over the first `K`
/// columns (one load of each column for both), then negated if `neg`.
#[inline(always)]
fn gemv2_add<T: Scalar, const K: usize>(
    xq: &mut [T],
    xv: &mut [T],
    cols: &[T],
    cq: &[T; 12],
    cv: &[T; 12],
    neg: bool,
) {
    gemv2::<T, K, false>(xq, xv, cols, cq, cv, neg, (&[], T::zero(), T::zero()));
}

/// [`gemv2_add`] with `OWN`: `(xq, xv)` start from `(h bq, h bv)` for
/// `own = (h, bq, bv)` (each `madd(h, b, 0)`, as an axpy into zeros) instead of
/// their contents, which are not read.
#[inline(always)]
fn gemv2<T: Scalar, const K: usize, const OWN: bool>(
    xq: &mut [T],
    xv: &mut [T],
    cols: &[T],
    cq: &[T; 12],
    cv: &[T; 12],
    neg: bool,
    own: (&[T], T, T),
) {
    let n = xq.len();
    // filled in a loop (`array::from_fn` was an out-of-line call)
    let mut c: [&[T]; K] = [&[]; K];
    for (k, ck) in c.iter_mut().enumerate() {
        *ck = &cols[k * n..(k + 1) * n];
    }
    let xv = &mut xv[..n];
    let (h0, b0q, b0v) = own;
    let h0 = if OWN { &h0[..n] } else { h0 };
    for i in 0..n {
        let (mut sq, mut sv) = if OWN {
            (madd(h0[i], b0q, T::zero()), madd(h0[i], b0v, T::zero()))
        } else {
            (xq[i], xv[i])
        };
        for k in 0..K {
            let h = c[k][i];
            sq = madd(h, cq[k], sq);
            sv = madd(h, cv[k], sv);
        }
        if neg {
            sq = -sq;
            sv = -sv;
        }
        xq[i] = sq;
        xv[i] = sv;
    }
}

/// [`gemv2`] over columns that change in the same pass, for one-coordinate
/// bodies of a chain (the low-rank products' S and P): entry i of column k,
/// `cₖ[i]`, becomes `madd(g[i], gc[k], cₖ[i])` (the update of [`ger_add`]) —
/// before the sums read it when `PRE` (P_i = P_λ + H⁻¹[:, λ] J_λᵀ, then
/// P_i G_c), after when not (S_i β_c, then S += H⁻¹[:, i] αᵢᵀ). The same
/// operations as [`ger_add`] and [`gemv2`] one after the other, in one pass.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn gemv2_ger<T: Scalar, const K: usize, const OWN: bool, const PRE: bool>(
    xq: &mut [T],
    xv: &mut [T],
    cols: &mut [T],
    cq: &[T; 12],
    cv: &[T; 12],
    neg: bool,
    own: (&[T], T, T),
    g: &[T],
    gc: &[T; 12],
) {
    let n = xq.len();
    let mut c: [&mut [T]; K] = std::array::from_fn(|_| Default::default());
    let mut rest = &mut cols[..K * n];
    for ck in c.iter_mut() {
        let (head, tail) = std::mem::take(&mut rest).split_at_mut(n);
        *ck = head;
        rest = tail;
    }
    let xv = &mut xv[..n];
    let g = &g[..n];
    let (h0, b0q, b0v) = own;
    let h0 = if OWN { &h0[..n] } else { h0 };
    for i in 0..n {
        let (mut sq, mut sv) = if OWN {
            (madd(h0[i], b0q, T::zero()), madd(h0[i], b0v, T::zero()))
        } else {
            (xq[i], xv[i])
        };
        let gi = g[i];
        for k in 0..K {
            let old = c[k][i];
            let h = if PRE { madd(gi, gc[k], old) } else { old };
            sq = madd(h, cq[k], sq);
            sv = madd(h, cv[k], sv);
            c[k][i] = if PRE { h } else { madd(gi, gc[k], old) };
        }
        if neg {
            sq = -sq;
            sv = -sv;
        }
        xq[i] = sq;
        xv[i] = sv;
    }
}

/// `cols[k n..(k + 1) n] += h coef[k]` for the first `K` columns.
#[inline(always)]
fn ger_add<T: Scalar, const K: usize>(cols: &mut [T], h: &[T], coef: &[T; 12]) {
    let n = h.len();
    for (k, col) in cols.chunks_exact_mut(n).take(K).enumerate() {
        let ck = coef[k];
        for (y, &x) in col.iter_mut().zip(h) {
            *y = madd(x, ck, *y);
        }
    }
}

/// Four 3-vectors `[a; b; c; d]` as 12 coefficients.
#[inline(always)]
fn coef12<T: Scalar>(x: [&Vector3<T>; 4]) -> [T; 12] {
    let mut c = [T::zero(); 12];
    for (b, v) in x.iter().enumerate() {
        for r in 0..3 {
            c[3 * b + r] = v[r];
        }
    }
    c
}

/// `−H⁻¹ ∂τ/∂q`, `−H⁻¹ ∂τ/∂v` from the low-rank parts of ∂τ/∂x (docs/theory.md
/// §"Derivatives", "The products"): column c of B (coordinate c on body i) is
/// `Jᵣᵀ G_c` on the coordinates r of i's strict ancestors (G = ∂F/∂q or ∂F/∂q̇ of
/// c's column, the subtree's rigid turn included), `αᵣᵀ β_c` on those of its
/// strict descendants (α = [Yᶜ J; (Ẏᶜᵀ J).ang; e.ang], β = [∂a/∂q; ∂v/∂q.ang; ω]
/// or [∂a/∂q̇; ω; 0]) and B's own block on i's joint. So
/// `H⁻¹ B[:, c] = H⁻¹[:, i] B[i, c] + P_i G_c + S_i β_c`, with
/// `P_i = Σ_{anc} H⁻¹[:, r] Jᵣᵀ` (root outwards) and `S_i = Σ_{desc} H⁻¹[:, r] αᵣᵀ`
/// (leaves inwards): O(nv²) instead of O(nv³). Reads the derivative sweep's
/// per-column vectors from `data`; `ext`: wrenches were given (e is set).
fn neg_mul_low_rank<T: Scalar>(model: &Model<T>, data: &mut Data<T>, ext: bool) {
    let (n, nb) = (model.nv, model.nbodies);
    let parent = &model.parent[..nb];
    let joints = &model.joints[..nb];
    let Data {
        minv,
        dqdd_dq,
        dqdd_dv,
        dtau_dq,
        dtau_dv,
        deriv_j: jc,
        deriv_dfda: dfda,
        deriv_ytj: ytj,
        deriv_ext_e: ext_e,
        deriv_dadq: dadq,
        deriv_dvdq: dvdq,
        deriv_dadv: dadv,
        deriv_dfdq: dfdq,
        deriv_dfdv: dfdv,
        deriv_prod_s: sbuf,
        deriv_prod_s_off: soff,
        ..
    } = data;
    let a = minv.as_slice();
    let (xq, xv) = (dqdd_dq.as_mut_slice(), dqdd_dv.as_mut_slice());
    let (bq, bv) = (dtau_dq.as_slice(), dtau_dv.as_slice());
    let zero = Vector3::zeros();
    let alpha = |r: usize| {
        let e = if ext { &ext_e[r].ang } else { &zero };
        coef12([&dfda[r].ang, &dfda[r].lin, &ytj[r].ang, e])
    };
    let sz = 12 * n;
    sbuf.fill(T::zero());
    // Leaves inwards: x[:, c] = H⁻¹[:, i] B[i, c] + S_i β_c; then S_i += H⁻¹[:, r] αᵣᵀ
    // over i's coordinates and S_λ += S_i.
    for i in (1..nb).rev() {
        let (c0, ni) = (joints[i].iv, joints[i].nv());
        let si = soff[i];
        for c in c0..c0 + ni {
            let bq_c = coef12([&dadq[c].ang, &dadq[c].lin, &dvdq[c].ang, &jc[c].ang]);
            let bv_c = coef12([&dadv[c].ang, &dadv[c].lin, &jc[c].ang, &zero]);
            let (xqc, xvc) = (&mut xq[c * n..(c + 1) * n], &mut xv[c * n..(c + 1) * n]);
            if ni == 1 && !ext {
                // one coordinate: its H⁻¹ column times B[i, c] starts the sums
                // (no pass over zeros), S += H⁻¹[:, i] αᵢᵀ in the same pass
                let h = &a[c0 * n..(c0 + 1) * n];
                let own = (h, bq[c0 + c * n], bv[c0 + c * n]);
                let (s, al) = (&mut sbuf[si..si + sz], alpha(c0));
                gemv2_ger::<T, 9, true, false>(xqc, xvc, s, &bq_c, &bv_c, false, own, h, &al);
                continue;
            }
            let s = &sbuf[si..si + sz];
            for (xc, b) in [(&mut *xqc, bq), (&mut *xvc, bv)] {
                xc.fill(T::zero());
                for r in c0..c0 + ni {
                    let brc = b[r + c * n];
                    for (y, &h) in xc.iter_mut().zip(&a[r * n..(r + 1) * n]) {
                        *y = madd(h, brc, *y);
                    }
                }
            }
            if ext {
                gemv2_add::<T, 12>(xqc, xvc, s, &bq_c, &bv_c, false);
            } else {
                gemv2_add::<T, 9>(xqc, xvc, s, &bq_c, &bv_c, false);
            }
        }
        let s = &mut sbuf[si..si + sz];
        for r in c0..c0 + ni {
            if ni == 1 && !ext {
                // done with the column's sums above
                break;
            }
            let al = alpha(r);
            let h = &a[r * n..(r + 1) * n];
            if ext {
                ger_add::<T, 12>(s, h, &al);
            } else {
                ger_add::<T, 9>(s, h, &al);
            }
        }
        let p = parent[i];
        if p == 0 || soff[p] != si {
            if p != 0 {
                let sp = soff[p];
                let (lo, hi) = sbuf.split_at_mut(si);
                for (y, &x) in lo[sp..sp + sz].iter_mut().zip(&hi[..sz]) {
                    *y += x;
                }
            }
            sbuf[si..si + sz].fill(T::zero());
        }
    }
    // Root outwards: P_i = P_λ + H⁻¹[:, λ] J_λᵀ; x[:, c] = −(x[:, c] + P_i G_c).
    // P lives in S's buffer (free now) and slots: an only child updates its
    // parent's P in place, the children of a branching body start from a copy.
    let psz = 6 * n;
    let pbuf = sbuf;
    let poff = soff;
    for i in 1..nb {
        let p = parent[i];
        let (c0, ni) = (joints[i].iv, joints[i].nv());
        let o = poff[i];
        if p == 0 {
            pbuf[o..o + psz].fill(T::zero());
        } else {
            let r0 = poff[p];
            if r0 != o {
                // a deeper slot (r0 < o)
                let (lo, hi) = pbuf.split_at_mut(o);
                hi[..psz].copy_from_slice(&lo[r0..r0 + psz]);
            }
            let dst = &mut pbuf[o..o + psz];
            let (cp, np) = (joints[p].iv, joints[p].nv());
            if np == 1 && ni == 1 {
                // one coordinate on each side: P's update and x[:, c] in one pass
                let (c, g) = (c0, &a[cp * n..(cp + 1) * n]);
                let jr = coef12([&jc[cp].ang, &jc[cp].lin, &zero, &zero]);
                let (xqc, xvc) = (&mut xq[c * n..(c + 1) * n], &mut xv[c * n..(c + 1) * n]);
                let (gq, gv) = (&dfdq[c], &dfdv[c]);
                let (cq, cv) = (
                    coef12([&gq.ang, &gq.lin, &zero, &zero]),
                    coef12([&gv.ang, &gv.lin, &zero, &zero]),
                );
                let own = (&[][..], T::zero(), T::zero());
                gemv2_ger::<T, 6, false, true>(xqc, xvc, dst, &cq, &cv, true, own, g, &jr);
                continue;
            }
            for r in cp..cp + np {
                let jr = coef12([&jc[r].ang, &jc[r].lin, &zero, &zero]);
                ger_add::<T, 6>(dst, &a[r * n..(r + 1) * n], &jr);
            }
        }
        let pi = &pbuf[o..o + psz];
        for c in c0..c0 + ni {
            let (xqc, xvc) = (&mut xq[c * n..(c + 1) * n], &mut xv[c * n..(c + 1) * n]);
            let (gq, gv) = (&dfdq[c], &dfdv[c]);
            let (cq, cv) = (
                coef12([&gq.ang, &gq.lin, &zero, &zero]),
                coef12([&gv.ang, &gv.lin, &zero, &zero]),
            );
            // P_i is zero at a root
            gemv2_add::<T, 6>(xqc, xvc, pi, &cq, &cv, true);
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
