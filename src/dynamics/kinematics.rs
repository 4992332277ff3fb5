use crate::model::{dispatch_joint, Data, FrameId, JointModel, Model, NameError};
use crate::spatial::{Scalar, Se3};
use nalgebra::DVector;

/// Forward kinematics of every body: `liMi = X_tree,i · X_J(q_i)` and
/// `oMi = oM_λ(i) · liMi`.
/// `q` must have nq entries (else the error, nothing computed).
pub fn forward_kinematics<T: Scalar>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &DVector<T>,
) -> Result<(), super::DynamicsError> {
    super::check_sizes(model, q, &[], None)?;
    forward_kinematics_pass(model, data, q);
    Ok(())
}

/// [`forward_kinematics`] for callers whose `q` has nq entries by construction
/// (the simulation's own state).
pub(crate) fn forward_kinematics_pass<T: Scalar>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &DVector<T>,
) {
    let nb = model.nbodies;
    let q = q.as_slice();
    let joints = &model.joints[..nb];
    let parent = &model.parent[..nb];
    let placements = &model.placements[..nb];
    let ident = &model.placement_identity[..nb];
    let li_m_i = &mut data.li_m_i[..nb];
    let o_m_i = &mut data.o_m_i[..nb];
    for i in 1..nb {
        let op = o_m_i[parent[i]];
        // The joint kind matched once per body (dispatch_joint!).
        let (li, om) = dispatch_joint!(&joints[i], ident[i], jm => {
            let li = jm.placement(&placements[i], q);
            let om = jm.world_pose(&op, &li);
            (li, om)
        });
        li_m_i[i] = li;
        o_m_i[i] = om;
    }
}

/// The world pose of every URDF link frame, `oMf = oMi · iMf`, from `data.o_m_i`
/// (call [`forward_kinematics`] first).
pub fn update_frames<T: Scalar>(model: &Model<T>, data: &mut Data<T>) {
    for (k, f) in model.frames.iter().enumerate() {
        // Most link frames are their body's frame (identity placement): copy.
        data.o_m_f[k] = if f.placement == Se3::identity() {
            data.o_m_i[f.body]
        } else {
            data.o_m_i[f.body].compose(&f.placement)
        };
    }
}

/// The world pose `⁰M_f = ⁰Mᵢ ⁱM_f` of one URDF link frame, from `data.o_m_i` (call
/// [`forward_kinematics`] first); an id the model does not have is an error.
pub fn frame_placement<T: Scalar>(
    model: &Model<T>,
    data: &Data<T>,
    frame: FrameId,
) -> Result<Se3<T>, super::DynamicsError> {
    frame_pose(model, data, frame).map(|(_, m)| m)
}

/// The body of a link frame and its world pose `⁰M_f` from `data.o_m_i`, or the
/// error for an id the model does not have.
pub(crate) fn frame_pose<T: Scalar>(
    model: &Model<T>,
    data: &Data<T>,
    frame: FrameId,
) -> Result<(usize, Se3<T>), super::DynamicsError> {
    let f = model.frames.get(frame.0).ok_or(NameError::OutOfRange {
        kind: "frame",
        id: frame.0,
        len: model.frames.len(),
    })?;
    Ok((f.body, data.o_m_i[f.body].compose(&f.placement)))
}
