use super::kinematics::frame_pose;
use super::DynamicsError;
use crate::model::{Data, DimensionError, FrameId, Model};
use crate::spatial::{Force, Scalar};
use nalgebra::Vector3;

/// Adds an external wrench on a URDF link to the per-body array `fext` that
/// [`super::rnea`], [`super::bias`] and forward dynamics take (docs/theory.md
/// §"External forces"): `force` acts at the link frame's origin p and `torque` is
/// a pure couple, both in world coordinates, so the body receives `[τ + p × f; f]`
/// at the world origin. A link merged into a body by fixed joints adds to that
/// body; a link welded to the world adds to entry 0, which the algorithms ignore.
/// Reads `data.o_m_i` (forward kinematics at the state's q first); `fext` must
/// have `nbodies` entries.
pub fn add_link_wrench<T: Scalar>(
    model: &Model<T>,
    data: &Data<T>,
    frame: FrameId,
    force: &Vector3<T>,
    torque: &Vector3<T>,
    fext: &mut [Force<T>],
) -> Result<(), DynamicsError> {
    DimensionError::check("fext", model.nbodies, fext.len())?;
    let (body, o_m_f) = frame_pose(model, data, frame)?;
    let mut f = Force::at_point(*force, &o_m_f.trans);
    f.ang += torque;
    fext[body] += f;
    Ok(())
}
