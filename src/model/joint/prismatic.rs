//! The prismatic joint: translation along an axis, `ŝ = [0; u]`
//! (docs/theory.md §"Joints and motion subspace").

use super::{dot6, mat6_col, Joint, JointModel};
use crate::spatial::{Axis, AxisOf, CompositeInertia, Force, Motion, Scalar, Se3};
use nalgebra::{Matrix6, Vector3, Vector6};

/// A prismatic joint along axis `A`.
#[derive(Clone, Copy)]
pub(crate) struct PrismaticJ<'j, T: Scalar, A> {
    pub ax: A,
    pub j: &'j Joint<T>,
    /// The coordinate's multiplier and offset (`q_j = mult·q + offset`): the
    /// joint's, negated for a joint on a negative coordinate axis run on the
    /// positive one (`super::dispatch_of`).
    pub mult: T,
    /// See `mult`.
    pub offset: T,
}
impl<'j, T: Scalar, A: AxisOf<T>> JointModel<T> for PrismaticJ<'j, T, A> {
    const NV: usize = 1;
    #[inline(always)]
    fn rot_axis(&self) -> Option<Axis<T>> {
        None
    }
    #[inline(always)]
    fn placement(&self, xt: &Se3<T>, q: &[T]) -> Se3<T> {
        let qj = self.mult * q[self.j.iq] + self.offset;
        Se3::new(xt.rot, xt.trans + self.ax.get().mat_mul(&xt.rot) * qj)
    }
    #[inline(always)]
    fn add_motion(&self, m: &mut Motion<T>, x: &[T]) {
        self.ax
            .get()
            .add_scaled(&mut m.lin, self.mult * x[self.j.iv]);
    }
    #[inline(always)]
    fn add_cross_motion(&self, m: &mut Motion<T>, vi: &Motion<T>, x: &[T]) {
        let s = self.mult * x[self.j.iv];
        self.ax.get().add_cross_scaled(&mut m.lin, &vi.ang, s);
    }
    #[inline(always)]
    fn project_add(&self, f: &Force<T>, tau: &mut [T]) {
        tau[self.j.iv] += self.mult * self.ax.get().dot(&f.lin);
    }
    #[inline(always)]
    fn project_column(&self, _c: usize, f: &Force<T>) -> T {
        self.mult * self.ax.get().dot(&f.lin)
    }
    #[inline(always)]
    fn subspace(&self, _c: usize) -> Motion<T> {
        Motion::new(Vector3::zeros(), self.ax.get().vector() * self.mult)
    }
    #[inline(always)]
    fn subspace_in(&self, _c: usize, m: &Se3<T>) -> Motion<T> {
        Motion::new(Vector3::zeros(), self.ax.get().mat_mul(&m.rot) * self.mult)
    }
    #[inline(always)]
    fn mul_subspace(&self, ic: &CompositeInertia<T>, _c: usize) -> Force<T> {
        let ax = self.ax.get();
        match ax {
            Axis::Unit(u) => ic.mul_motion(&Motion::new(Vector3::zeros(), u * self.mult)),
            _ => Force {
                ang: ax.cross_from(&ic.h) * self.mult,
                lin: ax.vector() * (ic.m * self.mult),
            },
        }
    }
    #[inline(always)]
    fn mat6_subspace(&self, m: &Matrix6<T>) -> Vector6<T> {
        mat6_col(m, 3, self.ax.get(), self.mult)
    }
    #[inline(always)]
    fn subspace_dot6(&self, x: &Vector6<T>) -> T {
        dot6(x, 3, self.ax.get(), self.mult)
    }
    #[inline(always)]
    fn add_subspace_scaled(&self, m: &mut Motion<T>, x: T) {
        self.ax.get().add_scaled(&mut m.lin, self.mult * x);
    }
    #[inline(always)]
    fn joint(&self) -> &Joint<T> {
        self.j
    }
}
