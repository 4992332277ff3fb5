use super::kinematics::frame_pose;
use super::DynamicsError;
use crate::model::{Data, DimensionError, FrameId, Model};
use crate::spatial::Scalar;
use nalgebra::{DMatrix, Vector3};

/// The coordinates a frame quantity (Jacobian, velocity, acceleration) is given in:
/// rows 0–2 the linear velocity of the frame's origin, rows 3–5 the angular
/// velocity (docs/theory.md §"Frame Jacobian").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Reference {
    /// World axes at the frame's origin (Pinocchio's `LOCAL_WORLD_ALIGNED`; the
    /// eval contract's `jacobian`).
    #[default]
    WorldAligned,
    /// The frame's own axes at its origin (Pinocchio's `LOCAL`; the eval
    /// contract's `jacobian_local`).
    Local,
}

/// The Jacobian of a link frame: `J v` is the frame's `[linear velocity of its
/// origin; angular velocity]`, in world axes ([`Reference::WorldAligned`]) or the
/// frame's own ([`Reference::Local`]). Column k sums, over the joints on the path to
/// the root that move with coordinate k, the joint's motion subspace `ŝ`
/// (docs/theory.md §"Joints and motion subspace", §"Frame Jacobian") carried to the
/// world (`⁰X̂ⱼ ŝ`) and read at the frame's origin p: `[v₀ + ω × p; ω]`; a mimic
/// joint adds its multiplier times that to its leader's column (the reduced
/// `J_full G`). Uses `data.o_m_i` (call forward kinematics first).
/// `j` must be 6 × nv and is overwritten.
///
/// A Jacobian by link name:
/// ```
/// use urdyn::dynamics::{forward_kinematics, frame_jacobian, Reference};
/// use urdyn::nalgebra::DMatrix;
/// let model = urdyn::load_file("tests/urdf/double_pendulum.urdf", Default::default()).unwrap();
/// let mut data = urdyn::Data::new(&model);
/// let q = model.neutral();
/// forward_kinematics(&model, &mut data, &q).unwrap();
/// let tip = model.frame_id("lower").unwrap();
/// let mut j = DMatrix::zeros(6, model.nv);
/// frame_jacobian(&model, &data, tip, Reference::WorldAligned, &mut j).unwrap();
/// // a misspelt link is an error naming the nearest one
/// let err = model.frame_id("lowr").unwrap_err();
/// assert!(err.to_string().contains("(nearest: \"lower\")"));
/// ```
pub fn frame_jacobian<T: Scalar>(
    model: &Model<T>,
    data: &Data<T>,
    frame: FrameId,
    reference: Reference,
    j: &mut DMatrix<T>,
) -> Result<(), DynamicsError> {
    DimensionError::check("jacobian rows", 6, j.nrows())?;
    DimensionError::check("jacobian columns", model.nv, j.ncols())?;
    let (body, o_m_f) = frame_pose(model, data, frame)?;
    j.as_mut_slice().fill(T::zero());
    let p = o_m_f.trans;
    let rt = o_m_f.rot.transpose();
    let mut b = body;
    while b != 0 {
        let joint = &model.joints[b];
        for k in 0..joint.nv() {
            let s = data.o_m_i[b].act_motion(&joint.subspace_column(k));
            let mut lin = s.lin + s.ang.cross(&p);
            let mut ang = s.ang;
            if reference == Reference::Local {
                lin = rt * lin;
                ang = rt * ang;
            }
            let col = joint.iv + k;
            add_column(j, col, &lin, &ang);
        }
        b = model.parent[b];
    }
    Ok(())
}

fn add_column<T: Scalar>(j: &mut DMatrix<T>, col: usize, lin: &Vector3<T>, ang: &Vector3<T>) {
    for r in 0..3 {
        j[(r, col)] += lin[r];
        j[(r + 3, col)] += ang[r];
    }
}
