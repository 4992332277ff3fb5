//! States between MuJoCo and urdyn (mjcf.md §"What the file becomes"): the same
//! coordinates in the same order, except that a free joint's quaternion is
//! w-first in MuJoCo (`[x y z qw qx qy qz]`) and `[x y z qx qy qz qw]` in urdyn,
//! and its linear velocity is world-frame in MuJoCo's qvel, body-frame in urdyn's
//! v (v_lin = Rᵀ qvel_lin, R the body's orientation; the angular part is
//! body-frame in both). A ball joint swaps its quaternion the same way and keeps
//! its velocity (body-frame angular in both).

use crate::model::{DimensionError, JointKind, Model};
use nalgebra::{DVector, Quaternion, UnitQuaternion, Vector3};

/// Where each free joint's coordinates start: `(iq, iv)`.
fn free_joints(model: &Model) -> impl Iterator<Item = (usize, usize)> + '_ {
    model.joints[1..]
        .iter()
        .filter(|j| matches!(j.kind, JointKind::Free))
        .map(|j| (j.iq, j.iv))
}

/// Where each quaternion starts in q: a free joint's at `iq + 3`, a ball joint's at `iq`.
fn quaternions(model: &Model) -> impl Iterator<Item = usize> + '_ {
    model.joints[1..].iter().filter_map(|j| match j.kind {
        JointKind::Free => Some(j.iq + 3),
        JointKind::Spherical => Some(j.iq),
        _ => None,
    })
}

/// The rotation of a w-first quaternion at `q[at..at + 4]` (normalised).
fn rot_wxyz(q: &[f64]) -> UnitQuaternion<f64> {
    UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3]))
}

/// urdyn's q from MuJoCo's qpos.
pub fn from_mujoco_qpos(
    model: &Model,
    qpos: &DVector<f64>,
) -> Result<DVector<f64>, DimensionError> {
    DimensionError::check("qpos", model.nq, qpos.len())?;
    let mut q = qpos.clone();
    for at in quaternions(model) {
        for k in 0..3 {
            q[at + k] = qpos[at + 1 + k];
        }
        q[at + 3] = qpos[at];
    }
    Ok(q)
}

/// MuJoCo's qpos from urdyn's q.
pub fn to_mujoco_qpos(model: &Model, q: &DVector<f64>) -> Result<DVector<f64>, DimensionError> {
    DimensionError::check("q", model.nq, q.len())?;
    let mut qpos = q.clone();
    for at in quaternions(model) {
        qpos[at] = q[at + 3];
        for k in 0..3 {
            qpos[at + 1 + k] = q[at + k];
        }
    }
    Ok(qpos)
}

/// urdyn's v from MuJoCo's qpos and qvel.
pub fn from_mujoco_qvel(
    model: &Model,
    qpos: &DVector<f64>,
    qvel: &DVector<f64>,
) -> Result<DVector<f64>, DimensionError> {
    DimensionError::check("qpos", model.nq, qpos.len())?;
    DimensionError::check("qvel", model.nv, qvel.len())?;
    let mut v = qvel.clone();
    for (iq, iv) in free_joints(model) {
        let r = rot_wxyz(&qpos.as_slice()[iq + 3..iq + 7]);
        let lin = r.inverse() * Vector3::new(qvel[iv], qvel[iv + 1], qvel[iv + 2]);
        v.fixed_rows_mut::<3>(iv).copy_from(&lin);
    }
    Ok(v)
}

/// MuJoCo's qvel from urdyn's q and v.
pub fn to_mujoco_qvel(
    model: &Model,
    q: &DVector<f64>,
    v: &DVector<f64>,
) -> Result<DVector<f64>, DimensionError> {
    DimensionError::check("q", model.nq, q.len())?;
    DimensionError::check("v", model.nv, v.len())?;
    let mut qvel = v.clone();
    for (iq, iv) in free_joints(model) {
        let r = UnitQuaternion::from_quaternion(Quaternion::new(
            q[iq + 6],
            q[iq + 3],
            q[iq + 4],
            q[iq + 5],
        ));
        let lin = r * Vector3::new(v[iv], v[iv + 1], v[iv + 2]);
        qvel.fixed_rows_mut::<3>(iv).copy_from(&lin);
    }
    Ok(qvel)
}
