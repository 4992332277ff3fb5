//! The products of the ABA derivatives on long chains (docs/theory.md
//! §"Derivatives", "The products"): `−H⁻¹ ∂τ/∂x` from the low-rank parts of
//! ∂τ/∂x in O(nv²) instead of O(nv³), for `aba_derivatives.rs`
//! (`data.deriv_low_rank`). Column kernels of fixed width, so that the sums of
//! each entry are taken in one order whatever the model.

use crate::model::{Data, Model};
use crate::spatial::ops::madd;
use crate::spatial::Scalar;
use nalgebra::Vector3;

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
#[inline(always)]
pub(super) fn neg_mul_low_rank<T: Scalar>(model: &Model<T>, data: &mut Data<T>, ext: bool) {
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
