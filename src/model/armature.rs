//! Rotor inertia (armature) per velocity coordinate: the diagonal A that MuJoCo's
//! `qM` and Pinocchio's `armature` add to H (an MJCF joint's `armature`; 0 for a
//! URDF, whose `--armature` is a simulation option).

use super::Model;
use nalgebra::DVector;

impl Model<f64> {
    /// A (nv): each joint degree of freedom's armature at its v index, 0 for free
    /// joints; `None` when every entry is 0 (H is then the rigid bodies' alone).
    pub fn armature(&self) -> Option<DVector<f64>> {
        if self.dofs.iter().all(|d| d.armature == 0.0) {
            return None;
        }
        let mut a = DVector::zeros(self.nv);
        for (d, _, iv) in self.dof_indices() {
            a[iv] = self.dofs[d].armature;
        }
        Some(a)
    }
}
