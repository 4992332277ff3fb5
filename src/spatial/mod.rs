//! Spatial vector algebra in Featherstone's notation (docs/theory.md §"Notation").
//!
//! Every spatial quantity here is stored in structured form — two 3-vectors, a
//! rotation plus a translation, a mass plus a centre of mass plus a 3x3 inertia —
//! never as a 6x6 matrix in hot code. The 6x6 forms exist (`to_matrix`) for tests
//! and for readers who want to check a formula against docs/theory.md §"Notation".
//!
//! Ordering convention: **angular first** (as the joint axis `ŝ = [s; r×s]`;
//! docs/theory.md §"Spatial vectors"):
//! a motion vector is `[ω; v]`, a force vector is `[n; f]`. The CLI and the eval
//! JSON use Pinocchio's linear-first order for the floating base; the conversion
//! happens at that boundary only.

mod axis;
mod composite;
mod force;
mod inertia;
mod motion;
pub mod ops;
mod se3;

pub use axis::Axis;
pub(crate) use axis::{rodrigues, AxU, AxX, AxY, AxZ, AxisOf};
pub use composite::CompositeInertia;
pub use force::Force;
pub use inertia::Inertia;
pub use motion::Motion;
pub use se3::Se3;

use nalgebra::{Matrix3, RealField, Vector3};

/// The scalar type of every algorithm: any nalgebra real field that is `Copy`
/// (`f64` by default; a higher-precision type for stress tests, a dual number for
/// derivatives). Generic code is monomorphised, so `f64` pays nothing for it.
pub trait Scalar: RealField + Copy {}
impl<T: RealField + Copy> Scalar for T {}

/// `(sin x, cos x)` for a joint angle. For `f64` this is `libm::sincos` (the
/// FreeBSD msun / musl algorithm: Cody–Waite reduction by π/2 and degree-13/14
/// kernels on [−π/4, π/4], error < 1 ulp), about 35 instructions a call fewer than
/// the system libm's `sincos` on this machine (callgrind); any other scalar type
/// uses its own `sin_cos`. The choice is made at compile time (monomorphisation
/// folds the type test).
#[inline(always)]
pub fn sin_cos<T: Scalar>(x: T) -> (T, T) {
    use std::any::Any;
    if let Some(&xf) = (&x as &dyn Any).downcast_ref::<f64>() {
        let sc = libm::sincos(xf);
        let mut out = (T::zero(), T::one());
        if let Some(o) = (&mut out as &mut dyn Any).downcast_mut::<(f64, f64)>() {
            *o = sc;
            return out;
        }
    }
    x.sin_cos()
}

/// Converts an `f64` literal into the scalar type.
#[inline(always)]
pub fn lit<T: Scalar>(x: f64) -> T {
    nalgebra::convert(x)
}

/// The cross-product matrix `t*` (docs/theory.md §"Cross products"): `t* u = t × u`.
#[inline]
pub fn skew<T: Scalar>(t: &Vector3<T>) -> Matrix3<T> {
    let z = T::zero();
    Matrix3::new(z, -t.z, t.y, t.z, z, -t.x, -t.y, t.x, z)
}

/// Rotation matrix from URDF roll-pitch-yaw (fixed axes X, then Y, then Z:
/// `R = Rz(yaw) Ry(pitch) Rx(roll)`).
pub fn rpy_to_matrix<T: Scalar>(roll: T, pitch: T, yaw: T) -> Matrix3<T> {
    let (sr, cr) = roll.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    let (sy, cy) = yaw.sin_cos();
    Matrix3::new(
        cy * cp,
        cy * sp * sr - sy * cr,
        cy * sp * cr + sy * sr,
        sy * cp,
        sy * sp * sr + cy * cr,
        sy * sp * cr - cy * sr,
        -sp,
        cp * sr,
        cp * cr,
    )
}

/// Rotation matrix of a unit quaternion given as (x, y, z, w).
pub fn quat_to_matrix<T: Scalar>(x: T, y: T, z: T, w: T) -> Matrix3<T> {
    let two = lit::<T>(2.0);
    let one = T::one();
    Matrix3::new(
        one - two * (y * y + z * z),
        two * (x * y - z * w),
        two * (x * z + y * w),
        two * (x * y + z * w),
        one - two * (x * x + z * z),
        two * (y * z - x * w),
        two * (x * z - y * w),
        two * (y * z + x * w),
        one - two * (x * x + y * y),
    )
}

/// Rotation by angle `q` about a unit axis `u` (Rodrigues).
#[inline]
pub fn axis_angle<T: Scalar>(u: &Vector3<T>, q: T) -> Matrix3<T> {
    let (s, c) = sin_cos(q);
    let k = skew(u);
    Matrix3::identity() + k * s + k * k * (T::one() - c)
}
