//! Every body's world Jacobian at once (Pinocchio's `computeJointJacobians`).

use super::{check_sizes, DynamicsError};
use crate::model::{dispatch_joint, Data, JointModel, Model};
use crate::spatial::Scalar;
use nalgebra::{DMatrix, DVector};

/// Forward kinematics and the world Jacobian of every joint, written to
/// `data.jacobians` (6 × nv, angular rows 0–2, linear rows 3–5 at the world origin,
/// Featherstone's order): column k is `⁰X̂ᵢ Sₖ`, the world spatial motion of the
/// body of coordinate k per unit of it (docs/theory.md §"Frame Jacobian"); a mimic
/// joint adds its own to its leader's column. Body i's Jacobian is the columns of
/// i's ancestors (Pinocchio's `data.J`, there linear first).
pub fn joint_jacobians<'d, T: Scalar>(
    model: &Model<T>,
    data: &'d mut Data<T>,
    q: &DVector<T>,
) -> Result<&'d DMatrix<T>, DynamicsError> {
    check_sizes(model, q, &[], None)?;
    let nb = model.nbodies;
    let qs = q.as_slice();
    if model.has_mimic {
        data.jacobians.as_mut_slice().fill(T::zero());
    }
    for i in 1..nb {
        let op = data.o_m_i[model.parent[i]];
        let (li, om) = dispatch_joint!(&model.joints[i], model.placement_identity[i], jm => {
            let li = jm.placement(&model.placements[i], qs);
            let om = jm.world_pose(&op, &li);
            let iv = jm.joint().iv;
            for c in 0..jm.nv() {
                // ⁰X̂ᵢ S
                let s = jm.subspace_in(c, &om);
                let mut col = data.jacobians.column_mut(iv + c);
                let x = [s.ang.x, s.ang.y, s.ang.z, s.lin.x, s.lin.y, s.lin.z];
                for r in 0..6 {
                    if model.has_mimic {
                        col[r] += x[r];
                    } else {
                        col[r] = x[r];
                    }
                }
            }
            (li, om)
        });
        data.li_m_i[i] = li;
        data.o_m_i[i] = om;
    }
    Ok(&data.jacobians)
}
