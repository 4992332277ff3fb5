//! The articulated-body algorithm on a model whose every body is a lone free
//! body on the world (the piles' models, `Data::lone_free`), at forward
//! kinematics' placements: ABA's three sweeps in one pass over the bodies, each
//! body's articulated inertia factored once and kept (docs/theory.md
//! §"Articulated-body algorithm").
//!
//! Per body the operations of [`super::aba`]'s sweeps, in their order, so the
//! same numbers bit for bit: the body's parent is the world, whose velocity
//! (zero) is moved into the body's frame as sweep 1 moves it (the signs of
//! its zeros kept), v̂ᵢ = ᵢX̂₀ v̂₀ + ŝᵢ q̇ᵢ, cᵢ = 0 + v̂ᵢ × ŝᵢ q̇ᵢ,
//! pᴬᵢ = v̂ᵢ ×* Îᵢ v̂ᵢ; sweep 2 hands the world nothing (uᵢ = τᵢ − pᴬᵢ); sweep
//! 3 from â₀: a' = ᵢX̂₀ â₀ + cᵢ, âᵢ = Iᴬᵢ⁻¹ uᵢ, q̈ᵢ = âᵢ − a'. With no child,
//! Iᴬᵢ = Îᵢ, constant in the body's frame: its `L D Lᵀ` (the one `spd6_solve`
//! makes) is kept in `data.aba_kept` with the inertia it is of, and made
//! again only when that inertia changes (compared bit for bit).

use super::aba::{fvec, inertia_matrix};
use super::linalg::{ldl6_solve, spd6_factor};
use super::DynamicsError;
use crate::model::joint::FreeJ;
use crate::model::{Data, FdMethod, Joint, JointModel, KeptLdl6, Model};
use crate::spatial::{CompositeInertia, Force, Inertia, Motion, Se3};
use nalgebra::Vector3;

/// q̈ by [`super::aba`] (no external forces) on a model with
/// `data.lone_free`, written over `tau` (nv entries: each body's six read,
/// then its q̈ written there), reading the joint placements `data.li_m_i`
/// that forward kinematics left at this q — the caller's word (the
/// simulation's own workspace after its contact refresh); `data.v` and
/// `data.a` are written as by `aba`, its sweeps' scratch and `data.qdd` are
/// not. `None`, nothing computed, where `aba` would not run this way (another
/// model shape or forward-dynamics method, mimic or massless joints, a
/// length that does not match).
pub(crate) fn aba_lone_placed(
    model: &Model<f64>,
    data: &mut Data<f64>,
    v: &[f64],
    tau: &mut [f64],
) -> Option<Result<(), DynamicsError>> {
    let nb = model.nbodies;
    if !data.lone_free
        || model.topology.fd_method != FdMethod::Aba
        || model.has_mimic
        || !model.massless_joints.is_empty()
        || v.len() != model.nv
        || tau.len() != model.nv
        || v.len() != 6 * (nb - 1)
    {
        return None;
    }
    let (Some((joints, inertias, li_m_i, vel)), Some(inertias_o), Some(acc), Some(kept)) = (
        lone_parts(model, &data.li_m_i, &mut data.v),
        model.inertias_origin.get(..nb),
        data.a.get_mut(..nb),
        data.aba_kept.get_mut(..nb),
    ) else {
        return None;
    };
    // docs/theory.md §"Gravity": v̂₀ = 0, â₀ = [0; −g]
    let (v0, a0) = (
        Motion::zero(),
        Motion::new(Vector3::zeros(), -model.gravity),
    );
    vel[0] = v0;
    acc[0] = a0;
    for (i, t) in (1..nb).zip(tau.chunks_exact_mut(6)) {
        let jm = FreeJ { j: &joints[i] };
        let m = &li_m_i[i];
        // sweep 1, docs/theory.md §"Velocity recursion": v̂ᵢ = ᵢX̂₀ v̂₀ + ŝᵢ q̇ᵢ,
        // cᵢ = v̂ᵢ × ŝᵢ q̇ᵢ, pᴬᵢ = v̂ᵢ ×* Îᵢ v̂ᵢ
        let mut vi = m.inv_act_motion(&v0);
        jm.add_motion(&mut vi, v);
        let mut ci = Motion::zero();
        jm.add_cross_motion(&mut ci, &vi, v);
        let pi = vi.cross_force(&inertias[i].mul_motion(&vi));
        vel[i] = vi;
        // sweep 2 (a free joint on the world): uᵢ = τᵢ − pᴬᵢ
        let tf = Force::new(
            Vector3::new(t[3], t[4], t[5]),
            Vector3::new(t[0], t[1], t[2]),
        );
        let u = fvec(&(tf - pi));
        // sweep 3: a' = ᵢX̂₀ â₀ + cᵢ, âᵢ = Iᴬᵢ⁻¹ uᵢ, q̈ᵢ = âᵢ − a' (linear first)
        let a1 = m.inv_act_motion(&a0) + ci;
        let Some((l, dinv)) = kept_factor(&mut kept[i], &inertias_o[i]) else {
            return Some(Err(DynamicsError::Singular(jm.joint().iv)));
        };
        let x = ldl6_solve(|r, c| l[r * (r - 1) / 2 + c], dinv, &u);
        let ai = Motion::new(
            Vector3::new(x[0], x[1], x[2]),
            Vector3::new(x[3], x[4], x[5]),
        );
        let rel = ai - a1;
        for r in 0..3 {
            t[r] = rel.lin[r];
            t[3 + r] = rel.ang[r];
        }
        acc[i] = ai;
    }
    Some(Ok(()))
}

/// The kept `L D Lᵀ` of `Iᴬ = Î` for the origin-form inertia `io`, made
/// (and kept) when none is kept for exactly this inertia; `None` when it is
/// not positive definite.
#[inline(always)]
fn kept_factor<'k>(
    kept: &'k mut KeptLdl6,
    io: &CompositeInertia<f64>,
) -> Option<&'k ([f64; 15], [f64; 6])> {
    if !kept.of.as_ref().is_some_and(|k| same_bits(k, io)) {
        kept.of = Some(*io);
        kept.ldl = spd6_factor(&inertia_matrix(io));
    }
    kept.ldl.as_ref()
}

/// Whether two inertias are the same bit for bit (every entry's bits: −0
/// and +0 differ, a NaN equals only itself), without an early exit (fixed
/// bounds, unrolled: no iterator call a body).
#[inline(always)]
pub(crate) fn same_bits(a: &CompositeInertia<f64>, b: &CompositeInertia<f64>) -> bool {
    let eq = |x: f64, y: f64| x.to_bits() == y.to_bits();
    let (ia, ib) = (&a.io.data.0, &b.io.data.0);
    let mut same = eq(a.m, b.m);
    for k in 0..3 {
        same &= eq(a.h[k], b.h[k]);
        for r in 0..3 {
            same &= eq(ia[k][r], ib[k][r]);
        }
    }
    same
}

/// The per-body slices the pass reads (every one `model.nbodies` long): the
/// joints, the inertias, the joint placements `li_m_i` and the body
/// velocities `v` it writes; `None` where one is shorter.
#[allow(clippy::type_complexity)]
#[inline(always)]
fn lone_parts<'a>(
    model: &'a Model<f64>,
    li_m_i: &'a [Se3<f64>],
    v: &'a mut [Motion<f64>],
) -> Option<(
    &'a [Joint<f64>],
    &'a [Inertia<f64>],
    &'a [Se3<f64>],
    &'a mut [Motion<f64>],
)> {
    let nb = model.nbodies;
    Some((
        model.joints.get(..nb)?,
        model.inertias.get(..nb)?,
        li_m_i.get(..nb)?,
        v.get_mut(..nb)?,
    ))
}
