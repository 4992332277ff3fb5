//! A model's `initial` joint values (scene.md, cli.md `--initial`): a number
//! for a 1-DoF joint, mechanisms.md's array for a ball or free joint
//! (`[qx, qy, qz, qw]` / `[x, y, z, qx, qy, qz, qw]` in `q`, `[wx, wy, wz]` /
//! `[vx, vy, vz, wx, wy, wz]` in `v` and `tau`, child-frame velocities); a
//! quaternion within 1e-3 of unit norm is normalised. A free joint of an MJCF
//! model hanging from its world is given in the file's frame, as its
//! `qpos0`, and placed by the model's pose (its q is a world pose).

use super::file::InitialValue;
use super::load::Loader;
use super::SceneError;
use crate::model::{JointKind, Model};
use crate::spatial::Se3;
use nalgebra::{Quaternion, Rotation3, UnitQuaternion, Vector3};

impl Loader<'_> {
    /// The coordinates `x` gives the joint `full` (`which`: "q", "v" or
    /// "tau") of `model`, as (first index, values): `q`'s or `v`'s. A free
    /// root of an MJCF model's world (`world_pose`: the model's pose) is placed
    /// by it. `key` names the value in errors.
    pub(super) fn initial_joint(
        &self,
        key: &str,
        model: &Model,
        full: &str,
        which: &str,
        x: &InitialValue,
        world_pose: Option<&Se3<f64>>,
    ) -> Result<(usize, Vec<f64>), SceneError> {
        let Some(dof) = model.dofs.iter().find(|d| d.name == full) else {
            return Err(self.err(key, format!("unknown joint \"{full}\"")));
        };
        let kind = dof.kind;
        let n = if which == "q" { kind.nq() } else { kind.nv() };
        let layout = match (kind, which == "q") {
            (JointKind::Spherical, true) => " [qx, qy, qz, qw]",
            (JointKind::Spherical, false) => " [wx, wy, wz]",
            (JointKind::Planar, true) => " [x, y, theta]",
            (JointKind::Planar, false) => " [vx, vy, wz]",
            (JointKind::Free, true) => " [x, y, z, qx, qy, qz, qw]",
            (JointKind::Free, false) => " [vx, vy, vz, wx, wy, wz]",
            _ => "",
        };
        let mut vals = match x {
            InitialValue::Number(x) if n == 1 => vec![*x],
            InitialValue::Array(a) if n > 1 && a.len() == n => a.clone(),
            _ => {
                let found = match x {
                    InitialValue::Number(_) => "a number".to_string(),
                    InitialValue::Array(a) => format!("an array of {}", a.len()),
                };
                let takes = if n == 1 {
                    "a number".to_string()
                } else {
                    format!("an array of {n} numbers{layout}")
                };
                return Err(self.err(
                    key,
                    format!("a {} joint takes {takes}, found {found}", kind.name()),
                ));
            }
        };
        self.finite(key, &vals)?;
        let quat = match (kind, which) {
            (JointKind::Spherical, "q") => Some(0),
            (JointKind::Free, "q") => Some(3),
            _ => None,
        };
        if let Some(at) = quat {
            let o = [vals[at], vals[at + 1], vals[at + 2], vals[at + 3]];
            let o = self.quaternion(key, Some(o))?;
            vals[at..at + 4].copy_from_slice(&o);
        }
        let at = if which == "q" { dof.iq } else { dof.iv };
        // a free joint hanging from the world: its q is a world pose
        let root = (1..model.nbodies).any(|b| {
            model.parent[b] == 0
                && model.joints[b].iq == dof.iq
                && matches!(model.joints[b].kind, JointKind::Free)
        });
        if let (Some(w), true, "q") = (world_pose, root, which) {
            let r =
                UnitQuaternion::new_normalize(Quaternion::new(vals[6], vals[3], vals[4], vals[5]));
            let wr = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(w.rot));
            let t = w.rot * Vector3::new(vals[0], vals[1], vals[2]) + w.trans;
            let o = wr * r;
            vals.copy_from_slice(&[t.x, t.y, t.z, o.i, o.j, o.k, o.w]);
        }
        Ok((at, vals))
    }
}
