use crate::model::{Data, Model};
use crate::spatial::Scalar;
use nalgebra::DMatrix;

/// The Jacobian of a link frame, world-aligned at the frame's origin: `J v` is the
/// frame's `[linear velocity; angular velocity]` in world coordinates (Pinocchio's
/// `LOCAL_WORLD_ALIGNED`). Column k sums, over the joints on the path to the root
/// that move with coordinate k, the joint's motion subspace `ŝ` (docs/theory.md
/// §"Joints and motion subspace", §"Frame Jacobian")
/// carried to the world (`⁰X̂ⱼ ŝ`) and read at the frame's origin p:
/// `[v₀ + ω × p; ω]`. Uses `data.o_m_i` (call forward kinematics first);
/// `j` must be 6 × nv and is overwritten.
pub fn frame_jacobian<T: Scalar>(
    model: &Model<T>,
    data: &Data<T>,
    frame: usize,
    j: &mut DMatrix<T>,
) {
    j.fill(T::zero());
    let Some(f) = model.frames.get(frame) else {
        return;
    };
    let p = data.o_m_i[f.body].act_point(&f.placement.trans);
    let mut b = f.body;
    while b != 0 {
        let joint = &model.joints[b];
        for k in 0..joint.nv() {
            let s = data.o_m_i[b].act_motion(&joint.subspace_column(k));
            let lin = s.lin + s.ang.cross(&p);
            let col = joint.iv + k;
            for r in 0..3 {
                j[(r, col)] += lin[r];
                j[(r + 3, col)] += s.ang[r];
            }
        }
        b = model.parent[b];
    }
}
