//! H⁻¹ and q̈ together, by the articulated-body recursion in world coordinates
//! (Carpentier & Mansard, RSS 2018; Pinocchio's `computeABADerivatives`, passes
//! 1–3, and `computeMinverse`): docs/theory.md §"Derivatives", "Inverse of H".
//! O(n·nv) for n coordinates; `aba_derivatives` is its one caller.

use super::DynamicsError;
use crate::model::{dispatch_joint, Data, JointModel, Model};
use crate::spatial::ops::madd;
use crate::spatial::{CompositeInertia, Force, Motion, Scalar};
use nalgebra::{DVector, Matrix6, Vector3, Vector6};

/// `m = [I_o, h*; h*ᵀ, m 1]`, the 6x6 angular-first matrix of an origin-form inertia
/// (docs/theory.md §"Spatial inertia").
#[inline(always)]
fn matrix6<T: Scalar>(y: &CompositeInertia<T>, m: &mut Matrix6<T>) {
    let hx = crate::spatial::skew(&y.h);
    m.fill(T::zero());
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&y.io);
    m.fixed_view_mut::<3, 3>(0, 3).copy_from(&hx);
    m.fixed_view_mut::<3, 3>(3, 0).copy_from(&hx.transpose());
    m[(3, 3)] = y.m;
    m[(4, 4)] = y.m;
    m[(5, 5)] = y.m;
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

/// `y += a x` on slices (of one length).
#[inline(always)]
fn axpy<T: Scalar>(y: &mut [T], a: T, x: &[T]) {
    for (y, &x) in y.iter_mut().zip(x) {
        *y = madd(a, x, *y);
    }
}

/// The six component rows `x[k w..(k + 1) w]`, each cut to `[lo, hi)`.
#[inline(always)]
fn rows6_mut<T>(x: &mut [T], w: usize, lo: usize, hi: usize) -> [&mut [T]; 6] {
    let (r0, x) = x.split_at_mut(w);
    let (r1, x) = x.split_at_mut(w);
    let (r2, x) = x.split_at_mut(w);
    let (r3, x) = x.split_at_mut(w);
    let (r4, x) = x.split_at_mut(w);
    let r5 = &mut x[..w];
    // built entry by entry (`[..].map` was an out-of-line call)
    [
        &mut r0[lo..hi],
        &mut r1[lo..hi],
        &mut r2[lo..hi],
        &mut r3[lo..hi],
        &mut r4[lo..hi],
        &mut r5[lo..hi],
    ]
}

/// [`rows6_mut`] for reading.
#[inline(always)]
fn rows6<T>(x: &[T], w: usize, lo: usize, hi: usize) -> [&[T]; 6] {
    let (r0, x) = x.split_at(w);
    let (r1, x) = x.split_at(w);
    let (r2, x) = x.split_at(w);
    let (r3, x) = x.split_at(w);
    let (r4, x) = x.split_at(w);
    let r5 = &x[..w];
    [
        &r0[lo..hi],
        &r1[lo..hi],
        &r2[lo..hi],
        &r3[lo..hi],
        &r4[lo..hi],
        &r5[lo..hi],
    ]
}

/// `a += b` on 6x6 matrices (inlined: nalgebra's `+=` was an out-of-line call).
#[inline(always)]
fn add6<T: Scalar>(a: &mut Matrix6<T>, b: &Matrix6<T>) {
    for (x, &y) in a.as_mut_slice().iter_mut().zip(b.as_slice()) {
        *x += y;
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
        deriv_oy: oy,
        deriv_hm: hmom,
        ..
    } = data;
    let qdd = qdd.as_mut_slice();
    // Row r of H⁻¹'s upper triangle (columns c ≥ r) is kept as column r of `m`
    // from row r down (contiguous): `m[c + r n] = H⁻¹[r, c]`; mirrored at the end.
    let m = minv.as_mut_slice();

    // Sweep 1, root outwards: ⁰Mᵢ, J = ⁰X̂ᵢ S, ⁰v̂ᵢ, the velocity-product
    // acceleration cᵢ = ⁰v̂_λ × ⁰v̂ᵢ, Yᵢ as Iᴬᵢ and the bias force pᴬᵢ.
    ov[0] = Motion::zero();
    for i in 1..nb {
        let p = parent[i];
        let ovp = ov[p];
        let (ovi, om) = dispatch_joint!(&joints[i], ident[i], jm => {
            let li = jm.placement(&placements[i], q);
            let om = jm.world_pose(&o_m_i[p], &li);
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
            (ovp + vj, om)
        });
        ov[i] = ovi;
        // cᵢ = ⁰v̂_λ × ⁰v̂ᵢ (= ⁰v̂ᵢ × J q̇)
        agf[i] = ovp.cross(&ovi);
        // Iᴬᵢ = Yᵢ = ⁰X̂*ᵢ Îᵢ ⁱX̂₀, pᴬᵢ = ⁰v̂ᵢ ×* Yᵢ ⁰v̂ᵢ − f̂ᵢˣ
        let y = inertias[i].act(&om);
        matrix6(&y, &mut ia[i]);
        let hm = y.mul_motion(&ovi);
        // Yᵢ and ⁰v̂ᵢ's momentum left for the derivative sweep that follows
        // (`rnea_derivatives_pass_after_minv`)
        oy[i] = y;
        hmom[i] = hm;
        let mut pi = ovi.cross_force(&hm);
        if let Some(fx) = fext {
            pi -= fx[i];
        }
        of[i] = pi;
    }

    // Sweep 2, leaves inwards: uᵢ = τᵢ − Jᵀ pᴬᵢ, U = Iᴬ J, D = Jᵀ U; the rows of
    // H⁻¹ against the subtree, H⁻¹[i, i] = D⁻¹, H⁻¹[i, sub] = −D⁻¹ Jᵀ F[sub]; the
    // columns' forces F[sub] += U H⁻¹[i, sub] and Iᵃ, pᵃ passed to the parent.
    // F is kept by components (`fs[k nv + c]`: the loops over columns vectorise).
    let fs = &mut fcol[..6 * nv];
    for i in (1..nb).rev() {
        let p = parent[i];
        let jt = &joints[i];
        let (c0, ni) = (jt.iv, jt.nv());
        let (ce, end) = (c0 + ni, sub_end[i]);
        let fi = of[i];
        // Iᴬᵢ in place (not needed after), the parent's before it (p < i)
        let (ia_lo, ia_hi) = ia.split_at_mut(i);
        let iai = &mut ia_hi[0];
        // the columns after the subtree start at zero (sweep 3 subtracts from them)
        for r in c0..ce {
            m[r * nv + end..(r + 1) * nv].fill(T::zero());
        }
        if ni == 1 {
            let s = jcol[c0];
            let ui = tau[c0] - s.dot(&fi);
            uq[c0] = ui;
            let uvec = &*iai * mv(&s);
            let d = s.dot(&fv(&uvec));
            if d.partial_cmp(&T::zero()) != Some(std::cmp::Ordering::Greater) || !d.is_finite() {
                return Err(DynamicsError::Singular(c0));
            }
            let dinv = T::one() / d;
            let udvec = uvec * dinv;
            udinv[c0] = fv(&udvec);
            let sv = mv(&s);
            let col = &mut m[c0 * nv..(c0 + 1) * nv];
            col[c0] = dinv;
            let sub = &mut col[ce..end];
            if p != 0 {
                // own column: F = U D⁻¹
                for k in 0..6 {
                    fs[k * nv + c0] = udvec[k];
                }
            }
            let [f0, f1, f2, f3, f4, f5] = rows6_mut(fs, nv, ce, end);
            let len = sub.len();
            let (f0, f1, f2, f3, f4, f5) = (
                &mut f0[..len],
                &mut f1[..len],
                &mut f2[..len],
                &mut f3[..len],
                &mut f4[..len],
                &mut f5[..len],
            );
            let nd = -dinv;
            for j in 0..len {
                // H⁻¹[i, c] = −D⁻¹ Jᵀ F_c
                let y = madd(
                    sv[5],
                    f5[j],
                    madd(
                        sv[4],
                        f4[j],
                        madd(
                            sv[3],
                            f3[j],
                            madd(sv[2], f2[j], madd(sv[1], f1[j], sv[0] * f0[j])),
                        ),
                    ),
                );
                let x = nd * y;
                sub[j] = x;
                if p != 0 {
                    // F_c += U H⁻¹[i, c]
                    f0[j] = madd(uvec[0], x, f0[j]);
                    f1[j] = madd(uvec[1], x, f1[j]);
                    f2[j] = madd(uvec[2], x, f2[j]);
                    f3[j] = madd(uvec[3], x, f3[j]);
                    f4[j] = madd(uvec[4], x, f4[j]);
                    f5[j] = madd(uvec[5], x, f5[j]);
                }
            }
            if p != 0 {
                // Iᵃ = Iᴬ − U D⁻¹ Uᵀ, pᵃ = pᴬ + Iᵃ c + U D⁻¹ u
                for cc in 0..6 {
                    for r in 0..6 {
                        iai[(r, cc)] = madd(-udvec[r], uvec[cc], iai[(r, cc)]);
                    }
                }
                let pa = fi + fv(&(&*iai * mv(&agf[i]) + udvec * ui));
                add6(&mut ia_lo[p], iai);
                of[p] += pa;
            }
        } else {
            // a joint of 3 or 6 coordinates: J, U = Iᴬ J and D = Jᵀ U as 6x6 blocks
            // (zero columns past the joint's)
            let mut jm = Matrix6::<T>::zeros();
            for r in 0..ni {
                jm.set_column(r, &mv(&jcol[c0 + r]));
                uq[c0 + r] = tau[c0 + r] - jcol[c0 + r].dot(&fi);
            }
            let u = &*iai * jm;
            let mut d = jm.transpose() * u;
            // fewer than 6 coordinates (spherical, planar): the unused block is 1
            for r in ni..6 {
                d[(r, r)] = T::one();
            }
            let dinv = super::linalg::spd6_inverse(&d).ok_or(DynamicsError::Singular(c0))?;
            let ud = u * dinv;
            for r in 0..ni {
                udinv[c0 + r] = fv(&ud.column(r).into_owned());
                for s in 0..ni {
                    m[c0 + s + (c0 + r) * nv] = dinv[(r, s)];
                }
            }
            // H⁻¹[i, c] = −D⁻¹ Jᵀ F_c over the strict subtree: y = Jᵀ F into the
            // rows, then x = −D⁻¹ y column by column
            for r in 0..ni {
                let row = &mut m[(c0 + r) * nv + ce..(c0 + r) * nv + end];
                row.fill(T::zero());
                for k in 0..6 {
                    axpy(row, jm[(k, r)], &fs[k * nv + ce..k * nv + end]);
                }
            }
            for c in ce..end {
                let y = Vector6::from_fn(|r, _| {
                    if r < ni {
                        m[c + (c0 + r) * nv]
                    } else {
                        T::zero()
                    }
                });
                let x = -(dinv * y);
                for r in 0..ni {
                    m[c + (c0 + r) * nv] = x[r];
                }
            }
            if p != 0 {
                // F_c += U H⁻¹[i, c] (own columns: F_c = U D⁻¹)
                for k in 0..6 {
                    for s in 0..ni {
                        fs[k * nv + c0 + s] = ud[(k, s)];
                    }
                    for r in 0..ni {
                        let (fk, row) = (k * nv, (c0 + r) * nv);
                        let x = &m[row + ce..row + end];
                        axpy(&mut fs[fk + ce..fk + end], u[(k, r)], x);
                    }
                }
                let uvec = Vector6::from_fn(|r, _| if r < ni { uq[c0 + r] } else { T::zero() });
                *iai -= ud * u.transpose();
                let pa = fi + fv(&(&*iai * mv(&agf[i]) + ud * uvec));
                add6(&mut ia_lo[p], iai);
                of[p] += pa;
            }
        }
    }

    // Sweep 3, root outwards from â₀ = [0; −g]: a' = â_λ + cᵢ,
    // q̈ᵢ = D⁻¹ uᵢ − (U D⁻¹)ᵀ a', âᵢ = a' + J q̈ᵢ; the rows of H⁻¹ against every
    // later column, H⁻¹[i, c] −= (U D⁻¹)ᵀ A_λ[c], and the columns' accelerations
    // Aᵢ[c] = A_λ[c] + J H⁻¹[i, c] (c ≥ i), by components: body i's at
    // `acol[off_i + k nv + c]` (a buffer its children read, see `Data::minv_acol`).
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
        if p == 0 && leaf {
            continue;
        }
        let w = nv - c0;
        // A_λ's components from column c0 on (none at the root), and this body's
        let sz = 6 * nv;
        let (ap_buf, out): (&[T], &mut [T]) = if p != 0 {
            let (r, o) = (acol_off[p], acol_off[i]);
            if r < o {
                let (lo, hi) = acol.split_at_mut(o);
                (&lo[r..r + sz], &mut hi[..sz])
            } else {
                let (lo, hi) = acol.split_at_mut(r);
                (&hi[..sz], &mut lo[o..o + sz])
            }
        } else {
            (&[], &mut acol[acol_off[i]..acol_off[i] + sz])
        };
        let ap: [&[T]; 6] = if p != 0 {
            rows6(ap_buf, nv, c0, nv)
        } else {
            [&[]; 6]
        };
        if ni == 1 && p != 0 && !leaf {
            let (ud, sv) = (ff(&udinv[c0]), mv(&jcol[c0]));
            let row = &mut m[c0 * nv + c0..(c0 + 1) * nv];
            let [o0, o1, o2, o3, o4, o5] = rows6_mut(out, nv, c0, nv);
            let [a0, a1, a2, a3, a4, a5] = ap;
            let row = &mut row[..w];
            let (o0, o1, o2, o3, o4, o5) = (
                &mut o0[..w],
                &mut o1[..w],
                &mut o2[..w],
                &mut o3[..w],
                &mut o4[..w],
                &mut o5[..w],
            );
            let (a0, a1, a2, a3, a4, a5) =
                (&a0[..w], &a1[..w], &a2[..w], &a3[..w], &a4[..w], &a5[..w]);
            for j in 0..w {
                // H⁻¹[i, c] −= (U D⁻¹)ᵀ A_λ[c], Aᵢ[c] = A_λ[c] + J H⁻¹[i, c]
                let y = madd(
                    ud[5],
                    a5[j],
                    madd(
                        ud[4],
                        a4[j],
                        madd(
                            ud[3],
                            a3[j],
                            madd(ud[2], a2[j], madd(ud[1], a1[j], ud[0] * a0[j])),
                        ),
                    ),
                );
                let x = row[j] - y;
                row[j] = x;
                o0[j] = madd(sv[0], x, a0[j]);
                o1[j] = madd(sv[1], x, a1[j]);
                o2[j] = madd(sv[2], x, a2[j]);
                o3[j] = madd(sv[3], x, a3[j]);
                o4[j] = madd(sv[4], x, a4[j]);
                o5[j] = madd(sv[5], x, a5[j]);
            }
        } else {
            // general joints, the root, the leaves: component sweeps
            if p != 0 {
                for r in 0..ni {
                    let ud = ff(&udinv[c0 + r]);
                    let row = &mut m[(c0 + r) * nv + c0..(c0 + r + 1) * nv];
                    for k in 0..6 {
                        axpy(row, -ud[k], ap[k]);
                    }
                }
            }
            if !leaf {
                for k in 0..6 {
                    let ok = &mut out[k * nv + c0..(k + 1) * nv];
                    if p != 0 {
                        ok.copy_from_slice(ap[k]);
                    } else {
                        ok.fill(T::zero());
                    }
                    for r in 0..ni {
                        let row = &m[(c0 + r) * nv + c0..(c0 + r + 1) * nv];
                        axpy(ok, mv(&jcol[c0 + r])[k], row);
                    }
                }
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
