//! The planar joint: q = `[x, y, θ]`, the child frame translated by (x, y, 0) and
//! turned by θ about z in the joint frame; v = `[vx, vy, ω]` in the child frame,
//! `S = [0 0 e_z; e_x e_y 0]` (angular over linear), as Pinocchio's
//! `JointModelPlanar` (docs/theory.md §"Spherical, planar and floating joints").
//! A URDF planar joint about another `<axis>` is this joint between two fixed
//! rotations, folded into the placement and the child's frames at import.

use super::{Joint, JointModel};
use crate::spatial::{sin_cos, Axis, CompositeInertia, Force, Motion, Scalar, Se3};
use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};

/// The 3-DoF planar joint (the xy plane of the joint frame).
#[derive(Clone, Copy)]
pub(crate) struct PlanarJ<'j, T: Scalar> {
    pub j: &'j Joint<T>,
}

impl<'j, T: Scalar> PlanarJ<'j, T> {
    /// `S x` for the joint's coordinates of `x`.
    #[inline(always)]
    fn motion(&self, x: &[T]) -> Motion<T> {
        let x = &x[self.j.iv..self.j.iv + 3];
        let z = T::zero();
        Motion::new(Vector3::new(z, z, x[2]), Vector3::new(x[0], x[1], z))
    }
}

impl<'j, T: Scalar> JointModel<T> for PlanarJ<'j, T> {
    const NV: usize = 3;
    #[inline(always)]
    fn rot_axis(&self) -> Option<Axis<T>> {
        None
    }
    #[inline(always)]
    fn placement(&self, xt: &Se3<T>, q: &[T]) -> Se3<T> {
        let q = &q[self.j.iq..self.j.iq + 3];
        let (s, c) = sin_cos(q[2]);
        let (z, o) = (T::zero(), T::one());
        let rot = Matrix3::new(c, -s, z, s, c, z, z, z, o);
        Se3::new(
            xt.rot * rot,
            xt.trans + xt.rot.column(0) * q[0] + xt.rot.column(1) * q[1],
        )
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
        let t = &mut tau[self.j.iv..self.j.iv + 3];
        t[0] += f.lin.x;
        t[1] += f.lin.y;
        t[2] += f.ang.z;
    }
    #[inline(always)]
    fn project_column(&self, c: usize, f: &Force<T>) -> T {
        match c {
            0 => f.lin.x,
            1 => f.lin.y,
            _ => f.ang.z,
        }
    }
    #[inline(always)]
    fn subspace(&self, c: usize) -> Motion<T> {
        let mut m = Motion::zero();
        match c {
            0 => m.lin.x = T::one(),
            1 => m.lin.y = T::one(),
            _ => m.ang.z = T::one(),
        }
        m
    }
    #[inline(always)]
    fn subspace_in(&self, c: usize, m: &Se3<T>) -> Motion<T> {
        if c < 2 {
            Motion::new(Vector3::zeros(), m.rot.column(c).into())
        } else {
            let w: Vector3<T> = m.rot.column(2).into();
            Motion::new(w, m.trans.cross(&w))
        }
    }
    #[inline(always)]
    fn mul_subspace(&self, ic: &CompositeInertia<T>, c: usize) -> Force<T> {
        // columns of the origin-form inertia [I_o, h×; −h×, m 1]
        if c < 2 {
            let ax = [Axis::X, Axis::Y][c];
            let mut lin = Vector3::zeros();
            lin[c] = ic.m;
            Force::new(ax.cross_from(&ic.h), lin)
        } else {
            Force::new(ic.io.column(2).into(), -Axis::Z.cross_from(&ic.h))
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
    fn subspace_rows(&self) -> [usize; 3] {
        // angular-first: lin x, lin y, ang z
        [3, 4, 2]
    }
    #[inline(always)]
    fn joint(&self) -> &Joint<T> {
        self.j
    }
}
