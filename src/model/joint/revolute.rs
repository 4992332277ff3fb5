//! The revolute joint (and the continuous one, a revolute joint without limits):
//! rotation about an axis through the joint origin, `ŝ = [u; 0]`
//! (docs/theory.md §"Joints and motion subspace").

use super::{dot6, mat6_col, Joint, JointModel};
use crate::spatial::sin_cos;
use crate::spatial::{Axis, AxisOf, CompositeInertia, Force, Motion, Scalar, Se3};
use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};

/// A revolute joint about axis `A`; `AXROT`: its placement rotation is the
/// identity (so `λ(i)Mi`'s rotation is a rotation about the axis-aligned `A`).
#[derive(Clone, Copy)]
pub(crate) struct RevoluteJ<'j, T: Scalar, A, const AXROT: bool> {
    pub ax: A,
    pub j: &'j Joint<T>,
    /// The coordinate's multiplier and offset (`q_j = mult·q + offset`): the
    /// joint's, negated for a joint on a negative coordinate axis run on the
    /// positive one (`super::dispatch_of`).
    pub mult: T,
    /// See `mult`.
    pub offset: T,
}
impl<'j, T: Scalar, A: AxisOf<T>, const AXROT: bool> JointModel<T> for RevoluteJ<'j, T, A, AXROT> {
    const NV: usize = 1;
    #[inline(always)]
    fn rot_axis(&self) -> Option<Axis<T>> {
        if AXROT {
            Some(self.ax.get())
        } else {
            None
        }
    }
    #[inline(always)]
    fn placement(&self, xt: &Se3<T>, q: &[T]) -> Se3<T> {
        let (s, c) = sin_cos(self.mult * q[self.j.iq] + self.offset);
        let ax = self.ax.get();
        if AXROT {
            let (z, o) = (T::zero(), T::one());
            let rot = match ax {
                Axis::X => Matrix3::new(o, z, z, z, c, -s, z, s, c),
                Axis::Y => Matrix3::new(c, z, s, z, o, z, -s, z, c),
                _ => Matrix3::new(c, -s, z, s, c, z, z, z, o),
            };
            Se3::new(rot, xt.trans)
        } else {
            Se3::new(ax.rotate_right(&xt.rot, s, c), xt.trans)
        }
    }
    #[inline(always)]
    fn add_motion(&self, m: &mut Motion<T>, x: &[T]) {
        self.ax
            .get()
            .add_scaled(&mut m.ang, self.mult * x[self.j.iv]);
    }
    #[inline(always)]
    fn add_cross_motion(&self, m: &mut Motion<T>, vi: &Motion<T>, x: &[T]) {
        let ax = self.ax.get();
        let s = self.mult * x[self.j.iv];
        ax.add_cross_scaled(&mut m.ang, &vi.ang, s);
        ax.add_cross_scaled(&mut m.lin, &vi.lin, s);
    }
    #[inline(always)]
    fn project_add(&self, f: &Force<T>, tau: &mut [T]) {
        tau[self.j.iv] += self.mult * self.ax.get().dot(&f.ang);
    }
    #[inline(always)]
    fn project_column(&self, _c: usize, f: &Force<T>) -> T {
        self.mult * self.ax.get().dot(&f.ang)
    }
    #[inline(always)]
    fn subspace(&self, _c: usize) -> Motion<T> {
        Motion::new(self.ax.get().vector() * self.mult, Vector3::zeros())
    }
    #[inline(always)]
    fn subspace_in(&self, _c: usize, m: &Se3<T>) -> Motion<T> {
        let w = self.ax.get().mat_mul(&m.rot) * self.mult;
        Motion::new(w, m.trans.cross(&w))
    }
    #[inline(always)]
    fn mul_subspace(&self, ic: &CompositeInertia<T>, _c: usize) -> Force<T> {
        let ax = self.ax.get();
        match ax {
            Axis::Unit(u) => ic.mul_motion(&Motion::new(u * self.mult, Vector3::zeros())),
            _ => Force {
                ang: ax.mat_mul(&ic.io) * self.mult,
                lin: ax.cross_from(&ic.h) * (-self.mult),
            },
        }
    }
    #[inline(always)]
    fn mat6_subspace(&self, m: &Matrix6<T>) -> Vector6<T> {
        mat6_col(m, 0, self.ax.get(), self.mult)
    }
    #[inline(always)]
    fn subspace_dot6(&self, x: &Vector6<T>) -> T {
        dot6(x, 0, self.ax.get(), self.mult)
    }
    #[inline(always)]
    fn add_subspace_scaled(&self, m: &mut Motion<T>, x: T) {
        self.ax.get().add_scaled(&mut m.ang, self.mult * x);
    }
    #[inline(always)]
    fn joint(&self) -> &Joint<T> {
        self.j
    }
}
