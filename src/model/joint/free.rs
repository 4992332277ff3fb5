//! The 6-DoF free joint of a floating base: q = [p; quaternion xyzw],
//! v = [v; ω] in the body frame, as Pinocchio's free flyer (docs/theory.md
//! §"Floating base").

use super::{Joint, JointModel};
use crate::spatial::{quat_to_matrix, Axis, CompositeInertia, Force, Motion, Scalar, Se3};
use nalgebra::{Matrix6, Vector3, Vector6};

/// The 6-DoF free joint.
#[derive(Clone, Copy)]
pub(crate) struct FreeJ<'j, T: Scalar> {
    pub j: &'j Joint<T>,
}

impl<'j, T: Scalar> FreeJ<'j, T> {
    /// The joint's own pose X_J(q) = (R(quaternion), p) from its 7
    /// coordinates of `q` (`λ(i)Mi` at an identity placement).
    #[inline(always)]
    pub(crate) fn joint_pose(&self, q: &[T]) -> Se3<T> {
        let q = &q[self.j.iq..self.j.iq + 7];
        Se3::new(
            quat_to_matrix(q[3], q[4], q[5], q[6]),
            Vector3::new(q[0], q[1], q[2]),
        )
    }

    /// `S x` for the free joint's 6 coordinates of `x` (linear first in `x`).
    #[inline(always)]
    fn motion(&self, x: &[T]) -> Motion<T> {
        let x = &x[self.j.iv..self.j.iv + 6];
        Motion::new(
            Vector3::new(x[3], x[4], x[5]),
            Vector3::new(x[0], x[1], x[2]),
        )
    }
}

impl<'j, T: Scalar> JointModel<T> for FreeJ<'j, T> {
    const NV: usize = 6;
    #[inline(always)]
    fn rot_axis(&self) -> Option<Axis<T>> {
        None
    }
    #[inline(always)]
    fn placement(&self, xt: &Se3<T>, q: &[T]) -> Se3<T> {
        xt.compose(&self.joint_pose(q))
    }
    #[inline(always)]
    fn add_motion(&self, m: &mut Motion<T>, x: &[T]) {
        *m += self.motion(x);
    }
    #[inline(always)]
    fn add_cross_motion(&self, m: &mut Motion<T>, vi: &Motion<T>, x: &[T]) {
        *m += vi.cross(&self.motion(x));
    }
    #[inline(always)]
    fn project_add(&self, f: &Force<T>, tau: &mut [T]) {
        let t = &mut tau[self.j.iv..self.j.iv + 6];
        for r in 0..3 {
            t[r] += f.lin[r];
            t[3 + r] += f.ang[r];
        }
    }
    #[inline(always)]
    fn project_column(&self, c: usize, f: &Force<T>) -> T {
        // S = 1 up to the order: linear coordinates first.
        if c < 3 {
            f.lin[c]
        } else {
            f.ang[c - 3]
        }
    }
    #[inline(always)]
    fn subspace(&self, c: usize) -> Motion<T> {
        // Linear coordinates first.
        let mut m = Motion::zero();
        if c < 3 {
            m.lin[c] = T::one();
        } else {
            m.ang[c - 3] = T::one();
        }
        m
    }
    #[inline(always)]
    fn subspace_in(&self, c: usize, m: &Se3<T>) -> Motion<T> {
        if c < 3 {
            Motion::new(Vector3::zeros(), m.rot.column(c).into())
        } else {
            let w: Vector3<T> = m.rot.column(c - 3).into();
            Motion::new(w, m.trans.cross(&w))
        }
    }
    #[inline(always)]
    fn mul_subspace(&self, ic: &CompositeInertia<T>, c: usize) -> Force<T> {
        // A column of the 6x6 inertia [I_o, h*; h*ᵀ, m 1] (linear coordinates first).
        if c < 3 {
            let ax = [Axis::X, Axis::Y, Axis::Z][c];
            let mut lin = Vector3::zeros();
            lin[c] = ic.m;
            Force::new(ax.cross_from(&ic.h), lin)
        } else {
            let ax = [Axis::X, Axis::Y, Axis::Z][c - 3];
            Force::new(ic.io.column(c - 3).into(), -ax.cross_from(&ic.h))
        }
    }
    #[inline(always)]
    fn mat6_subspace(&self, _m: &Matrix6<T>) -> Vector6<T> {
        Vector6::zeros()
    }
    #[inline(always)]
    fn subspace_dot6(&self, _x: &Vector6<T>) -> T {
        T::zero()
    }
    #[inline(always)]
    fn add_subspace_scaled(&self, _m: &mut Motion<T>, _x: T) {}
    #[inline(always)]
    fn joint(&self) -> &Joint<T> {
        self.j
    }
}
