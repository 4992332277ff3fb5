//! Rotor inertia (armature) per velocity coordinate: the diagonal A that MuJoCo's
//! `qM` and Pinocchio's `armature` add to H (an MJCF joint's `armature`; 0 for a
//! URDF, whose `--armature` is a simulation option).

use super::Model;
use nalgebra::DVector;

impl Model<f64> {
    /// A (nv): each joint's armature on each of its velocity coordinates (MuJoCo's
    /// `dof_armature`), 0 for a free base; `None` when every entry is 0 (H is then
    /// the rigid bodies' alone).
    pub fn armature(&self) -> Option<DVector<f64>> {
        if self.dofs.iter().all(|d| d.armature == 0.0) {
            return None;
        }
        let mut a = DVector::zeros(self.nv);
        for d in &self.dofs {
            for k in 0..d.kind.nv() {
                a[d.iv + k] = d.armature;
            }
        }
        Some(a)
    }
}
