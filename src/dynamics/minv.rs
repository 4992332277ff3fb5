//! H⁻¹ and q̈ together, by the articulated-body recursion in world coordinates
//! (Carpentier & Mansard, RSS 2018; Pinocchio's `computeABADerivatives`, passes
//! 1–3, and `computeMinverse`): docs/theory.md §"Derivatives", "Inverse of H".
//! O(n·nv) for n coordinates; `aba_derivatives` is its one caller.

use super::DynamicsError;
use crate::model::{dispatch_joint, Data, JointModel, Model};
use crate::spatial::ops::madd;
use crate::spatial::{CompositeInertia, Force, Motion, Scalar};
use nalgebra::{DVector, Matrix6, Vector3, Vector6};

/// `[I_o, h*; h*ᵀ, m 1]`, the 6x6 angular-first matrix of an origin-form inertia
/// (docs/theory.md §"Spatial inertia").
#[inline(always)]
fn matrix6<T: Scalar>(y: &CompositeInertia<T>) -> Matrix6<T> {
    let hx = crate::spatial::skew(&y.h);
    let mut m = Matrix6::zeros();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&y.io);
    m.fixed_view_mut::<3, 3>(0, 3).copy_from(&hx);
    m.fixed_view_mut::<3, 3>(3, 0).copy_from(&hx.transpose());
    m[(3, 3)] = y.m;
    m[(4, 4)] = y.m;
    m[(5, 5)] = y.m;
    m
}

#[inline(always)]
fn mv<T: Scalar>(m: &Motion<T>) -> Vector6<T> {
    m.to_vector()
}

#[inline(always)]
fn fv<T: Scalar>(x: &Vector6<T>) -> Force<T> {
    Force::new(
        Vector3::new(x[0], x[1], x[2]),
        Vector3::new(x[3], x[4], x[5]),
    )
}

#[inline(always)]
fn ff<T: Scalar>(f: &Force<T>) -> Vector6<T> {
    f.to_vector()
}

/// `f += a · s` on spatial forces.
#[inline(always)]
fn force_axpy<T: Scalar>(f: &mut Force<T>, s: T, a: &Force<T>) {
    for r in 0..3 {
        f.ang[r] = madd(s, a.ang[r], f.ang[r]);
        f.lin[r] = madd(s, a.lin[r], f.lin[r]);
    }
}

/// `m += a · s` on spatial motions.
#[inline(always)]
fn motion_axpy<T: Scalar>(m: &mut Motion<T>, s: T, a: &Motion<T>) {
    for r in 0..3 {
        m.ang[r] = madd(s, a.ang[r], m.ang[r]);
        m.lin[r] = madd(s, a.lin[r], m.lin[r]);
    }
}

/// `data.qdd` = q̈ = FD(q, v, τ) with the per-body world wrenches `fext` (at the
/// world origin, as [`super::rnea`] takes them) and `data.minv` = H⁻¹ (whole,
/// symmetric), by three sweeps in world coordinates (docs/theory.md
/// §"Derivatives", "Inverse of H"). Models without mimic joints (checked by the
/// caller, with the sizes and the massless joints). A non-positive or non-finite
/// pivot `D` is [`DynamicsError::Singular`] (its coordinate).
pub(crate) fn minv_pass<T: Scalar>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &DVector<T>,
    v: &DVector<T>,
    tau: &DVector<T>,
    fext: Option<&[Force<T>]>,
) -> Result<(), DynamicsError> {
    let nb = model.nbodies;
    let nv = model.nv;
    let (q, v, tau) = (q.as_slice(), v.as_slice(), tau.as_slice());
    let joints = &model.joints[..nb];
    let parent = &model.parent[..nb];
    let placements = &model.placements[..nb];
    let ident = &model.placement_identity[..nb];
    let inertias = &model.inertias_origin[..nb];
    let Data {
        li_m_i,
        o_m_i,
        qdd,
        minv,
        deriv_sub_end: sub_end,
        minv_j: jcol,
        minv_udinv: udinv,
        minv_uq: uq,
        minv_ia: ia,
        minv_ov: ov,
        minv_agf: agf,
        minv_of: of,
        minv_fcol: fcol,
        minv_acol: acol,
        minv_acol_off: acol_off,
        ..
    } = data;
    let qdd = qdd.as_mut_slice();
    // Row r of H⁻¹'s upper triangle (columns c ≥ r) is kept as column r of `m`
    // from row r down (contiguous): `m[c + r n] = H⁻¹[r, c]`; mirrored at the end.
    let m = minv.as_mut_slice();
    m.fill(T::zero());

    // Sweep 1, root outwards: ⁰Mᵢ, J = ⁰X̂ᵢ S, ⁰v̂ᵢ, the velocity-product
    // acceleration cᵢ = ⁰v̂_λ × ⁰v̂ᵢ, Yᵢ as Iᴬᵢ and the bias force pᴬᵢ.
    ov[0] = Motion::zero();
    for i in 1..nb {
        let p = parent[i];
        let (op, ovp) = (o_m_i[p], ov[p]);
        let ovi = dispatch_joint!(&joints[i], ident[i], jm => {
            let li = jm.placement(&placements[i], q);
            let om = jm.world_pose(&op, &li);
            li_m_i[i] = li;
            o_m_i[i] = om;
            let iv = jm.joint().iv;
            // ⁰v̂ᵢ = ⁰v̂_λ + J q̇
            let mut vj = Motion::zero();
            for c in 0..jm.nv() {
                let s = jm.subspace_in(c, &om);
                jcol[iv + c] = s;
                motion_axpy(&mut vj, v[iv + c], &s);
            }
            ovp + vj
        });
        ov[i] = ovi;
        // cᵢ = ⁰v̂_λ × ⁰v̂ᵢ (= ⁰v̂ᵢ × J q̇)
        agf[i] = ovp.cross(&ovi);
        // Iᴬᵢ = Yᵢ = ⁰X̂*ᵢ Îᵢ ⁱX̂₀, pᴬᵢ = ⁰v̂ᵢ ×* Yᵢ ⁰v̂ᵢ − f̂ᵢˣ
        let y = inertias[i].act(&o_m_i[i]);
        ia[i] = matrix6(&y);
        let mut pi = ovi.cross_force(&y.mul_motion(&ovi));
        if let Some(fx) = fext {
            pi -= fx[i];
        }
        of[i] = pi;
    }

    // Sweep 2, leaves inwards: uᵢ = τᵢ − Jᵀ pᴬᵢ, U = Iᴬ J, D = Jᵀ U; the rows of
    // H⁻¹ against the subtree, H⁻¹[i, i] = D⁻¹, H⁻¹[i, sub] = −D⁻¹ Jᵀ F[sub]; the
    // columns' forces F[sub] += U H⁻¹[i, sub] and Iᵃ, pᵃ passed to the parent.
    for i in (1..nb).rev() {
        let p = parent[i];
        let jt = &joints[i];
        let (c0, ni) = (jt.iv, jt.nv());
        let (ce, end) = (c0 + ni, sub_end[i]);
        let fi = of[i];
        let mut iai = ia[i];
        if ni == 1 {
            let s = jcol[c0];
            let ui = tau[c0] - s.dot(&fi);
            uq[c0] = ui;
            let u = fv(&(iai * mv(&s)));
            let d = s.dot(&u);
            if !(d > T::zero()) || !d.is_finite() {
                return Err(DynamicsError::Singular(c0));
            }
            let dinv = T::one() / d;
            let ud = u * dinv;
            udinv[c0] = ud;
            let col = &mut m[c0 * nv..(c0 + 1) * nv];
            col[c0] = dinv;
            // H⁻¹[i, c] = −D⁻¹ Jᵀ F_c over the strict subtree
            for c in ce..end {
                col[c] = -dinv * s.dot(&fcol[c]);
            }
            if p != 0 {
                // F_c += U H⁻¹[i, c]
                fcol[c0] = ud;
                for c in ce..end {
                    force_axpy(&mut fcol[c], col[c], &u);
                }
                // Iᵃ = Iᴬ − U D⁻¹ Uᵀ, pᵃ = pᴬ + Iᵃ c + U D⁻¹ u
                let (uvec, udvec) = (ff(&u), ff(&ud));
                for cc in 0..6 {
                    for r in 0..6 {
                        iai[(r, cc)] = madd(-udvec[r], uvec[cc], iai[(r, cc)]);
                    }
                }
                let pa = fi + fv(&(iai * mv(&agf[i]))) + ud * ui;
                ia[p] += iai;
                of[p] += pa;
            }
        } else {
            // a free joint (6 coordinates): J, U = Iᴬ J and D = Jᵀ U as 6x6 blocks
            let mut jm = Matrix6::<T>::zeros();
            for r in 0..ni {
                jm.set_column(r, &mv(&jcol[c0 + r]));
                uq[c0 + r] = tau[c0 + r] - jcol[c0 + r].dot(&fi);
            }
            let u = iai * jm;
            let d = jm.transpose() * u;
            let dinv = d
                .cholesky()
                .map(|ch| ch.inverse())
                .ok_or(DynamicsError::Singular(c0))?;
            let ud = u * dinv;
            for r in 0..ni {
                udinv[c0 + r] = fv(&ud.column(r).into_owned());
                for s in 0..ni {
                    m[c0 + s + (c0 + r) * nv] = dinv[(r, s)];
                }
            }
            // H⁻¹[i, c] = −D⁻¹ Jᵀ F_c over the strict subtree
            for c in ce..end {
                let jf = jm.transpose() * ff(&fcol[c]);
                let x = -(dinv * jf);
                for r in 0..ni {
                    m[c + (c0 + r) * nv] = x[r];
                }
            }
            if p != 0 {
                for c in c0..end {
                    let mut f = if c < ce { Force::zero() } else { fcol[c] };
                    for r in 0..ni {
                        force_axpy(&mut f, m[c + (c0 + r) * nv], &fv(&u.column(r).into_owned()));
                    }
                    fcol[c] = f;
                }
                let uvec = Vector6::from_column_slice(&uq[c0..ce]);
                iai -= ud * u.transpose();
                let pa = fi + fv(&(iai * mv(&agf[i]) + ud * uvec));
                ia[p] += iai;
                of[p] += pa;
            }
        }
    }

    // Sweep 3, root outwards from â₀ = [0; −g]: a' = â_λ + cᵢ,
    // q̈ᵢ = D⁻¹ uᵢ − (U D⁻¹)ᵀ a', âᵢ = a' + J q̈ᵢ; the rows of H⁻¹ against every
    // later column, H⁻¹[i, c] −= (U D⁻¹)ᵀ A_λ[c], and the columns' accelerations
    // Aᵢ[c] = A_λ[c] + J H⁻¹[i, c] (c ≥ i).
    agf[0] = Motion::new(Vector3::zeros(), -model.gravity);
    for i in 1..nb {
        let p = parent[i];
        let jt = &joints[i];
        let (c0, ni) = (jt.iv, jt.nv());
        let ce = c0 + ni;
        let mut ai = agf[i] + agf[p];
        for r in 0..ni {
            // q̈_r = Σ_s D⁻¹[r, s] u_s − (U D⁻¹)_rᵀ a'
            let mut x = -ai.dot(&udinv[c0 + r]);
            for s in 0..ni {
                x = madd(m[c0 + s + (c0 + r) * nv], uq[c0 + s], x);
            }
            qdd[c0 + r] = x;
        }
        for r in 0..ni {
            motion_axpy(&mut ai, qdd[c0 + r], &jcol[c0 + r]);
        }
        agf[i] = ai;
        let leaf = sub_end[i] == ce;
        let (oi, op) = (acol_off[i], acol_off[p]);
        let (ci0, cp0) = (c0, if p != 0 { joints[p].iv } else { 0 });
        for c in c0..nv {
            let ap = if p != 0 {
                acol[op + c - cp0]
            } else {
                Motion::zero()
            };
            let mut a = ap;
            for r in 0..ni {
                let at = c + (c0 + r) * nv;
                let mut x = m[at];
                if p != 0 {
                    x -= ap.dot(&udinv[c0 + r]);
                    m[at] = x;
                }
                motion_axpy(&mut a, x, &jcol[c0 + r]);
            }
            if !leaf {
                acol[oi + c - ci0] = a;
            }
        }
    }

    // The lower triangle holds H⁻¹'s; mirror it.
    for r in 0..nv {
        for c in (r + 1)..nv {
            m[r + c * nv] = m[c + r * nv];
        }
    }
    Ok(())
}
