//! The articulated-body algorithm (ABA): forward dynamics in O(n).

use super::rnea::{act_force_ax, inv_act_motion_ax};
use super::{CompositeInertia, DynamicsError};
use crate::model::{dispatch_joint, Axis, Data, JointModel, Model};
use crate::spatial::ops::{cross, madd, mat_mat};
use crate::spatial::{skew, Force, Motion, Scalar, Se3};
use nalgebra::{DVector, Matrix3, Matrix6, Matrix6x3, Vector3, Vector6};

/// The 6x6 angular-first matrix of a rigid-body inertia in origin form (the
/// model's `inertias_origin`, computed at load), docs/theory.md §"Spatial inertia":
/// `[I_o, h*; h*ᵀ, m 1]` with `h = m c` and `I_o = I_c − m c*c*`.
#[inline(always)]
fn inertia_matrix<T: Scalar>(i: &CompositeInertia<T>) -> Matrix6<T> {
    let hx = skew(&i.h);
    let mut m = Matrix6::zeros();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&i.io);
    m.fixed_view_mut::<3, 3>(0, 3).copy_from(&hx);
    m.fixed_view_mut::<3, 3>(3, 0).copy_from(&hx.transpose());
    m[(3, 3)] = i.m;
    m[(4, 4)] = i.m;
    m[(5, 5)] = i.m;
    m
}

/// `ᵃX*_b I ᵇX_a`: a 6x6 spatial inertia (angular-first, blocks `[A B; Bᵀ C]`)
/// moved from frame b to frame a, given `aMb = (R, t)` (docs/theory.md
/// §"Plücker transforms").
/// Rotation: every block becomes `R · Rᵀ`; then translation by `T = t*`:
/// `C' = C`, `B' = B + T C`, `A' = A − W − Wᵀ − T C T` with `W = B T`.
#[inline(always)]
fn act_matrix6<T: Scalar>(x: &Se3<T>, m: &Matrix6<T>) -> Matrix6<T> {
    let r = &x.rot;
    let a: Matrix3<T> = m.fixed_view::<3, 3>(0, 0).into_owned();
    let b: Matrix3<T> = m.fixed_view::<3, 3>(0, 3).into_owned();
    let c: Matrix3<T> = m.fixed_view::<3, 3>(3, 3).into_owned();
    let rt = r.transpose();
    let a = mat_mat(&mat_mat(r, &a), &rt);
    let b = mat_mat(&mat_mat(r, &b), &rt);
    let c = mat_mat(&mat_mat(r, &c), &rt);
    translate6(&x.trans, &a, &b, &c)
}

/// The translation part of [`act_matrix6`] on rotated blocks `[A B; Bᵀ C]`, with
/// `T = t*` applied as cross products (`T M` column by column, `M T` row by row;
/// no products with the zeros of `t*`).
#[inline(always)]
fn translate6<T: Scalar>(
    t: &Vector3<T>,
    a: &Matrix3<T>,
    b: &Matrix3<T>,
    c: &Matrix3<T>,
) -> Matrix6<T> {
    // T M: column j is t × M_j.
    let skew_mul = |m: &Matrix3<T>| -> Matrix3<T> {
        Matrix3::from_columns(&[
            cross(t, &m.column(0).into()),
            cross(t, &m.column(1).into()),
            cross(t, &m.column(2).into()),
        ])
    };
    // M T: row i is M_i × t (M_i the i-th row as a vector).
    let mul_skew = |m: &Matrix3<T>| -> Matrix3<T> {
        let r0 = cross(&Vector3::new(m[(0, 0)], m[(0, 1)], m[(0, 2)]), t);
        let r1 = cross(&Vector3::new(m[(1, 0)], m[(1, 1)], m[(1, 2)]), t);
        let r2 = cross(&Vector3::new(m[(2, 0)], m[(2, 1)], m[(2, 2)]), t);
        Matrix3::from_rows(&[r0.transpose(), r1.transpose(), r2.transpose()])
    };
    let tc = skew_mul(c);
    let w = mul_skew(b);
    let a2 = a - w - w.transpose() - mul_skew(&tc);
    let b2 = b + tc;
    let mut out = Matrix6::zeros();
    out.fixed_view_mut::<3, 3>(0, 0).copy_from(&a2);
    out.fixed_view_mut::<3, 3>(0, 3).copy_from(&b2);
    out.fixed_view_mut::<3, 3>(3, 0).copy_from(&b2.transpose());
    out.fixed_view_mut::<3, 3>(3, 3).copy_from(c);
    out
}

/// [`act_matrix6`] for `x` whose rotation is a rotation about `ax` (see
/// [`crate::model::Joint::axis_rotation`]): each `R · Rᵀ` is six axis rotations of
/// 3-vectors (24 products instead of 54).
#[inline(always)]
fn act_matrix6_ax<T: Scalar>(x: &Se3<T>, ax: Option<Axis<T>>, m: &Matrix6<T>) -> Matrix6<T> {
    let Some(ax) = ax else {
        return act_matrix6(x, m);
    };
    let r = &x.rot;
    // R b Rᵀ: N = R b by columns, then row i of N Rᵀ is R (row i of N).
    let sandwich = |b: Matrix3<T>| -> Matrix3<T> {
        let n0 = ax.rot_mul(r, &b.column(0).into());
        let n1 = ax.rot_mul(r, &b.column(1).into());
        let n2 = ax.rot_mul(r, &b.column(2).into());
        let p0 = ax.rot_mul(r, &Vector3::new(n0.x, n1.x, n2.x));
        let p1 = ax.rot_mul(r, &Vector3::new(n0.y, n1.y, n2.y));
        let p2 = ax.rot_mul(r, &Vector3::new(n0.z, n1.z, n2.z));
        Matrix3::from_rows(&[p0.transpose(), p1.transpose(), p2.transpose()])
    };
    let a = sandwich(m.fixed_view::<3, 3>(0, 0).into_owned());
    let b = sandwich(m.fixed_view::<3, 3>(0, 3).into_owned());
    let c = sandwich(m.fixed_view::<3, 3>(3, 3).into_owned());
    translate6(&x.trans, &a, &b, &c)
}

/// Sweep 2's step of a 3-DoF joint (docs/theory.md §"Spherical, planar and
/// floating joints"): `u = τ − Sᵀ pᴬ` (in the first three entries) and what the
/// parent receives, `ᵖX*ᵢ Iᵃ ⁱXₚ` and `ᵖX*ᵢ pᵃ`; `None` when D is singular.
#[inline(never)]
fn aba_step3_inward<T: Scalar, J: JointModel<T>>(
    jm: &J,
    ia: &Matrix6<T>,
    pa: &Force<T>,
    c: &Motion<T>,
    tau: &[T],
    li: &Se3<T>,
) -> Option<(Vector6<T>, (Matrix6<T>, Force<T>))> {
    let iv = jm.joint().iv;
    let (u_mat, dinv) = subspace_blocks(jm, ia)?;
    let ui = Vector3::from_fn(|r, _| tau[iv + r] - jm.project_column(r, pa));
    let ud = u_mat * dinv;
    let ia_a = ia - ud * u_mat.transpose();
    let pa_a = fvec(pa) + ia_a * mvec(c) + ud * ui;
    let ax = jm.rot_axis();
    Some((
        Vector6::new(ui.x, ui.y, ui.z, T::zero(), T::zero(), T::zero()),
        (act_matrix6_ax(li, ax, &ia_a), act_force_ax(li, ax, &vforce(&pa_a))),
    ))
}

/// Sweep 3's step of a 3-DoF joint: `q̈ = D⁻¹ (u − Uᵀ a')` into `qdd`, and
/// `âᵢ = a' + S q̈`.
#[inline(never)]
fn aba_step3_outward<T: Scalar, J: JointModel<T>>(
    jm: &J,
    ia: &Matrix6<T>,
    u: &Vector6<T>,
    a1: &Motion<T>,
    qdd: &mut [T],
) -> Option<Motion<T>> {
    let iv = jm.joint().iv;
    let (u_mat, dinv) = subspace_blocks(jm, ia)?;
    let x = dinv * (Vector3::new(u[0], u[1], u[2]) - u_mat.transpose() * mvec(a1));
    let mut ai = *a1;
    for r in 0..3 {
        qdd[iv + r] = x[r];
        ai += jm.subspace(r) * x[r];
    }
    Some(ai)
}

/// A 3-DoF joint's `U = Iᴬ S` (6x3) and `D⁻¹ = (Sᵀ U)⁻¹`, `None` when D is not
/// positive definite.
#[inline(always)]
fn subspace_blocks<T: Scalar, J: JointModel<T>>(
    jm: &J,
    ia: &Matrix6<T>,
) -> Option<(Matrix6x3<T>, Matrix3<T>)> {
    let s = Matrix6x3::from_fn(|r, c| mvec(&jm.subspace(c))[r]);
    let u = ia * s;
    let d = s.transpose() * u;
    let dinv = d.cholesky()?.inverse();
    dinv.iter().all(|x| x.is_finite()).then_some((u, dinv))
}

#[inline(always)]
fn mvec<T: Scalar>(m: &Motion<T>) -> Vector6<T> {
    Vector6::new(m.ang.x, m.ang.y, m.ang.z, m.lin.x, m.lin.y, m.lin.z)
}
#[inline(always)]
fn fvec<T: Scalar>(f: &Force<T>) -> Vector6<T> {
    Vector6::new(f.ang.x, f.ang.y, f.ang.z, f.lin.x, f.lin.y, f.lin.z)
}
#[inline(always)]
fn vforce<T: Scalar>(x: &Vector6<T>) -> Force<T> {
    Force::new(
        Vector3::new(x[0], x[1], x[2]),
        Vector3::new(x[3], x[4], x[5]),
    )
}

/// Forward dynamics by the articulated-body algorithm (Featherstone, RBDA §7.3):
/// `q̈` with `H q̈ + C = τ` (docs/theory.md §"Equation of motion") in three sweeps,
/// written to `data.qdd` (docs/theory.md §"Articulated-body algorithm").
///
/// 1. Root outwards: velocities (docs/theory.md §"Velocity recursion"), the
///    velocity-product accelerations `cᵢ = v̂ᵢ × ŝᵢ q̇ᵢ` (docs/theory.md
///    §"Acceleration recursion"), the rigid-body inertias `Iᴬᵢ = Îᵢ` (docs/theory.md
///    §"Spatial inertia") and bias forces `pᴬᵢ = v̂ᵢ ×* Îᵢ v̂ᵢ − ᵢX̂₀ f̂ᵢˣ`
///    (docs/theory.md §"Force recursion" with â = 0).
/// 2. Leaves inwards: `Uᵢ = Iᴬᵢ Sᵢ`, `Dᵢ = Sᵢᵀ Uᵢ`, `uᵢ = τᵢ − Sᵢᵀ pᴬᵢ`; the parent
///    receives `Iᵃ = Iᴬᵢ − Uᵢ Dᵢ⁻¹ Uᵢᵀ` and `pᵃ = pᴬᵢ + Iᵃ cᵢ + Uᵢ Dᵢ⁻¹ uᵢ`, moved by
///    `ᵖX*ᵢ` (docs/theory.md §"Plücker transforms").
/// 3. Root outwards, from `â₀ = [0; −g]` (docs/theory.md §"Gravity"):
///    `a' = ᵢX̂ₚ âₚ + cᵢ`, `q̈ᵢ = Dᵢ⁻¹ (uᵢ − Uᵢᵀ a')`, `âᵢ = a' + Sᵢ q̈ᵢ`
///    (docs/theory.md §"Acceleration recursion").
///
/// A free joint is one 6-DoF joint (S = 1 up to the coordinate order): its 6x6
/// `D = Iᴬ` is factorised directly, `âᵢ = Iᴬ⁻¹ (τ − pᴬ)`, and it passes nothing but
/// its own generalized force to a parent. External forces `fext` are per body in
/// the world frame, as in [`super::rnea`]. Mimic joints cannot be expressed (their
/// coupling is not a tree): such models get [`DynamicsError::Mimic`].
pub fn aba<'d, T: Scalar>(
    model: &Model<T>,
    data: &'d mut Data<T>,
    q: &DVector<T>,
    v: &DVector<T>,
    tau: &DVector<T>,
    fext: Option<&[Force<T>]>,
) -> Result<&'d DVector<T>, DynamicsError> {
    super::check_sizes(model, q, &[("v", v), ("tau", tau)], fext)?;
    if model.has_mimic {
        return Err(DynamicsError::Mimic);
    }
    super::check_massless(model)?;
    let nb = model.nbodies;
    let q = q.as_slice();
    let v = v.as_slice();
    let tau = tau.as_slice();
    let joints = &model.joints[..nb];
    let parent = &model.parent[..nb];
    let placements = &model.placements[..nb];
    let ident = &model.placement_identity[..nb];
    let inertias = &model.inertias[..nb];
    let inertias_o = &model.inertias_origin[..nb];
    let li_m_i = &mut data.li_m_i[..nb];
    let o_m_i = &mut data.o_m_i[..nb];
    let vel = &mut data.v[..nb];
    let acc = &mut data.a[..nb];
    let pa = &mut data.f[..nb];
    let ia = &mut data.aba_ia[..nb];
    let uu = &mut data.aba_u[..nb];
    let dinv = &mut data.aba_dinv[..nb];
    let uq = &mut data.aba_uq[..nb];
    let cc = &mut data.aba_c[..nb];

    // Sweep 1. Each sweep matches a body's joint kind once (dispatch_joint!).
    vel[0] = Motion::zero();
    for i in 1..nb {
        let p = parent[i];
        let vp = vel[p];
        let (m, vi, ci) = dispatch_joint!(&joints[i], ident[i], jm => {
            let m = jm.placement(&placements[i], q);
            // docs/theory.md §"Velocity recursion"
            let mut vi = inv_act_motion_ax(&m, jm.rot_axis(), &vp);
            jm.add_motion(&mut vi, v);
            let mut ci = Motion::zero();
            jm.add_cross_motion(&mut ci, &vi, v);
            (m, vi, ci)
        });
        li_m_i[i] = m;
        vel[i] = vi;
        cc[i] = ci;
        let inertia = &inertias[i];
        ia[i] = inertia_matrix(&inertias_o[i]);
        let mut pi = vi.cross_force(&inertia.mul_motion(&vi));
        if let Some(fext) = fext {
            let om = o_m_i[p].compose(&m);
            o_m_i[i] = om;
            if let Some(fx) = fext.get(i) {
                pi -= om.inv_act_force(fx);
            }
        }
        pa[i] = pi;
    }

    // Sweep 2.
    for i in (1..nb).rev() {
        let p = parent[i];
        let (ia_head, ia_tail) = ia.split_at_mut(i);
        let (pa_head, pa_tail) = pa.split_at_mut(i);
        let li = &li_m_i[i];
        dispatch_joint!(&joints[i], ident[i], jm => {
            let iv = jm.joint().iv;
            if jm.nv() == 1 {
                let u_col = jm.mat6_subspace(&ia_tail[0]);
                let d = jm.subspace_dot6(&u_col);
                if !(d > T::zero()) || !d.is_finite() {
                    return Err(DynamicsError::Singular(iv));
                }
                let di = T::one() / d;
                let ui = tau[iv] - jm.project_column(0, &pa_tail[0]);
                uu[i] = u_col;
                dinv[i] = di;
                uq[i] = ui;
                if p != 0 {
                    // Iᵃ = Iᴬ − U D⁻¹ Uᵀ, pᵃ = pᴬ + Iᵃ c + U D⁻¹ u
                    let ud = u_col * di;
                    let mut ia_a = ia_tail[0];
                    for c in 0..6 {
                        for r in 0..6 {
                            ia_a[(r, c)] = madd(-ud[r], u_col[c], ia_a[(r, c)]);
                        }
                    }
                    let mut pa_a = fvec(&pa_tail[0]);
                    let cv = mvec(&cc[i]);
                    for r in 0..6 {
                        pa_a[r] = madd(ud[r], ui, pa_a[r]);
                    }
                    for c in 0..6 {
                        for r in 0..6 {
                            pa_a[r] = madd(ia_a[(r, c)], cv[c], pa_a[r]);
                        }
                    }
                    let ax = jm.rot_axis();
                    ia_head[p] += act_matrix6_ax(li, ax, &ia_a);
                    pa_head[p] += act_force_ax(li, ax, &vforce(&pa_a));
                }
            } else if jm.nv() == 3 {
                // a 3-DoF joint (spherical, planar), out of line (the 1-DoF paths stay small)
                let (ui, pass) = aba_step3_inward(&jm, &ia_tail[0], &pa_tail[0], &cc[i], tau, li)
                    .ok_or(DynamicsError::Singular(iv))?;
                uu[i] = ui;
                if p != 0 {
                    ia_head[p] += pass.0;
                    pa_head[p] += pass.1;
                }
            } else {
                let t = &tau[iv..iv + 6];
                let tf = Force::new(Vector3::new(t[3], t[4], t[5]), Vector3::new(t[0], t[1], t[2]));
                uu[i] = fvec(&(tf - pa_tail[0]));
                if p != 0 {
                    pa_head[p] += act_force_ax(li, jm.rot_axis(), &tf);
                }
            }
        });
    }

    // Sweep 3.
    acc[0] = Motion::new(Vector3::zeros(), -model.gravity);
    let qdd = data.qdd.as_mut_slice();
    for i in 1..nb {
        let p = parent[i];
        let ap = acc[p];
        let li = &li_m_i[i];
        let ai = dispatch_joint!(&joints[i], ident[i], jm => {
            // docs/theory.md §"Acceleration recursion"
            let a1 = inv_act_motion_ax(li, jm.rot_axis(), &ap) + cc[i];
            let iv = jm.joint().iv;
            if jm.nv() == 1 {
                let x = dinv[i] * (uq[i] - a1.dot(&vforce(&uu[i])));
                qdd[iv] = x;
                let mut ai = a1;
                jm.add_subspace_scaled(&mut ai, x);
                ai
            } else if jm.nv() == 3 {
                aba_step3_outward(&jm, &ia[i], &uu[i], &a1, qdd).ok_or(DynamicsError::Singular(iv))?
            } else {
                let chol = ia[i].cholesky().ok_or(DynamicsError::Singular(iv))?;
                let x = chol.solve(&uu[i]);
                let ai = Motion::new(
                    Vector3::new(x[0], x[1], x[2]),
                    Vector3::new(x[3], x[4], x[5]),
                );
                let rel = ai - a1;
                let qd = &mut qdd[iv..iv + 6];
                for r in 0..3 {
                    qd[r] = rel.lin[r];
                    qd[3 + r] = rel.ang[r];
                }
                ai
            }
        });
        acc[i] = ai;
    }
    Ok(&data.qdd)
}
