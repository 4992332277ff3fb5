//! The time variation J̇ of a link frame's Jacobian (Pinocchio's
//! `getFrameJacobianTimeVariation`), docs/theory.md §"Derivatives".

use super::kinematics::frame_pose;
use super::{check_sizes, DynamicsError, Reference};
use crate::model::{dispatch_joint, Data, DimensionError, FrameId, JointModel, Model};
use crate::spatial::ops::{add_cross, cross, mat_tr_vec};
use crate::spatial::{Motion, Scalar};
use nalgebra::{DMatrix, DVector};

/// `J̇` (6 × nv) of the link frame `frame` at (q, v): the time derivative of its
/// [`super::frame_jacobian`] in `reference` along the velocity v, so that the
/// frame's classical acceleration is `J a + J̇ v` ([`Reference::WorldAligned`],
/// Pinocchio's LOCAL_WORLD_ALIGNED; [`Reference::Local`]: the derivative of the
/// local Jacobian, Pinocchio's LOCAL). Rows 0–2 linear, 3–5 angular; mimic joints
/// add to their leader's column, as in the Jacobian. Runs forward kinematics with
/// velocities (`data.o_m_i`, `data.deriv_ov` are updated); `out` must be 6 × nv.
///
/// Column k of a joint on the frame's path, with `J = ⁰X̂ S = [ω; v₀]` and `⁰v̂ᵦ`
/// the velocity of the joint's body b (world, at the origin), p the frame
/// origin and ṗ its velocity: `J̇₀ = ⁰v̂ᵦ × J`, and in world-aligned axes at p
/// `[J̇₀.v + J̇₀.ω × p + ω × ṗ; J̇₀.ω]`; in the frame's axes (rotation R, angular
/// velocity ω_f) `Rᵀ (J̇ − ω_f × J)` on each half.
pub fn frame_jacobian_time_variation<T: Scalar>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &DVector<T>,
    v: &DVector<T>,
    frame: FrameId,
    reference: Reference,
    out: &mut DMatrix<T>,
) -> Result<(), DynamicsError> {
    check_sizes(model, q, &[("v", v)], None)?;
    DimensionError::check("jacobian_dot rows", 6, out.nrows())?;
    DimensionError::check("jacobian_dot columns", model.nv, out.ncols())?;
    frame_pose(model, data, frame)?;
    let nb = model.nbodies;
    let (qs, vs) = (q.as_slice(), v.as_slice());
    // forward kinematics with world velocities: ⁰v̂ᵢ = ⁰v̂ₚ + ⁰X̂ᵢ S q̇
    data.deriv_ov[0] = Motion::zero();
    for i in 1..nb {
        let p = model.parent[i];
        let (op, ovp) = (data.o_m_i[p], data.deriv_ov[p]);
        let (li, om, ovi) = dispatch_joint!(&model.joints[i], model.placement_identity[i], jm => {
            let li = jm.placement(&model.placements[i], qs);
            let om = jm.world_pose(&op, &li);
            let iv = jm.joint().iv;
            let mut ovi = ovp;
            for c in 0..jm.nv() {
                ovi += jm.subspace_in(c, &om) * vs[iv + c];
            }
            (li, om, ovi)
        });
        data.li_m_i[i] = li;
        data.o_m_i[i] = om;
        data.deriv_ov[i] = ovi;
    }
    let (fb, o_m_f) = frame_pose(model, data, frame)?;
    let pf = o_m_f.trans;
    let vf = data.deriv_ov[fb];
    // ṗ = v₀ + ω × p, the frame origin's velocity
    let pdot = add_cross(&vf.lin, &vf.ang, &pf);
    out.as_mut_slice().fill(T::zero());
    let mut b = fb;
    while b != 0 {
        let joint = &model.joints[b];
        let ovb = data.deriv_ov[b];
        for c in 0..joint.nv() {
            let s = data.o_m_i[b].act_motion(&joint.subspace_column(c));
            // J̇₀ = ⁰v̂ᵦ × J
            let ds = ovb.cross(&s);
            // world-aligned at p: [J̇₀.v + J̇₀.ω × p + ω × ṗ; J̇₀.ω]
            let mut lin = add_cross(&add_cross(&ds.lin, &ds.ang, &pf), &s.ang, &pdot);
            let mut ang = ds.ang;
            if reference == Reference::Local {
                // Rᵀ (J̇ − ω_f × J), J = [v₀ + ω × p; ω]
                let jl = add_cross(&s.lin, &s.ang, &pf);
                lin = mat_tr_vec(&o_m_f.rot, &(lin - cross(&vf.ang, &jl)));
                ang = mat_tr_vec(&o_m_f.rot, &(ang - cross(&vf.ang, &s.ang)));
            }
            let col = joint.iv + c;
            for r in 0..3 {
                out[(r, col)] += lin[r];
                out[(r + 3, col)] += ang[r];
            }
        }
        b = model.parent[b];
    }
    Ok(())
}
