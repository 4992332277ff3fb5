//! The 3-vector and 3x3 kernels every spatial operation is made of, written as
//! chains of multiply-adds `a·b + c` ([`madd`]).
//!
//! Why not nalgebra's operators: rustc never contracts `a * b + c` into one
//! fused multiply-add (it would change the rounding), while g++ does by default
//! wherever the target has FMA (Pinocchio's `-march=native` build). With
//! [`madd`], a build for an FMA target (`-C target-cpu=native` on any x86-64 of
//! the last decade, or `-C target-feature=+fma`) fuses every product into its sum
//! — one instruction and one rounding instead of two — and any other build
//! computes exactly `a * b + c`, as before. The order of the terms is that of
//! nalgebra's products (`m v = m₀ v₀ + m₁ v₁ + m₂ v₂`, accumulated left to right).

use super::Scalar;
use nalgebra::{Matrix3, Vector3};

/// `a·b + c`: fused (one rounding) for `f64` when the build targets FMA hardware,
/// `a * b + c` otherwise. The choice is made at compile time.
#[inline(always)]
pub fn madd<T: Scalar>(a: T, b: T, c: T) -> T {
    #[cfg(target_feature = "fma")]
    {
        use std::any::Any;
        if let (Some(&a), Some(&b), Some(&c)) = (
            (&a as &dyn Any).downcast_ref::<f64>(),
            (&b as &dyn Any).downcast_ref::<f64>(),
            (&c as &dyn Any).downcast_ref::<f64>(),
        ) {
            let mut out = T::zero();
            if let Some(o) = (&mut out as &mut dyn Any).downcast_mut::<f64>() {
                *o = a.mul_add(b, c);
                return out;
            }
        }
    }
    a * b + c
}

/// `a·b − c·d` (a 2x2 determinant; the cross product's components).
#[inline(always)]
pub fn msub2<T: Scalar>(a: T, b: T, c: T, d: T) -> T {
    madd(a, b, -(c * d))
}

/// `a₀b₀ + a₁b₁ + a₂b₂`.
#[inline(always)]
pub fn dot3<T: Scalar>(a0: T, a1: T, a2: T, b0: T, b1: T, b2: T) -> T {
    madd(a2, b2, madd(a1, b1, a0 * b0))
}

/// `a · b`.
#[inline(always)]
pub fn dot<T: Scalar>(a: &Vector3<T>, b: &Vector3<T>) -> T {
    dot3(a.x, a.y, a.z, b.x, b.y, b.z)
}

/// `a × b`.
#[inline(always)]
pub fn cross<T: Scalar>(a: &Vector3<T>, b: &Vector3<T>) -> Vector3<T> {
    Vector3::new(
        msub2(a.y, b.z, a.z, b.y),
        msub2(a.z, b.x, a.x, b.z),
        msub2(a.x, b.y, a.y, b.x),
    )
}

/// `c + a × b`.
#[inline(always)]
pub fn add_cross<T: Scalar>(c: &Vector3<T>, a: &Vector3<T>, b: &Vector3<T>) -> Vector3<T> {
    Vector3::new(
        madd(a.y, b.z, madd(-a.z, b.y, c.x)),
        madd(a.z, b.x, madd(-a.x, b.z, c.y)),
        madd(a.x, b.y, madd(-a.y, b.x, c.z)),
    )
}

/// `m v`.
#[inline(always)]
pub fn mat_vec<T: Scalar>(m: &Matrix3<T>, v: &Vector3<T>) -> Vector3<T> {
    Vector3::new(
        dot3(m[(0, 0)], m[(0, 1)], m[(0, 2)], v.x, v.y, v.z),
        dot3(m[(1, 0)], m[(1, 1)], m[(1, 2)], v.x, v.y, v.z),
        dot3(m[(2, 0)], m[(2, 1)], m[(2, 2)], v.x, v.y, v.z),
    )
}

/// `c + m v`.
#[inline(always)]
pub fn add_mat_vec<T: Scalar>(c: &Vector3<T>, m: &Matrix3<T>, v: &Vector3<T>) -> Vector3<T> {
    let row = |i: usize, c: T| {
        madd(
            m[(i, 2)],
            v.z,
            madd(m[(i, 1)], v.y, madd(m[(i, 0)], v.x, c)),
        )
    };
    Vector3::new(row(0, c.x), row(1, c.y), row(2, c.z))
}

/// `mᵀ v`.
#[inline(always)]
pub fn mat_tr_vec<T: Scalar>(m: &Matrix3<T>, v: &Vector3<T>) -> Vector3<T> {
    Vector3::new(
        dot3(m[(0, 0)], m[(1, 0)], m[(2, 0)], v.x, v.y, v.z),
        dot3(m[(0, 1)], m[(1, 1)], m[(2, 1)], v.x, v.y, v.z),
        dot3(m[(0, 2)], m[(1, 2)], m[(2, 2)], v.x, v.y, v.z),
    )
}

/// `a b`.
#[inline(always)]
pub fn mat_mat<T: Scalar>(a: &Matrix3<T>, b: &Matrix3<T>) -> Matrix3<T> {
    Matrix3::from_columns(&[
        mat_vec(a, &b.column(0).into()),
        mat_vec(a, &b.column(1).into()),
        mat_vec(a, &b.column(2).into()),
    ])
}

/// `aᵀ b`.
#[inline(always)]
pub fn mat_tr_mat<T: Scalar>(a: &Matrix3<T>, b: &Matrix3<T>) -> Matrix3<T> {
    Matrix3::from_columns(&[
        mat_tr_vec(a, &b.column(0).into()),
        mat_tr_vec(a, &b.column(1).into()),
        mat_tr_vec(a, &b.column(2).into()),
    ])
}

/// `x + a s` (an axpy on 3-vectors).
#[inline(always)]
pub fn axpy<T: Scalar>(x: &Vector3<T>, a: &Vector3<T>, s: T) -> Vector3<T> {
    Vector3::new(madd(a.x, s, x.x), madd(a.y, s, x.y), madd(a.z, s, x.z))
}
