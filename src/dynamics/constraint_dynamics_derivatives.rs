//! Analytic derivatives of the constrained forward dynamics, ∂q̈/∂q, ∂q̈/∂v,
//! ∂q̈/∂τ (docs/theory.md §"Constrained dynamics", "Derivatives"). With
//! ID(q, v, a) the inverse dynamics (external wrenches included) and
//! A(q, v, a) = J_c a + γ_c the rows' classical accelerations, q̈ solves
//! ID(q, v, q̈) − J_cᵀ λ = τ and A(q, v, q̈) = 0. Differentiating at fixed λ:
//!
//! ```text
//! H ∂q̈ − J_cᵀ ∂λ = −G,   J_c ∂q̈ = −∂A,    G = ∂ID/∂x − ∂(J_cᵀ λ)/∂x
//! ∂q̈ = X − P (J_c X + ∂A),   X = −H⁻¹ G,   Y = H⁻¹ J_cᵀ,   K = J_c Y,   P = Y K⁺
//! (computed as ∂q̈ = −M_c G − Ȳ Sᵀ ∂A with M_c = ∂q̈/∂τ, Ȳ = Y S, K⁺ = S Sᵀ)
//! ∂q̈/∂τ = H⁻¹ − P Yᵀ
//! ```
//!
//! ∂ID/∂x from [`super::rnea_derivatives`] at a = q̈, H⁻¹ from the world-frame
//! articulated-body recursion (`minv.rs`), X by the tree-pattern product of
//! `aba_derivatives.rs`; the two constraint terms (the derivative of J_cᵀ λ
//! with λ fixed in world coordinates, and ∂A) in closed form over each side's
//! path to the root.

use super::aba_derivatives::{neg_mul_tree, TreePattern};
use super::constraint_dynamics::{
    bias_rows, check_workspace, jacobian_rows, side_point, solve_rows, ConstraintData,
    ConstraintDynamicsError,
};
use super::kkt::{mul_add, mul_add_bt};
use super::rnea_derivatives::{
    check_wrenches, rnea_derivatives_pass, rnea_derivatives_pass_after_minv, LinkWrench,
};
use super::{check_massless, check_sizes, minv};
use crate::model::{Attachment, ConstraintKind, Constraints, Data, Model};
use crate::spatial::{Force, Motion};
use nalgebra::{DMatrix, DVector, Vector3};

/// The derivatives of [`super::constraint_dynamics`] at (q, v, τ) with the link
/// wrenches `fext` (held fixed in world coordinates at their link origins, as
/// [`super::aba_derivatives`]): `cd.dqdd_dq`, `cd.dqdd_dv` (tangent space, as
/// eval-contract.md "Derivatives"), `cd.dqdd_dtau`, and `cd.qdd`, `cd.lambda`,
/// `cd.jc` as [`super::constraint_dynamics`] leaves them. The constraints'
/// frames move with their links, world anchors stay in the world; exact in
/// states that violate the constraints (the rows are defined at every q, v).
#[allow(clippy::too_many_arguments)]
pub fn constraint_dynamics_derivatives(
    model: &Model,
    data: &mut Data,
    cd: &mut ConstraintData,
    constraints: &Constraints,
    q: &DVector<f64>,
    v: &DVector<f64>,
    tau: &DVector<f64>,
    fext: Option<&[LinkWrench<f64>]>,
) -> Result<(), ConstraintDynamicsError> {
    check_sizes(model, q, &[("v", v), ("tau", tau)], None)?;
    check_wrenches(model, fext)?;
    check_massless(model)?;
    check_workspace(model, cd, constraints)?;
    let fext = fext.filter(|w| !w.is_empty());
    let mut fb = std::mem::take(&mut data.deriv_fext);
    if let Some(ws) = fext {
        super::forward_kinematics_unkeyed(model, data, q);
        fb.fill(Force::zero());
        for w in ws {
            if let Err(e) =
                super::add_link_wrench(model, data, w.frame, &w.force, &w.torque, &mut fb)
            {
                data.deriv_fext = fb;
                return Err(e.into());
            }
        }
    }
    let fbody = fext.map(|_| fb.as_slice());
    if model.has_mimic {
        // the reduced H through its factor (dense, or tree-sparse where the
        // followers keep the tree pattern)
        let r = super::constraint_dynamics::constraint_dynamics_with(
            model,
            data,
            cd,
            constraints,
            q,
            v,
            tau,
            fbody,
            true,
        )
        .map(|_| ());
        data.deriv_fext = fb;
        r?;
        // H⁻¹ = solve(H, 1), all columns at once (symmetric: rows are columns)
        let nv = model.nv;
        let mut minv = std::mem::replace(&mut data.minv, DMatrix::zeros(0, 0));
        minv.as_mut_slice().fill(0.0);
        for c in 0..nv {
            minv[(c, c)] = 1.0;
        }
        super::factor_solve_rows(model, data, nv, minv.as_mut_slice());
        data.minv = minv;
        if !super::dense_factor(model) {
            // the tree path left W in cd.y: Y = H⁻¹ J_cᵀ
            mul_add_bt(&mut cd.y, 1.0, &data.minv, &cd.jc, 0.0);
        }
    } else {
        // q̈₀ and H⁻¹ by the world-frame ABA, world velocities in data.minv_ov
        let r = minv::minv_pass(model, data, q, v, tau, fbody);
        data.deriv_fext = fb;
        r?;
        // velocity-product accelerations (world): ⁰â⁰ᵢ = ⁰â⁰ₚ + ⁰v̂ₚ × ⁰v̂ᵢ
        cd.oa0[0] = Motion::zero();
        for i in 1..model.nbodies {
            let p = model.parent[i];
            cd.oa0[i] = cd.oa0[p] + data.minv_ov[p].cross(&data.minv_ov[i]);
        }
        jacobian_rows(model, data, constraints, &mut cd.jc);
        let (ov, oa0) = (&data.minv_ov, &cd.oa0);
        bias_rows(data, constraints, |b| ov[b], |b| oa0[b], &mut cd.gamma);
        // Y = H⁻¹ J_cᵀ (J_cᵀ's zeros skipped)
        mul_add_bt(&mut cd.y, 1.0, &data.minv, &cd.jc, 0.0);
        cd.qdd.copy_from(&data.qdd);
        solve_rows(cd, constraints)?;
    }
    // ∂ID/∂q, ∂ID/∂v at a = q̈ (world velocities and accelerations kept)
    let mut a = std::mem::replace(&mut data.deriv_tmp, DVector::zeros(0));
    a.copy_from(&cd.qdd);
    if model.has_mimic {
        rnea_derivatives_pass(model, data, q, v, &a, fext);
    } else {
        // the poses and world columns of minv_pass
        rnea_derivatives_pass_after_minv(model, data, q, v, &a, fext, false);
    }
    data.deriv_tmp = a;
    // G_q −= ∂(J_cᵀ λ)/∂q; ∂A/∂q, ∂A/∂v
    cd.aq.as_mut_slice().fill(0.0);
    cd.av.as_mut_slice().fill(0.0);
    let mut row = 0;
    for con in &constraints.items {
        let n = con.rows();
        if !matches!(con.kind, ConstraintKind::Joint { .. }) {
            let frame = con.kind == ConstraintKind::Frame;
            for (side, sign) in [(&con.a, 1.0), (&con.b, -1.0)] {
                side_terms(model, data, cd, side, sign, frame, row);
            }
        }
        row += n;
    }
    // ∂q̈/∂τ = M_c = H⁻¹ − Y K⁺ Yᵀ = H⁻¹ − Ȳ Ȳᵀ with Ȳ = Y S, K⁺ = S Sᵀ
    // (docs/theory.md §"Constrained dynamics", "Derivatives")
    cd.dqdd_dtau.copy_from(&data.minv);
    if cd.rows > 0 {
        cd.kkt.right_half(&mut cd.y, &mut cd.p);
        mul_add_bt(&mut cd.dqdd_dtau, -1.0, &cd.y, &cd.y, 1.0);
    }
    // ∂q̈ = −M_c G − Ȳ (Sᵀ ∂A): first −M_c G
    if model.has_mimic || !data.deriv_direct {
        for (x, g) in [
            (&mut cd.dqdd_dq, &data.dtau_dq),
            (&mut cd.dqdd_dv, &data.dtau_dv),
        ] {
            mul_add(x, -1.0, &cd.dqdd_dtau, g, 0.0);
        }
    } else {
        let Data {
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
        neg_mul_tree(
            &cd.dqdd_dtau,
            [dtau_dq, dtau_dv],
            [&mut cd.dqdd_dq, &mut cd.dqdd_dv],
            &pat,
            [0, 0],
        );
    }
    if cd.rows == 0 {
        return Ok(());
    }
    // ∂Aᵀ S = (Sᵀ ∂A)ᵀ (aq, av hold ∂Aᵀ)
    for (x, da) in [(&mut cd.dqdd_dq, &mut cd.aq), (&mut cd.dqdd_dv, &mut cd.av)] {
        cd.kkt.right_half(da, &mut cd.p);
        mul_add_bt(x, -1.0, &cd.y, da, 1.0);
    }
    Ok(())
}

/// One side's terms (docs/theory.md §"Constrained dynamics", "Derivatives"):
/// with the force `f` (and torque `t`) it takes, `sign` times the constraint's
/// λ, held fixed in world coordinates at its point p, and the columns j, k of its
/// path (world motions `sⱼ`, on bodies mⱼ, mₖ):
/// `∂(Jᵀ w)ₖ/∂qⱼ = [mⱼ ≼ mₖ] (sⱼ × sₖ)·W + ωₖ · ((vⱼ + ωⱼ × p) × f)`, W = [t + p × f; f],
/// subtracted from `data.dtau_dq`; and the rows of ∂A/∂q, ∂A/∂v from
/// `∂⁰v̂_b/∂qⱼ = sⱼ × (⁰v̂_b − ⁰v̂_λ)`,
/// `∂⁰â_b/∂qⱼ = sⱼ × (⁰â_b − ⁰â_λ) − (sⱼ × ⁰v̂_λ) × (⁰v̂_b − ⁰v̂_λ)`,
/// `∂⁰â_b/∂q̇ⱼ = sⱼ × (⁰v̂_b − ⁰v̂ₘ − ⁰v̂_λ)` (λ = λ(mⱼ)) through
/// p̈ = a + α × p + ω × ṗ.
fn side_terms(
    model: &Model,
    data: &mut Data,
    cd: &mut ConstraintData,
    s: &Attachment,
    sign: f64,
    frame: bool,
    row: usize,
) {
    let b = s.body;
    if b == 0 {
        return;
    }
    let p = side_point(data, s);
    let lam = |i: usize| sign * cd.lambda[row + i];
    let f = Vector3::new(lam(0), lam(1), lam(2));
    let t = if frame {
        Vector3::new(lam(3), lam(4), lam(5))
    } else {
        Vector3::zeros()
    };
    let w = Force::new(t + p.cross(&f), f);
    cd.path.clear();
    let mut m = b;
    while m != 0 {
        let joint = &model.joints[m];
        for k in 0..joint.nv() {
            let sw = data.o_m_i[m].act_motion(&joint.subspace_column(k));
            cd.path.push((joint.iv + k, m, sw));
        }
        m = model.parent[m];
    }
    let (ov, oa) = (&data.deriv_ov, &data.deriv_oa);
    let (ovb, oab) = (ov[b], oa[b]);
    let omega = ovb.ang;
    let alpha = oab.ang;
    let pdot = ovb.lin + omega.cross(&p);
    let dtau = &mut data.dtau_dq;
    let n = model.nv;
    let dtau = dtau.as_mut_slice();
    for &(cj, mj, sj) in &cd.path {
        let dp = sj.lin + sj.ang.cross(&p);
        let dpf = dp.cross(&f);
        // (sⱼ × sₖ)·W = −sₖ·(sⱼ ×* W)
        let fj = sj.cross_force(&w);
        let (e1a, e1l) = (dpf - fj.ang, -fj.lin);
        let col = &mut dtau[cj * n..(cj + 1) * n];
        for &(ck, mk, sk) in &cd.path {
            let x = if mj <= mk {
                sk.ang.dot(&e1a) + sk.lin.dot(&e1l)
            } else {
                sk.ang.dot(&dpf)
            };
            col[ck] -= x;
        }
        let pm = model.parent[mj];
        let (ovp, oap) = (ov[pm], oa[pm]);
        let dvb = ovb - ovp;
        // ∂/∂q
        let dov = sj.cross(&dvb);
        let doa = sj.cross(&(oab - oap)) - sj.cross(&ovp).cross(&dvb);
        let dpdd = doa.lin
            + doa.ang.cross(&p)
            + alpha.cross(&dp)
            + dov.ang.cross(&pdot)
            + omega.cross(&(dov.lin + dov.ang.cross(&p) + omega.cross(&dp)));
        add_rows(&mut cd.aq, row, cj, sign, &dpdd, frame.then_some(&doa.ang));
        // ∂/∂v
        let doa = sj.cross(&(ovb - ov[mj] - ovp));
        let dpdd = doa.lin
            + doa.ang.cross(&p)
            + sj.ang.cross(&pdot)
            + omega.cross(&(sj.lin + sj.ang.cross(&p)));
        add_rows(&mut cd.av, row, cj, sign, &dpdd, frame.then_some(&doa.ang));
    }
}

fn add_rows(
    a: &mut DMatrix<f64>,
    row: usize,
    col: usize,
    sign: f64,
    lin: &Vector3<f64>,
    ang: Option<&Vector3<f64>>,
) {
    // a holds ∂Aᵀ (nv × m)
    for r in 0..3 {
        a[(col, row + r)] += sign * lin[r];
        if let Some(w) = ang {
            a[(col, row + 3 + r)] += sign * w[r];
        }
    }
}
