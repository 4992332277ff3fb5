//! Joint axes and the transforms specialised on them: an axis-aligned axis (most
//! URDF axes are ±x, ±y, ±z) turns a rotation about it into a mix of two rows or
//! columns, and its products with vectors into component picks
//! (docs/theory.md §"Joints and motion subspace", §"Plücker transforms").

use super::ops::{axpy, cross, madd, mat_mat, mat_tr_vec, mat_vec};
use super::{axis_angle, sin_cos, Scalar};
use nalgebra::{Matrix3, Vector3};

/// A joint axis. Axis-aligned axes (most URDF axes are ±x, ±y, ±z) get their own
/// variants so that the transform and projections are specialised.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Axis<T: Scalar = f64> {
    /// The unit x axis (1, 0, 0).
    X,
    /// The unit y axis (0, 1, 0).
    Y,
    /// The unit z axis (0, 0, 1).
    Z,
    /// Any other unit vector (negative or oblique axes).
    Unit(Vector3<T>),
}

impl<T: Scalar> Axis<T> {
    /// Classifies a unit vector.
    pub fn from_unit(u: Vector3<T>) -> Self {
        let (z, o) = (T::zero(), T::one());
        if u == Vector3::new(o, z, z) {
            Axis::X
        } else if u == Vector3::new(z, o, z) {
            Axis::Y
        } else if u == Vector3::new(z, z, o) {
            Axis::Z
        } else {
            Axis::Unit(u)
        }
    }
    /// The axis as a unit vector.
    #[inline(always)]
    pub fn vector(&self) -> Vector3<T> {
        match self {
            Axis::X => Vector3::x(),
            Axis::Y => Vector3::y(),
            Axis::Z => Vector3::z(),
            Axis::Unit(u) => *u,
        }
    }
    /// `u · x`.
    #[inline(always)]
    pub fn dot(&self, x: &Vector3<T>) -> T {
        match self {
            Axis::X => x.x,
            Axis::Y => x.y,
            Axis::Z => x.z,
            Axis::Unit(u) => u.dot(x),
        }
    }
    /// The rotation by `q` about this axis.
    #[inline(always)]
    pub fn rotation(&self, q: T) -> Matrix3<T> {
        let (s, c) = sin_cos(q);
        let (z, o) = (T::zero(), T::one());
        match self {
            Axis::X => Matrix3::new(o, z, z, z, c, -s, z, s, c),
            Axis::Y => Matrix3::new(c, z, s, z, o, z, -s, z, c),
            Axis::Z => Matrix3::new(c, -s, z, s, c, z, z, z, o),
            Axis::Unit(u) => axis_angle(u, q),
        }
    }
    /// `m · R(q)` for the rotation by `q = atan2(s, c)` about this axis, without a
    /// full 3x3 product: an axis-aligned rotation mixes two columns of `m`
    /// (12 products instead of 27).
    #[inline(always)]
    pub fn rotate_right(&self, m: &Matrix3<T>, s: T, c: T) -> Matrix3<T> {
        let (c0, c1, c2) = (m.column(0), m.column(1), m.column(2));
        match self {
            Axis::X => Matrix3::from_columns(&[c0.into(), mix(c1, c, c2, s), mix(c2, c, c1, -s)]),
            Axis::Y => Matrix3::from_columns(&[mix(c0, c, c2, -s), c1.into(), mix(c0, s, c2, c)]),
            Axis::Z => Matrix3::from_columns(&[mix(c0, c, c1, s), mix(c1, c, c0, -s), c2.into()]),
            Axis::Unit(u) => {
                let k = super::skew(u);
                mat_mat(m, &rodrigues(&k, &(k * k), s, c))
            }
        }
    }
    /// `w × u`, with the zeros of an axis-aligned `u` left out.
    #[inline(always)]
    pub fn cross_from(&self, w: &Vector3<T>) -> Vector3<T> {
        let z = T::zero();
        match self {
            Axis::X => Vector3::new(z, w.z, -w.y),
            Axis::Y => Vector3::new(-w.z, z, w.x),
            Axis::Z => Vector3::new(w.y, -w.x, z),
            Axis::Unit(u) => w.cross(u),
        }
    }
    /// `x += (w × u) s`, touching the two components an axis-aligned `u` leaves
    /// non-zero (no products with zero).
    #[inline(always)]
    pub fn add_cross_scaled(&self, x: &mut Vector3<T>, w: &Vector3<T>, s: T) {
        match self {
            Axis::X => {
                x.y = madd(w.z, s, x.y);
                x.z = madd(-w.y, s, x.z);
            }
            Axis::Y => {
                x.x = madd(-w.z, s, x.x);
                x.z = madd(w.x, s, x.z);
            }
            Axis::Z => {
                x.x = madd(w.y, s, x.x);
                x.y = madd(-w.x, s, x.y);
            }
            Axis::Unit(u) => *x = axpy(x, &cross(w, u), s),
        }
    }
    /// `x += u s`, touching one component for an axis-aligned `u`.
    #[inline(always)]
    pub fn add_scaled(&self, x: &mut Vector3<T>, s: T) {
        match self {
            Axis::X => x.x += s,
            Axis::Y => x.y += s,
            Axis::Z => x.z += s,
            Axis::Unit(u) => *x = axpy(x, u, s),
        }
    }
    /// `R v` for a rotation `R` about this axis (read from `r`): 4 products for an
    /// axis-aligned axis, whose row and column through the axis are those of 1.
    #[inline(always)]
    pub fn rot_mul(&self, r: &Matrix3<T>, v: &Vector3<T>) -> Vector3<T> {
        match self {
            Axis::X => Vector3::new(
                v.x,
                madd(r[(1, 2)], v.z, r[(1, 1)] * v.y),
                madd(r[(2, 2)], v.z, r[(2, 1)] * v.y),
            ),
            Axis::Y => Vector3::new(
                madd(r[(0, 2)], v.z, r[(0, 0)] * v.x),
                v.y,
                madd(r[(2, 2)], v.z, r[(2, 0)] * v.x),
            ),
            Axis::Z => Vector3::new(
                madd(r[(0, 1)], v.y, r[(0, 0)] * v.x),
                madd(r[(1, 1)], v.y, r[(1, 0)] * v.x),
                v.z,
            ),
            Axis::Unit(_) => mat_vec(r, v),
        }
    }
    /// `Rᵀ v` for a rotation `R` about this axis (read from `r`).
    #[inline(always)]
    pub fn rot_tr_mul(&self, r: &Matrix3<T>, v: &Vector3<T>) -> Vector3<T> {
        match self {
            Axis::X => Vector3::new(
                v.x,
                madd(r[(2, 1)], v.z, r[(1, 1)] * v.y),
                madd(r[(2, 2)], v.z, r[(1, 2)] * v.y),
            ),
            Axis::Y => Vector3::new(
                madd(r[(2, 0)], v.z, r[(0, 0)] * v.x),
                v.y,
                madd(r[(2, 2)], v.z, r[(0, 2)] * v.x),
            ),
            Axis::Z => Vector3::new(
                madd(r[(1, 0)], v.y, r[(0, 0)] * v.x),
                madd(r[(1, 1)], v.y, r[(0, 1)] * v.x),
                v.z,
            ),
            Axis::Unit(_) => mat_tr_vec(r, v),
        }
    }
    /// `m R` for a rotation `R` about this axis (read from `r`): two columns of `m`
    /// mixed (12 products instead of 27).
    #[inline(always)]
    pub fn mul_rot(&self, m: &Matrix3<T>, r: &Matrix3<T>) -> Matrix3<T> {
        let (c0, c1, c2) = (m.column(0), m.column(1), m.column(2));
        match self {
            Axis::X => Matrix3::from_columns(&[
                c0.into(),
                mix(c1, r[(1, 1)], c2, r[(2, 1)]),
                mix(c1, r[(1, 2)], c2, r[(2, 2)]),
            ]),
            Axis::Y => Matrix3::from_columns(&[
                mix(c0, r[(0, 0)], c2, r[(2, 0)]),
                c1.into(),
                mix(c0, r[(0, 2)], c2, r[(2, 2)]),
            ]),
            Axis::Z => Matrix3::from_columns(&[
                mix(c0, r[(0, 0)], c1, r[(1, 0)]),
                mix(c0, r[(0, 1)], c1, r[(1, 1)]),
                c2.into(),
            ]),
            Axis::Unit(_) => mat_mat(m, r),
        }
    }
    /// `m · u` for a 3x3 matrix (a column for axis-aligned axes).
    #[inline(always)]
    pub fn mat_mul(&self, m: &Matrix3<T>) -> Vector3<T> {
        match self {
            Axis::X => m.column(0).into(),
            Axis::Y => m.column(1).into(),
            Axis::Z => m.column(2).into(),
            Axis::Unit(u) => mat_vec(m, u),
        }
    }
}

/// The rotation by `atan2(s, c)` about a unit axis `u` (Rodrigues, as
/// [`super::axis_angle`]): `1 + k s + k² (1 − c)` for `k = u*` and `k2 = k k`
/// (a joint's `k k` may be made once, `Data::axis_k2`: the same product, the
/// same bits).
#[inline(always)]
pub(crate) fn rodrigues<T: Scalar>(k: &Matrix3<T>, k2: &Matrix3<T>, s: T, c: T) -> Matrix3<T> {
    Matrix3::identity() + k * s + k2 * (T::one() - c)
}

/// `a x + b y` for two columns of a 3x3 matrix (an axis rotation mixing them).
#[inline(always)]
fn mix<T: Scalar>(
    a: nalgebra::MatrixView3x1<'_, T>,
    x: T,
    b: nalgebra::MatrixView3x1<'_, T>,
    y: T,
) -> Vector3<T> {
    Vector3::new(
        madd(b[0], y, a[0] * x),
        madd(b[1], y, a[1] * x),
        madd(b[2], y, a[2] * x),
    )
}

/// An axis known at compile time (`AxX`, `AxY`, `AxZ`) or carried as a unit vector
/// (`AxU`): `get` returns the [`Axis`], a constant for the zero-sized ones.
pub(crate) trait AxisOf<T: Scalar>: Copy {
    /// The axis.
    fn get(&self) -> Axis<T>;
}
/// The x axis, known at compile time.
#[derive(Clone, Copy)]
pub(crate) struct AxX;
/// The y axis, known at compile time.
#[derive(Clone, Copy)]
pub(crate) struct AxY;
/// The z axis, known at compile time.
#[derive(Clone, Copy)]
pub(crate) struct AxZ;
/// Any other unit axis, carried as a vector.
#[derive(Clone, Copy)]
pub(crate) struct AxU<T: Scalar>(pub Vector3<T>);
impl<T: Scalar> AxisOf<T> for AxX {
    #[inline(always)]
    fn get(&self) -> Axis<T> {
        Axis::X
    }
}
impl<T: Scalar> AxisOf<T> for AxY {
    #[inline(always)]
    fn get(&self) -> Axis<T> {
        Axis::Y
    }
}
impl<T: Scalar> AxisOf<T> for AxZ {
    #[inline(always)]
    fn get(&self) -> Axis<T> {
        Axis::Z
    }
}
impl<T: Scalar> AxisOf<T> for AxU<T> {
    #[inline(always)]
    fn get(&self) -> Axis<T> {
        Axis::Unit(self.0)
    }
}
