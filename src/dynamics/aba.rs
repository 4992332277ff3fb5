//! The articulated-body algorithm (ABA): forward dynamics in O(n).

use super::rnea::{act_force_ax, inv_act_motion_ax};
use super::{CompositeInertia, DynamicsError};
use crate::model::{dispatch_joint, Axis, Data, JointModel, Model};
use crate::spatial::ops::{cross, madd, mat_mat};
use crate::spatial::{Force, Motion, Scalar, Se3};
use nalgebra::{DVector, Matrix3, Matrix6, Matrix6x3, Vector3, Vector6};

/// The 6x6 angular-first matrix of a rigid-body inertia in origin form (the
/// model's `inertias_origin`, computed at load), docs/theory.md §"Spatial inertia":
/// `[I_o, h*; h*ᵀ, m 1]` with `h = m c` and `I_o = I_c − m c*c*`.
#[inline(always)]
pub(super) fn inertia_matrix<T: Scalar>(y: &CompositeInertia<T>) -> Matrix6<T> {
    // entry by entry (nalgebra's block copies went through an out-of-line
    // iterator): [I_o, h*; h*ᵀ, m 1] with h* = [0 −h_z h_y; h_z 0 −h_x; −h_y h_x 0]
    let (io, h, z) = (&y.io, &y.h, T::zero());
    let mut m = Matrix6::zeros();
    for j in 0..3 {
        for i in 0..3 {
            m[(i, j)] = io[(i, j)];
        }
    }
    let hx = [[z, -h.z, h.y], [h.z, z, -h.x], [-h.y, h.x, z]];
    for i in 0..3 {
        for j in 0..3 {
            m[(i, j + 3)] = hx[i][j];
            m[(j + 3, i)] = hx[i][j];
        }
    }
    m[(3, 3)] = y.m;
    m[(4, 4)] = y.m;
    m[(5, 5)] = y.m;
    m
}

/// The 3x3 block of `m` at `(r0, c0)`, entry by entry (nalgebra's
/// `fixed_view(..).into_owned()` and `from_rows` went through an out-of-line
/// iterator copy).
#[inline(always)]
fn block3<T: Scalar>(m: &Matrix6<T>, r0: usize, c0: usize) -> Matrix3<T> {
    Matrix3::new(
        m[(r0, c0)],
        m[(r0, c0 + 1)],
        m[(r0, c0 + 2)],
        m[(r0 + 1, c0)],
        m[(r0 + 1, c0 + 1)],
        m[(r0 + 1, c0 + 2)],
        m[(r0 + 2, c0)],
        m[(r0 + 2, c0 + 1)],
        m[(r0 + 2, c0 + 2)],
    )
}

/// The matrix with rows `r0`, `r1`, `r2`.
#[inline(always)]
fn rows3<T: Scalar>(r0: &Vector3<T>, r1: &Vector3<T>, r2: &Vector3<T>) -> Matrix3<T> {
    Matrix3::new(r0.x, r0.y, r0.z, r1.x, r1.y, r1.z, r2.x, r2.y, r2.z)
}

/// `out += ᵃX*_b I ᵇX_a`: a 6x6 spatial inertia (angular-first, blocks
/// `[A B; Bᵀ C]`) moved from frame b to frame a, given `aMb = (R, t)`
/// (docs/theory.md §"Plücker transforms"), added to `out`.
/// Rotation: every block becomes `R · Rᵀ`; then translation by `T = t*`:
/// `C' = C`, `B' = B + T C`, `A' = A − W − Wᵀ − T C T` with `W = B T`.
#[inline(always)]
fn add_act_matrix6<T: Scalar>(x: &Se3<T>, m: &Matrix6<T>, out: &mut Matrix6<T>) {
    let r = &x.rot;
    let rt = r.transpose();
    let a = mat_mat(&mat_mat(r, &block3(m, 0, 0)), &rt);
    let b = mat_mat(&mat_mat(r, &block3(m, 0, 3)), &rt);
    let c = mat_mat(&mat_mat(r, &block3(m, 3, 3)), &rt);
    add_translate6(&x.trans, &a, &b, &c, out)
}

/// `out +=` the translation part of [`add_act_matrix6`] on rotated blocks
/// `[A B; Bᵀ C]`, with `T = t*` applied as cross products (`T M` column by
/// column, `M T` row by row; no products with the zeros of `t*`).
#[inline(always)]
fn add_translate6<T: Scalar>(
    t: &Vector3<T>,
    a: &Matrix3<T>,
    b: &Matrix3<T>,
    c: &Matrix3<T>,
    out: &mut Matrix6<T>,
) {
    // T M: column j is t × M_j.
    let skew_mul = |m: &Matrix3<T>| -> Matrix3<T> {
        let c0 = cross(t, &Vector3::new(m[(0, 0)], m[(1, 0)], m[(2, 0)]));
        let c1 = cross(t, &Vector3::new(m[(0, 1)], m[(1, 1)], m[(2, 1)]));
        let c2 = cross(t, &Vector3::new(m[(0, 2)], m[(1, 2)], m[(2, 2)]));
        Matrix3::new(c0.x, c1.x, c2.x, c0.y, c1.y, c2.y, c0.z, c1.z, c2.z)
    };
    // M T: row i is M_i × t (M_i the i-th row as a vector).
    let mul_skew = |m: &Matrix3<T>| -> Matrix3<T> {
        let r0 = cross(&Vector3::new(m[(0, 0)], m[(0, 1)], m[(0, 2)]), t);
        let r1 = cross(&Vector3::new(m[(1, 0)], m[(1, 1)], m[(1, 2)]), t);
        let r2 = cross(&Vector3::new(m[(2, 0)], m[(2, 1)], m[(2, 2)]), t);
        rows3(&r0, &r1, &r2)
    };
    let tc = skew_mul(c);
    let w = mul_skew(b);
    let tct = mul_skew(&tc);
    for j in 0..3 {
        for i in 0..3 {
            let a2 = a[(i, j)] - w[(i, j)] - w[(j, i)] - tct[(i, j)];
            let b2 = b[(i, j)] + tc[(i, j)];
            out[(i, j)] += a2;
            out[(i, j + 3)] += b2;
            out[(j + 3, i)] += b2;
            out[(i + 3, j + 3)] += c[(i, j)];
        }
    }
}

/// [`add_act_matrix6`] for `x` whose rotation is a rotation about `ax` (see
/// [`crate::model::Joint::axis_rotation`]): each `R · Rᵀ` is six axis rotations of
/// 3-vectors (24 products instead of 54).
#[inline(always)]
fn add_act_matrix6_ax<T: Scalar>(
    x: &Se3<T>,
    ax: Option<Axis<T>>,
    m: &Matrix6<T>,
    out: &mut Matrix6<T>,
) {
    let Some(ax) = ax else {
        return add_act_matrix6(x, m, out);
    };
    let r = &x.rot;
    let a = sandwich_ax(ax, r, &block3(m, 0, 0));
    let b = sandwich_ax(ax, r, &block3(m, 0, 3));
    let c = sandwich_ax(ax, r, &block3(m, 3, 3));
    add_translate6(&x.trans, &a, &b, &c, out)
}

/// `R b Rᵀ` for a rotation `r` about `ax`: N = R b by columns, then row i of
/// N Rᵀ is R (row i of N) (a function, inlined: as a closure it was called out
/// of line).
#[inline(always)]
fn sandwich_ax<T: Scalar>(ax: Axis<T>, r: &Matrix3<T>, b: &Matrix3<T>) -> Matrix3<T> {
    let n0 = ax.rot_mul(r, &Vector3::new(b[(0, 0)], b[(1, 0)], b[(2, 0)]));
    let n1 = ax.rot_mul(r, &Vector3::new(b[(0, 1)], b[(1, 1)], b[(2, 1)]));
    let n2 = ax.rot_mul(r, &Vector3::new(b[(0, 2)], b[(1, 2)], b[(2, 2)]));
    let p0 = ax.rot_mul(r, &Vector3::new(n0.x, n1.x, n2.x));
    let p1 = ax.rot_mul(r, &Vector3::new(n0.y, n1.y, n2.y));
    let p2 = ax.rot_mul(r, &Vector3::new(n0.z, n1.z, n2.z));
    rows3(&p0, &p1, &p2)
}

/// `ᵃX*_b I ᵇX_a` ([`add_act_matrix6_ax`] into a zero matrix).
#[inline(always)]
fn act_matrix6_ax<T: Scalar>(x: &Se3<T>, ax: Option<Axis<T>>, m: &Matrix6<T>) -> Matrix6<T> {
    let mut out = Matrix6::zeros();
    add_act_matrix6_ax(x, ax, m, &mut out);
    out
}

/// `a += b` on 6x6 matrices (inlined: nalgebra's `+=` was an out-of-line call).
#[inline(always)]
fn add6<T: Scalar>(a: &mut Matrix6<T>, b: &Matrix6<T>) {
    for (x, &y) in a.as_mut_slice().iter_mut().zip(b.as_slice()) {
        *x += y;
    }
}

/// What a joint passes to its parent: `ᵖX*ᵢ Iᵃ ⁱXₚ` and `ᵖX*ᵢ pᵃ`.
type ParentShare<T> = (Matrix6<T>, Force<T>);

/// Sweep 2's step of a 3-DoF joint (docs/theory.md §"Spherical, planar and
/// floating joints"): its S selects three entries `k` of an angular-first vector,
/// so `U = Iᴬ S` is three columns of Iᴬ and `D = Sᵀ U` their rows `k`;
/// `u = τ − Sᵀ pᴬ` (in the first three entries) and what the parent receives,
/// `ᵖX*ᵢ Iᵃ ⁱXₚ` and `ᵖX*ᵢ pᵃ`; `None` when D is not positive definite.
#[inline(never)]
fn aba_step3_inward<T: Scalar, J: JointModel<T>>(
    jm: &J,
    ia: &Matrix6<T>,
    pa: &Force<T>,
    c: &Motion<T>,
    tau: &[T],
    li: &Se3<T>,
    to_parent: bool,
) -> Option<(Vector6<T>, ParentShare<T>)> {
    let iv = jm.joint().iv;
    let k = jm.subspace_rows();
    let pav = fvec(pa);
    let ui = Vector3::new(
        tau[iv] - pav[k[0]],
        tau[iv + 1] - pav[k[1]],
        tau[iv + 2] - pav[k[2]],
    );
    let uq = Vector6::new(ui.x, ui.y, ui.z, T::zero(), T::zero(), T::zero());
    let dinv = sym3_inverse(&Matrix3::from_fn(|r, s| ia[(k[r], k[s])]))?;
    if !to_parent {
        return Some((uq, (Matrix6::zeros(), Force::zero())));
    }
    let u_mat = Matrix6x3::from_fn(|r, s| ia[(r, k[s])]);
    let ud = u_mat * dinv;
    let ia_a = ia - ud * u_mat.transpose();
    let pa_a = pav + ia_a * mvec(c) + ud * ui;
    let ax = jm.rot_axis();
    Some((
        uq,
        (
            act_matrix6_ax(li, ax, &ia_a),
            act_force_ax(li, ax, &vforce(&pa_a)),
        ),
    ))
}

/// Sweep 3's step of a 3-DoF joint: `q̈ = D⁻¹ (u − Uᵀ a')` into `qdd` (Uᵀ a' the
/// rows `k` of Iᴬ a', Iᴬ symmetric), and `âᵢ = a' + S q̈`.
#[inline(never)]
fn aba_step3_outward<T: Scalar, J: JointModel<T>>(
    jm: &J,
    ia: &Matrix6<T>,
    u: &Vector6<T>,
    a1: &Motion<T>,
    qdd: &mut [T],
) -> Option<Motion<T>> {
    let iv = jm.joint().iv;
    let k = jm.subspace_rows();
    let dinv = sym3_inverse(&Matrix3::from_fn(|r, s| ia[(k[r], k[s])]))?;
    let av = mvec(a1);
    let uta = Vector3::from_fn(|r, _| ia.row(k[r]).dot(&av.transpose()));
    let x = dinv * (Vector3::new(u[0], u[1], u[2]) - uta);
    let mut ai = av;
    for r in 0..3 {
        qdd[iv + r] = x[r];
        ai[k[r]] += x[r];
    }
    Some(Motion::new(
        Vector3::new(ai[0], ai[1], ai[2]),
        Vector3::new(ai[3], ai[4], ai[5]),
    ))
}

/// The inverse of a symmetric 3x3 matrix by cofactors, `None` unless it is
/// positive definite (leading minors positive) with a finite inverse.
#[inline(always)]
fn sym3_inverse<T: Scalar>(d: &Matrix3<T>) -> Option<Matrix3<T>> {
    let c00 = d[(1, 1)] * d[(2, 2)] - d[(1, 2)] * d[(1, 2)];
    let c01 = d[(0, 2)] * d[(1, 2)] - d[(0, 1)] * d[(2, 2)];
    let c02 = d[(0, 1)] * d[(1, 2)] - d[(0, 2)] * d[(1, 1)];
    let det = d[(0, 0)] * c00 + d[(0, 1)] * c01 + d[(0, 2)] * c02;
    let m2 = d[(0, 0)] * d[(1, 1)] - d[(0, 1)] * d[(0, 1)];
    if !(d[(0, 0)] > T::zero() && m2 > T::zero() && det > T::zero()) {
        return None;
    }
    let c11 = d[(0, 0)] * d[(2, 2)] - d[(0, 2)] * d[(0, 2)];
    let c12 = d[(0, 1)] * d[(0, 2)] - d[(0, 0)] * d[(1, 2)];
    let c22 = m2;
    let inv = Matrix3::new(c00, c01, c02, c01, c11, c12, c02, c12, c22) * (T::one() / det);
    inv.iter().all(|x| x.is_finite()).then_some(inv)
}

#[inline(always)]
fn mvec<T: Scalar>(m: &Motion<T>) -> Vector6<T> {
    Vector6::new(m.ang.x, m.ang.y, m.ang.z, m.lin.x, m.lin.y, m.lin.z)
}
#[inline(always)]
pub(super) fn fvec<T: Scalar>(f: &Force<T>) -> Vector6<T> {
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
                    add_act_matrix6_ax(li, ax, &ia_a, &mut ia_head[p]);
                    pa_head[p] += act_force_ax(li, ax, &vforce(&pa_a));
                }
            } else if jm.nv() == 3 {
                // a 3-DoF joint (spherical, planar), out of line (the 1-DoF paths stay small)
                let (ui, pass) =
                    aba_step3_inward(&jm, &ia_tail[0], &pa_tail[0], &cc[i], tau, li, p != 0)
                        .ok_or(DynamicsError::Singular(iv))?;
                uu[i] = ui;
                if p != 0 {
                    add6(&mut ia_head[p], &pass.0);
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
                let x = super::linalg::spd6_solve(&ia[i], &uu[i]).ok_or(DynamicsError::Singular(iv))?;
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
