//! Analytic first-order derivatives of inverse dynamics: ∂τ/∂q, ∂τ/∂v (and
//! ∂τ/∂a = H) by one forward and one backward sweep in world coordinates
//! (Carpentier & Mansard, RSS 2018; Pinocchio's `computeRNEADerivatives`),
//! docs/theory.md §"Derivatives".

use super::rnea_derivatives_rows::{ancestor_rows, subtree_rows};
use super::{check_sizes, DynamicsError};
use crate::model::{dispatch_joint, Data, FrameId, JointModel, Model, NameError};
use crate::spatial::ops::cross;
use crate::spatial::{skew, CompositeInertia, Force, Motion, Scalar};
use nalgebra::{DVector, Matrix3, Vector3};

/// An external wrench on a URDF link (eval-contract.md "fext"): `force` acts at the
/// link frame's origin, `torque` is a pure couple, both in world coordinates. In
/// the derivatives it stays fixed in world coordinates and applied at the link
/// origin, which moves with q.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkWrench<T: Scalar = f64> {
    /// The link.
    pub frame: FrameId,
    /// Force (N), world coordinates, at the link frame's origin.
    pub force: Vector3<T>,
    /// Couple (N·m), world coordinates.
    pub torque: Vector3<T>,
}

/// The derivatives of inverse dynamics τ = ID(q, v, a) with the wrenches `fext`
/// (docs/theory.md §"Derivatives"): `data.dtau_dq` = ∂τ/∂q (tangent space: column
/// k is d/dε τ(q ⊕ ε eₖ), a free base moving by a body-frame twist, as Pinocchio's
/// `integrate`), `data.dtau_dv` = ∂τ/∂v and `data.h` = ∂τ/∂a = H (whole,
/// symmetric); `data.tau` holds τ. With mimic joints the reduced system's
/// (Gᵀ ∂τ_full/∂q_full G). O(n·d) for n bodies of depth d, no allocation.
pub fn rnea_derivatives<T: Scalar>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &DVector<T>,
    v: &DVector<T>,
    a: &DVector<T>,
    fext: Option<&[LinkWrench<T>]>,
) -> Result<(), DynamicsError> {
    check_sizes(model, q, &[("v", v), ("a", a)], None)?;
    check_wrenches(model, fext)?;
    rnea_derivatives_pass(model, data, q, v, a, fext);
    Ok(())
}

/// Every wrench's link exists (else the error naming its id).
pub(crate) fn check_wrenches<T: Scalar>(
    model: &Model<T>,
    fext: Option<&[LinkWrench<T>]>,
) -> Result<(), DynamicsError> {
    for w in fext.unwrap_or(&[]) {
        if w.frame.0 >= model.frames.len() {
            return Err(NameError::OutOfRange {
                kind: "frame",
                id: w.frame.0,
                len: model.frames.len(),
            }
            .into());
        }
    }
    Ok(())
}

/// [`rnea_derivatives`] for callers that checked the sizes and the frames.
pub(crate) fn rnea_derivatives_pass<T: Scalar>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &DVector<T>,
    v: &DVector<T>,
    a: &DVector<T>,
    fext: Option<&[LinkWrench<T>]>,
) {
    dispatch::<T, false>(model, data, q, v, a, fext, false);
}

/// [`rnea_derivatives_pass`] right after [`super::minv::minv_pass`] at the same
/// (q, v) on a model without mimic joints: the poses `data.li_m_i`, `data.o_m_i`,
/// the world columns `data.minv_j`, the world inertias `data.deriv_oy` and
/// momenta `data.deriv_hm` it left are reused (no joint placement, no sin/cos, no
/// inertia turned to the world). Its callers have H⁻¹ and read only ∂τ/∂q,
/// ∂τ/∂v: `data.h` is not written. `free_root` (body 1 a root on a free joint at
/// coordinates 0..6, no wrenches): the root's 6 columns of ∂τ/∂q and its 3
/// linear-velocity columns of ∂τ/∂v are not formed (`aba_derivatives` has the
/// matching columns of ∂q̈ in closed form); they keep what they held.
pub(crate) fn rnea_derivatives_pass_after_minv<T: Scalar>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &DVector<T>,
    v: &DVector<T>,
    a: &DVector<T>,
    fext: Option<&[LinkWrench<T>]>,
    free_root: bool,
) {
    debug_assert!(data.deriv_direct);
    dispatch::<T, true>(model, data, q, v, a, fext, free_root);
}

/// The full sweep (`pass` without `D`), monomorphised on whether wrenches
/// are read and whether ∂τ/∂x is formed by columns; `K`: after `minv_pass`
/// (its poses and world quantities reused). `free_root` applies without
/// wrenches only.
#[inline(always)]
fn dispatch<T: Scalar, const K: bool>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &DVector<T>,
    v: &DVector<T>,
    a: &DVector<T>,
    fext: Option<&[LinkWrench<T>]>,
    free_root: bool,
) {
    let c = by_cols(data);
    match fext {
        Some(w) if !w.is_empty() && c => {
            pass::<T, true, K, true, false>(model, data, q, v, a, w, false)
        }
        Some(w) if !w.is_empty() => {
            pass::<T, true, K, false, false>(model, data, q, v, a, w, false)
        }
        _ if c => pass::<T, false, K, true, false>(model, data, q, v, a, &[], free_root),
        _ => pass::<T, false, K, false, false>(model, data, q, v, a, &[], free_root),
    }
}

/// [`rnea_derivatives_pass_after_minv`] without a free root's shortcut, for the
/// low-rank products of `aba_derivatives` (`Data::deriv_low_rank`, long chains),
/// which read of ∂τ/∂q, ∂τ/∂v only the blocks of each joint's rows and columns:
/// the other entries are not formed (they keep what they held); every per-column
/// vector the products read (∂F/∂x, Y J, Ẏᵀ J, e, J, ∂v/∂q, ∂a/∂x) is.
pub(crate) fn rnea_derivatives_pass_diagonal<T: Scalar>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &DVector<T>,
    v: &DVector<T>,
    a: &DVector<T>,
    fext: Option<&[LinkWrench<T>]>,
) {
    debug_assert!(data.deriv_direct);
    if !by_cols(data) {
        // (not the case on the low-rank route: long patterns are by columns)
        return rnea_derivatives_pass_after_minv(model, data, q, v, a, fext, false);
    }
    match fext {
        Some(w) if !w.is_empty() => {
            pass::<T, true, true, true, true>(model, data, q, v, a, w, false)
        }
        _ => pass::<T, false, true, true, true>(model, data, q, v, a, &[], false),
    }
}

/// Whether the sweep forms ∂τ/∂x by loops over rows (`Data::deriv_by_cols`,
/// with the columns' components' buffer in place).
fn by_cols<T: Scalar>(data: &Data<T>) -> bool {
    data.deriv_by_cols && data.deriv_cols.len() >= 18 * data.deriv_col_iv.len()
}

/// The 3x3 part `S = ω×I_o − I_o ω× − h vᵀ − v hᵀ + 2 (v·h) 1` of the variation
/// `Ẏ = v×*Y − Y v× + (·)×*(Y v)` of the world force `Y a + v ×* Y v` with a uniform
/// change of the subtree's velocity (docs/theory.md §"Derivatives"); with the
/// momentum `Y v = [hₙ; h_f]`, `Ẏ x = [S xₐ − hₙ × xₐ; −2 h_f × xₐ]` and
/// `Ẏᵀ x = [S xₐ + hₙ × xₐ + 2 h_f × x_l; 0]`.
#[inline(always)]
fn variation_s<T: Scalar>(y: &CompositeInertia<T>, v: &Motion<T>) -> Matrix3<T> {
    let w = skew(&v.ang);
    let c = w * y.io;
    let hv = y.h * v.lin.transpose();
    let d = y.h.dot(&v.lin);
    // ω×I_o − I_o ω× = c + cᵀ ((ω×)ᵀ = −ω×)
    let mut s = c + c.transpose() - hv - hv.transpose();
    let two_d = d + d;
    s[(0, 0)] += two_d;
    s[(1, 1)] += two_d;
    s[(2, 2)] += two_d;
    s
}

/// `Ẏ x` from the parts of [`variation_s`].
#[inline(always)]
fn variation_mul<T: Scalar>(s: &Matrix3<T>, hm: &Force<T>, x: &Motion<T>) -> Force<T> {
    let hf2 = hm.lin + hm.lin;
    Force::new(
        crate::spatial::ops::mat_vec(s, &x.ang) - cross(&hm.ang, &x.ang),
        -cross(&hf2, &x.ang),
    )
}

/// `Ẏᵀ x` from the parts of [`variation_s`].
#[inline(always)]
fn variation_tr_mul<T: Scalar>(s: &Matrix3<T>, hm: &Force<T>, x: &Motion<T>) -> Force<T> {
    let hf2 = hm.lin + hm.lin;
    Force::new(
        crate::spatial::ops::mat_vec(s, &x.ang) + cross(&hm.ang, &x.ang) + cross(&hf2, &x.lin),
        Vector3::zeros(),
    )
}

/// The two sweeps; `F`: external wrenches present; `K`: the poses, world
/// columns, world inertias and momenta are those `minv_pass` left (direct columns
/// only), and H is not written; `C`: ∂τ/∂x's entries by loops over rows
/// (`Data::deriv_by_cols`, long patterns: each column's strict ancestors' rows at
/// its body, the strict subtree's rows of each column at the column's body); `D`
/// (with `C`): only each joint's own block (rows and columns of the joint), as
/// [`rnea_derivatives_pass_diagonal`] says; `free_root`: body 1's columns as
/// [`rnea_derivatives_pass_after_minv`] says.
fn pass<T: Scalar, const F: bool, const K: bool, const C: bool, const D: bool>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &DVector<T>,
    v: &DVector<T>,
    a: &DVector<T>,
    fext: &[LinkWrench<T>],
    free_root: bool,
) {
    let nb = model.nbodies;
    let (q, v, a) = (q.as_slice(), v.as_slice(), a.as_slice());
    let joints = &model.joints[..nb];
    let parent = &model.parent[..nb];
    let placements = &model.placements[..nb];
    let ident = &model.placement_identity[..nb];
    let inertias = &model.inertias_origin[..nb];
    let Data {
        li_m_i,
        o_m_i,
        tau,
        h,
        dtau_dq,
        dtau_dv,
        deriv_col0: col0,
        deriv_sub_end: sub_end,
        deriv_col_iv: col_iv,
        deriv_direct: direct,
        deriv_ov: ov,
        deriv_oa: oa,
        deriv_oy: oy,
        deriv_doy: doy,
        deriv_hm: hmom,
        deriv_of: of,
        deriv_ext_t: ext_t,
        deriv_ext_f: ext_f,
        deriv_ext_p: ext_p,
        deriv_fext: fbody,
        deriv_j: jcol,
        deriv_dvdq: dvdq,
        deriv_dadq: dadq,
        deriv_dadv: dadv,
        deriv_dfdq: dfdq,
        deriv_dfdv: dfdv,
        deriv_dfda: dfda,
        deriv_ytj: ytj,
        deriv_ext_e: ext_e,
        deriv_full: full,
        deriv_cols: cs,
        deriv_anc_runs: runs,
        deriv_anc_run0: run0,
        minv_j,
        ..
    } = data;
    // the stride of the columns' components (`deriv_cols`)
    let nc = col_iv.len();
    let (direct, by_cols) = (*direct, C);
    // the columns' components (`deriv_cols`), read only by the off-diagonal loops
    let comps_kept = C && !D;

    // Sweep 1, root outwards (docs/theory.md §"Derivatives"): world velocity and
    // acceleration, J = ⁰X̂ᵢ S and the columns' ∂v/∂q, ∂a/∂q, ∂a/∂v.
    ov[0] = Motion::zero();
    // â₀ = [0; −g] (docs/theory.md §"Gravity")
    oa[0] = Motion::new(Vector3::zeros(), -model.gravity);
    for i in 1..nb {
        let p = parent[i];
        let (ovp, oap) = (ov[p], oa[p]);
        let c0 = col0[i];
        // ⁰v̂ᵢ = ⁰v̂ₚ + J q̇, ⁰âᵢ = ⁰âₚ + J q̈ + ⁰v̂ᵢ × J q̇, the world columns J
        // (s, from c) first kept
        macro_rules! joint_columns {
            ($iv:expr, $n:expr, |$c:ident| $s:expr) => {{
                let iv = $iv;
                let mut vj = Motion::zero();
                let mut aj = Motion::zero();
                for $c in 0..$n {
                    let s = $s;
                    jcol[c0 + $c] = s;
                    if comps_kept {
                        for r in 0..3 {
                            cs[r * nc + c0 + $c] = s.ang[r];
                            cs[(3 + r) * nc + c0 + $c] = s.lin[r];
                        }
                    }
                    vj += s * v[iv + $c];
                    aj += s * a[iv + $c];
                }
                let ovi = ovp + vj;
                let oai = oap + aj + ovi.cross(&vj);
                for c in 0..$n {
                    let k = c0 + c;
                    let s = jcol[k];
                    // ∂v/∂q = v̂ₚ × J, ∂a/∂q = âₚ × J + v̂ₚ × ∂v/∂q, ∂a/∂v = v̂ᵢ × J + ∂v/∂q
                    let dv = ovp.cross(&s);
                    dvdq[k] = dv;
                    dadq[k] = oap.cross(&s) + ovp.cross(&dv);
                    dadv[k] = ovi.cross(&s) + dv;
                }
                (ovi, oai)
            }};
        }
        let (ovi, oai) = if K {
            // minv_pass's world columns (no joint dispatch); one column apart (a
            // loop of one iteration: nothing hoisted out and spilled)
            let jt = &joints[i];
            let (iv, n) = (jt.iv, jt.nv());
            if n == 1 {
                joint_columns!(iv, 1, |c| minv_j[iv + c])
            } else {
                joint_columns!(iv, n, |c| minv_j[iv + c])
            }
        } else {
            dispatch_joint!(&joints[i], ident[i], jm => {
                let li = jm.placement(&placements[i], q);
                let om = jm.world_pose(&o_m_i[p], &li);
                li_m_i[i] = li;
                o_m_i[i] = om;
                joint_columns!(jm.joint().iv, jm.nv(), |c| jm.subspace_in(c, &om))
            })
        };
        ov[i] = ovi;
        oa[i] = oai;
        // ⁰Yᵢ, the world force f = Y a + v ×* Y v and its variation Ẏ (with K,
        // the inertia and momentum minv_pass left, read in place)
        if !K {
            let y = inertias[i].act(&o_m_i[i]);
            let hm = y.mul_motion(&ovi);
            hmom[i] = hm;
            oy[i] = y;
        }
        let (y, hm) = (&oy[i], &hmom[i]);
        of[i] = y.mul_motion(&oai) + ovi.cross_force(hm);
        doy[i] = variation_s(y, &ovi);
        if F {
            fbody[i] = Force::zero();
            ext_t[i] = Vector3::zeros();
            ext_f[i] = Vector3::zeros();
            ext_p[i] = Matrix3::zeros();
        }
    }
    if F {
        // f̂ˣ = [t + p × f; f] at the world origin, p the link origin (world)
        for w in fext {
            let fr = &model.frames[w.frame.0];
            let b = fr.body;
            if b == 0 {
                continue;
            }
            let pw = o_m_i[b].act_point(&fr.placement.trans);
            let fx = Force::new(w.torque + cross(&pw, &w.force), w.force);
            fbody[b] += fx;
            of[b] -= fx;
            ext_t[b] += w.torque;
            ext_f[b] += w.force;
            ext_p[b] += pw * w.force.transpose();
        }
    }

    // Sweep 2, leaves inwards: composite Y, Ẏ, F; the blocks of each body's rows
    // and columns against its subtree.
    tau.as_mut_slice().fill(T::zero());
    let n = if direct { model.nv } else { col_iv.len() };
    let [fq, fv, fa] = full;
    let (mq, mv, ma) = if direct {
        if !K {
            h.as_mut_slice().fill(T::zero());
        }
        (
            dtau_dq.as_mut_slice(),
            dtau_dv.as_mut_slice(),
            h.as_mut_slice(),
        )
    } else {
        (fq.as_mut_slice(), fv.as_mut_slice(), fa.as_mut_slice())
    };
    let (mq, mv, ma) = (&mut mq[..n * n], &mut mv[..n * n], &mut ma[..n * n]);
    for i in (1..nb).rev() {
        let p = parent[i];
        // body i's composite Y, Ẏ, momentum and force read in place, its
        // parent's (p < i) accumulated after
        let (oy_lo, oy_hi) = oy.split_at_mut(i);
        let (doy_lo, doy_hi) = doy.split_at_mut(i);
        let (hm_lo, hm_hi) = hmom.split_at_mut(i);
        let (of_lo, of_hi) = of.split_at_mut(i);
        let (yi, doyi, hmi, fi) = (&oy_hi[0], &doy_hi[0], &hm_hi[0], &of_hi[0]);
        let c0 = col0[i];
        let nvi = joints[i].nv();
        let ce = c0 + nvi;
        let end = sub_end[i];
        // a root body's columns have ∂v/∂q = v̂₀ × J = 0 (the world is at rest):
        // the terms it multiplies are left out
        let root = p == 0;
        if K && !F && free_root && i == 1 {
            // the free root: τ, the root's rows against the later columns and its
            // angular-velocity columns of ∂τ/∂v (a root has nothing to pass on)
            for k in c0..ce {
                let s = jcol[k];
                tau[col_iv[k]] += s.dot(fi);
                if k >= c0 + 3 {
                    dfdv[k] = variation_mul(doyi, hmi, &s) + yi.mul_motion(&dadv[k]);
                }
            }
            for r in c0..ce {
                let s = jcol[r];
                for c in c0 + 3..ce {
                    mv[r + c * n] = s.dot(&dfdv[c]);
                }
                if by_cols {
                    // (by columns: at the later columns' bodies)
                    continue;
                }
                for c in ce..end {
                    let at = r + c * n;
                    mq[at] = s.dot(&dfdq[c]);
                    mv[at] = s.dot(&dfdv[c]);
                }
            }
            for r in c0 + 3..ce {
                let (av, jr) = (dadv[r], jcol[r]);
                for c in ce..end {
                    mv[c + r * n] = av.dot(&dfda[c]) + jr.dot(&ytj[c]);
                }
            }
            continue;
        }
        // the joint's columns against its subtree: written once for any
        // number of columns and once for one (a loop of one iteration: its
        // invariants are not hoisted out and spilled)
        macro_rules! columns {
            ($ce:ident) => {
                for k in c0..$ce {
                    let s = jcol[k];
                    // τ = Jᵀ F
                    tau[col_iv[k]] += s.dot(fi);
                    // ∂F/∂a = Y J, ∂F/∂q = Ẏ ∂v/∂q + Y ∂a/∂q, ∂F/∂v = Ẏ J + Y ∂a/∂v, Ẏᵀ J
                    dfda[k] = yi.mul_motion(&s);
                    dfdq[k] = if root {
                        yi.mul_motion(&dadq[k])
                    } else {
                        variation_mul(doyi, hmi, &dvdq[k]) + yi.mul_motion(&dadq[k])
                    };
                    dfdv[k] = variation_mul(doyi, hmi, &s) + yi.mul_motion(&dadv[k]);
                    ytj[k] = variation_tr_mul(doyi, hmi, &s);
                    if F {
                        // the wrenches' world-fixed correction (docs/theory.md §"Derivatives"):
                        // C = [ω × T + (tr P − Pᵀ) ω; ω × Σf], e = T × ω + (tr P − P) ω + Σf × v
                        let (t, fs, pm) = (ext_t[i], ext_f[i], ext_p[i]);
                        let tr = pm[(0, 0)] + pm[(1, 1)] + pm[(2, 2)];
                        let w = s.ang;
                        dfdq[k] += Force::new(cross(&w, &t) + w * tr - pm.transpose() * w, cross(&w, &fs));
                        ext_e[k] = Force::new(
                            cross(&t, &w) + w * tr - pm * w + cross(&fs, &s.lin),
                            Vector3::zeros(),
                        );
                    }
                    // Y J, (Ẏᵀ J).ang and e.ang by components, for the loops below
                    let (ya, yt) = (&dfda[k], &ytj[k]);
                    for r in 0..if comps_kept { 3 } else { 0 } {
                        cs[(6 + r) * nc + k] = ya.ang[r];
                        cs[(9 + r) * nc + k] = ya.lin[r];
                        cs[(12 + r) * nc + k] = yt.ang[r];
                        if F {
                            cs[(15 + r) * nc + k] = ext_e[k].ang[r];
                        }
                    }
                }
                for r in c0..$ce {
                    let s = jcol[r];
                    // rows of this joint, columns of its subtree (by columns: of
                    // this joint, the others at their bodies): Jᵀ ∂F
                    for c in c0..if by_cols { $ce } else { end } {
                        let at = r + c * n;
                        if !K {
                            ma[at] = s.dot(&dfda[c]);
                        }
                        mq[at] = s.dot(&dfdq[c]);
                        mv[at] = s.dot(&dfdv[c]);
                    }
                    // rows of the strict subtree, columns of this joint
                    if !by_cols {
                        let (aq, av, jr) = (dadq[r], dadv[r], s);
                        let (dv, ang) = (dvdq[r], s.ang);
                        for c in $ce..end {
                            let at = c + r * n;
                            let mut x = if root {
                                aq.dot(&dfda[c])
                            } else {
                                aq.dot(&dfda[c]) + dv.dot(&ytj[c])
                            };
                            if F {
                                x += crate::spatial::ops::dot(&ang, &ext_e[c].ang);
                            }
                            mq[at] = x;
                            mv[at] = av.dot(&dfda[c]) + jr.dot(&ytj[c]);
                            if !K {
                                ma[at] = ma[r + c * n];
                            }
                        }
                    } else if !D && $ce < end {
                        let (col, lo, hi) = (r * n, $ce, end);
                        let (xq, xv, xa) = (
                            &mut mq[col + lo..col + hi],
                            &mut mv[col + lo..col + hi],
                            &mut ma[col + lo..col + hi],
                        );
                        let (m, rows) = ([&dadq[r], &dvdq[r], &dadv[r], &s], (&cs[..], nc, lo));
                        if root {
                            subtree_rows::<T, F, K, true>(m, rows, [xq, xv, xa]);
                        } else {
                            subtree_rows::<T, F, K, false>(m, rows, [xq, xv, xa]);
                        }
                    }
                }
                for k in c0..$ce {
                    // the subtree moves rigidly with the joint: ∂F/∂q += J ×* F
                    dfdq[k] += jcol[k].cross_force(fi);
                    if !by_cols || D {
                        continue;
                    }
                    // rows of the strict ancestors, columns of this joint: Jᵀ ∂F
                    // (∂F whole now)
                    let f = [&dfdq[k], &dfdv[k], &dfda[k]];
                    let mut x = [&mut *mq, &mut *mv, &mut *ma];
                    if direct {
                        for &run in &runs[run0[c0]..run0[c0 + 1]] {
                            ancestor_rows::<T, K>(f, (&cs[..], nc), &mut x, k * n, run);
                        }
                    } else {
                        let mut b = p;
                        while b != 0 {
                            let run = (col0[b], col0[b] + joints[b].nv());
                            ancestor_rows::<T, K>(f, (&cs[..], nc), &mut x, k * n, run);
                            b = parent[b];
                        }
                    }
                }
            };
        }
        if nvi == 1 {
            let ce1 = c0 + 1;
            columns!(ce1);
        } else {
            columns!(ce);
        }
        if p != 0 {
            oy_lo[p].add_assign(yi);
            doy_lo[p] += *doyi;
            hm_lo[p] += *hmi;
            of_lo[p] += *fi;
            if F {
                let (t, fs, pm) = (ext_t[i], ext_f[i], ext_p[i]);
                ext_t[p] += t;
                ext_f[p] += fs;
                ext_p[p] += pm;
            }
        }
    }
    if !direct {
        // The reduced system: Gᵀ M_full G (G's multipliers are inside J).
        for (m_out, m_full) in [(dtau_dq, &*fq), (dtau_dv, &*fv), (h, &*fa)] {
            m_out.as_mut_slice().fill(T::zero());
            for c in 0..n {
                for r in 0..n {
                    let x = m_full[(r, c)];
                    m_out[(col_iv[r], col_iv[c])] += x;
                }
            }
        }
    }
}
