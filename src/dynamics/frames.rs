use super::kinematics::frame_pose;
use super::{check_sizes, DynamicsError, Reference};
use crate::model::{Data, FrameId, Model};
use crate::spatial::{Motion, Scalar, Se3};
use nalgebra::DVector;

/// Forward kinematics to second order (Pinocchio's `forwardKinematics(q, v, a)`):
/// `data.li_m_i`, `data.o_m_i`, each body's spatial velocity in `data.v` and its
/// spatial acceleration without gravity in `data.a` (body frames; docs/theory.md
/// §"Velocity recursion", §"Acceleration recursion"). What [`frame_velocity`],
/// [`frame_classical_acceleration`] and the centre of mass's velocity read.
pub fn forward_kinematics_second_order<T: Scalar>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &DVector<T>,
    v: &DVector<T>,
    a: &DVector<T>,
) -> Result<(), DynamicsError> {
    check_sizes(model, q, &[("v", v), ("a", a)], None)?;
    data.v[0] = Motion::zero();
    data.a[0] = Motion::zero();
    for i in 1..model.nbodies {
        let p = model.parent[i];
        let joint = &model.joints[i];
        let (x_j, v_j) = joint.calc(q, Some(v));
        let li = model.placements[i].compose(&x_j);
        data.li_m_i[i] = li;
        data.o_m_i[i] = data.o_m_i[p].compose(&li);
        let vi = li.inv_act_motion(&data.v[p]) + v_j;
        // âᵢ = ᵢX̂ₚ âₚ + v̂ᵢ × ŝᵢ q̇ᵢ + ŝᵢ q̈ᵢ
        let mut ai = li.inv_act_motion(&data.a[p]) + vi.cross(&v_j);
        joint.add_motion(&mut ai, a);
        data.a[i] = ai;
        data.v[i] = vi;
    }
    Ok(())
}

/// The spatial velocity of a link frame, `[ω; v]` of its origin (`Motion::ang`,
/// `Motion::lin`), in world axes or the frame's own (docs/theory.md §"Frame
/// Jacobian": it is `J v`). Reads `data.o_m_i` and `data.v`
/// ([`forward_kinematics_second_order`] first).
pub fn frame_velocity<T: Scalar>(
    model: &Model<T>,
    data: &Data<T>,
    frame: FrameId,
    reference: Reference,
) -> Result<Motion<T>, DynamicsError> {
    in_frame(model, data, frame, reference, |f_x_i, body| {
        f_x_i.inv_act_motion(&data.v[body])
    })
}

/// The classical acceleration of a link frame (docs/theory.md §"Classical
/// acceleration"): `lin` the second time derivative of its origin's world position,
/// `ang` the derivative of its angular velocity, in world axes or the frame's own
/// (Pinocchio's `getFrameClassicalAcceleration`). From the spatial acceleration
/// `[α; a]` and velocity `[ω; v]` in the frame: `[α; a + ω × v]`. Reads
/// `data.o_m_i`, `data.v`, `data.a` ([`forward_kinematics_second_order`] first).
pub fn frame_classical_acceleration<T: Scalar>(
    model: &Model<T>,
    data: &Data<T>,
    frame: FrameId,
    reference: Reference,
) -> Result<Motion<T>, DynamicsError> {
    in_frame(model, data, frame, reference, |f_x_i, body| {
        let v = f_x_i.inv_act_motion(&data.v[body]);
        let mut acc = f_x_i.inv_act_motion(&data.a[body]);
        acc.lin += v.ang.cross(&v.lin);
        acc
    })
}

/// A motion of a link frame: `local(ⁱM_f, body)` gives it in the frame's axes,
/// re-expressed in world axes when asked.
fn in_frame<T: Scalar>(
    model: &Model<T>,
    data: &Data<T>,
    frame: FrameId,
    reference: Reference,
    local: impl FnOnce(&Se3<T>, usize) -> Motion<T>,
) -> Result<Motion<T>, DynamicsError> {
    let (body, o_m_f) = frame_pose(model, data, frame)?;
    let m = local(&model.frames[frame.0].placement, body);
    Ok(express(m, &o_m_f.rot, reference))
}

/// A motion given in a frame's axes, re-expressed in world axes when asked.
fn express<T: Scalar>(m: Motion<T>, rot: &nalgebra::Matrix3<T>, reference: Reference) -> Motion<T> {
    match reference {
        Reference::Local => m,
        Reference::WorldAligned => Motion::new(rot * m.ang, rot * m.lin),
    }
}
