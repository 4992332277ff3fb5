use super::Scalar;
use nalgebra::{Vector3, Vector6};
use std::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};

/// A spatial force vector `[n; f]`: the moment about the frame's origin and the
/// resultant force (docs/theory.md §"Spatial vectors"). Dual to [`super::Motion`]:
/// `vᵀ f` is power.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Force<T: Scalar = f64> {
    /// Moment `n` about the frame's origin (N·m).
    pub ang: Vector3<T>,
    /// Resultant force `f` (N).
    pub lin: Vector3<T>,
}

impl<T: Scalar> Force<T> {
    /// `[ang; lin]`: moment about the origin (N·m), then force (N).
    #[inline(always)]
    pub fn new(ang: Vector3<T>, lin: Vector3<T>) -> Self {
        Self { ang, lin }
    }
    /// The zero force.
    #[inline(always)]
    pub fn zero() -> Self {
        Self {
            ang: Vector3::zeros(),
            lin: Vector3::zeros(),
        }
    }
    /// A pure force `f` applied at point `p` (both in the same frame): `[p × f; f]`.
    #[inline]
    pub fn at_point(f: Vector3<T>, p: &Vector3<T>) -> Self {
        Self {
            ang: p.cross(&f),
            lin: f,
        }
    }
    /// The 6-vector `[n; f]` (angular first).
    pub fn to_vector(&self) -> Vector6<T> {
        Vector6::new(
            self.ang.x, self.ang.y, self.ang.z, self.lin.x, self.lin.y, self.lin.z,
        )
    }
    /// From a 6-vector `[n; f]` (angular first), the inverse of [`Force::to_vector`].
    pub fn from_vector(x: &Vector6<T>) -> Self {
        Self {
            ang: Vector3::new(x[0], x[1], x[2]),
            lin: Vector3::new(x[3], x[4], x[5]),
        }
    }
    /// Whether all six entries are finite.
    pub fn is_finite(&self) -> bool {
        self.ang
            .iter()
            .chain(self.lin.iter())
            .all(|x| x.is_finite())
    }
}

impl<T: Scalar> Add for Force<T> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self {
            ang: self.ang + o.ang,
            lin: self.lin + o.lin,
        }
    }
}
impl<T: Scalar> Sub for Force<T> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self {
            ang: self.ang - o.ang,
            lin: self.lin - o.lin,
        }
    }
}
impl<T: Scalar> AddAssign for Force<T> {
    #[inline(always)]
    fn add_assign(&mut self, o: Self) {
        self.ang += o.ang;
        self.lin += o.lin;
    }
}
impl<T: Scalar> SubAssign for Force<T> {
    #[inline(always)]
    fn sub_assign(&mut self, o: Self) {
        self.ang -= o.ang;
        self.lin -= o.lin;
    }
}
impl<T: Scalar> Neg for Force<T> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self {
            ang: -self.ang,
            lin: -self.lin,
        }
    }
}
impl<T: Scalar> Mul<T> for Force<T> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: T) -> Self {
        Self {
            ang: self.ang * s,
            lin: self.lin * s,
        }
    }
}
