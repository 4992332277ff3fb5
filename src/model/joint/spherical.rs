//! The spherical (ball) joint: q = unit quaternion `[qx, qy, qz, qw]` of the child
//! frame in the joint frame, v = ω in the child frame, `S = [1₃; 0]`, as
//! Pinocchio's `JointModelSpherical` (docs/theory.md §"Spherical, planar and
//! floating joints").

use super::{Joint, JointModel};
use crate::spatial::{quat_to_matrix, Axis, CompositeInertia, Force, Motion, Scalar, Se3};
use nalgebra::{Matrix6, Vector3, Vector6};

/// The 3-DoF spherical joint.
#[derive(Clone, Copy)]
pub(crate) struct SphericalJ<'j, T: Scalar> {
    pub j: &'j Joint<T>,
}

impl<'j, T: Scalar> SphericalJ<'j, T> {
    /// `S x`: the angular velocity `x[iv..iv + 3]`.
    #[inline(always)]
    fn motion(&self, x: &[T]) -> Motion<T> {
        let x = &x[self.j.iv..self.j.iv + 3];
        Motion::new(Vector3::new(x[0], x[1], x[2]), Vector3::zeros())
    }
}

impl<'j, T: Scalar> JointModel<T> for SphericalJ<'j, T> {
    const NV: usize = 3;
    #[inline(always)]
    fn rot_axis(&self) -> Option<Axis<T>> {
        None
    }
    #[inline(always)]
    fn placement(&self, xt: &Se3<T>, q: &[T]) -> Se3<T> {
        let q = &q[self.j.iq..self.j.iq + 4];
        Se3::new(xt.rot * quat_to_matrix(q[0], q[1], q[2], q[3]), xt.trans)
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
        for (t, x) in tau[self.j.iv..self.j.iv + 3].iter_mut().zip(f.ang.iter()) {
            *t += *x;
        }
    }
    #[inline(always)]
    fn project_column(&self, c: usize, f: &Force<T>) -> T {
        f.ang[c]
    }
    #[inline(always)]
    fn subspace(&self, c: usize) -> Motion<T> {
        let mut m = Motion::zero();
        m.ang[c] = T::one();
        m
    }
    #[inline(always)]
    fn subspace_in(&self, c: usize, m: &Se3<T>) -> Motion<T> {
        let w: Vector3<T> = m.rot.column(c).into();
        Motion::new(w, m.trans.cross(&w))
    }
    #[inline(always)]
    fn mul_subspace(&self, ic: &CompositeInertia<T>, c: usize) -> Force<T> {
        // column c of the origin-form inertia's angular block [I_o; −h×]
        let ax = [Axis::X, Axis::Y, Axis::Z][c];
        Force::new(ic.io.column(c).into(), -ax.cross_from(&ic.h))
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
