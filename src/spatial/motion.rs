use super::ops::{add_cross, cross, dot, madd};
use super::{skew, Force, Scalar};
use nalgebra::{Matrix6, Vector3, Vector6};
use std::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};

/// A spatial motion vector `[ω; v]` (docs/theory.md §"Spatial vectors"): angular velocity and the
/// linear velocity of the point at the frame's origin. Also a spatial
/// acceleration or a joint axis `ŝ`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Motion<T: Scalar = f64> {
    /// Angular part ω (rad/s; rad/s² for an acceleration).
    pub ang: Vector3<T>,
    /// Linear velocity of the point at the frame's origin (m/s; m/s² for an
    /// acceleration).
    pub lin: Vector3<T>,
}

impl<T: Scalar> Motion<T> {
    /// `[ang; lin]`: angular part, then the linear part at the frame's origin.
    #[inline(always)]
    pub fn new(ang: Vector3<T>, lin: Vector3<T>) -> Self {
        Self { ang, lin }
    }
    /// The zero motion.
    #[inline(always)]
    pub fn zero() -> Self {
        Self {
            ang: Vector3::zeros(),
            lin: Vector3::zeros(),
        }
    }
    /// Spatial cross product on motions, docs/theory.md §"Cross products":
    /// `[a; a_o] × [b; b_o] = [a × b; a × b_o + a_o × b]`.
    #[inline(always)]
    pub fn cross(&self, m: &Motion<T>) -> Motion<T> {
        Motion {
            ang: cross(&self.ang, &m.ang),
            lin: add_cross(&cross(&self.ang, &m.lin), &self.lin, &m.ang),
        }
    }
    /// The dual cross product `v ×* f = [ω × n + v × f; ω × f]`, with `(v×*) = −(v×)ᵀ`.
    #[inline(always)]
    pub fn cross_force(&self, f: &Force<T>) -> Force<T> {
        Force {
            ang: add_cross(&cross(&self.ang, &f.ang), &self.lin, &f.lin),
            lin: cross(&self.ang, &f.lin),
        }
    }
    /// The power `vᵀ f` of a force on this motion (the course note's spatial transpose
    /// in angular-first coordinates, docs/theory.md §"Spatial vectors").
    #[inline(always)]
    pub fn dot(&self, f: &Force<T>) -> T {
        madd(
            self.lin.z,
            f.lin.z,
            madd(
                self.lin.y,
                f.lin.y,
                madd(self.lin.x, f.lin.x, dot(&self.ang, &f.ang)),
            ),
        )
    }
    /// The 6-vector `[ω; v]` (angular first).
    pub fn to_vector(&self) -> Vector6<T> {
        Vector6::new(
            self.ang.x, self.ang.y, self.ang.z, self.lin.x, self.lin.y, self.lin.z,
        )
    }
    /// From a 6-vector `[ω; v]` (angular first), the inverse of [`Motion::to_vector`].
    pub fn from_vector(x: &Vector6<T>) -> Self {
        Self {
            ang: Vector3::new(x[0], x[1], x[2]),
            lin: Vector3::new(x[3], x[4], x[5]),
        }
    }
    /// The 6x6 matrix of `self ×` (tests and documentation only).
    pub fn cross_matrix(&self) -> Matrix6<T> {
        let mut m = Matrix6::zeros();
        let w = skew(&self.ang);
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&w);
        m.fixed_view_mut::<3, 3>(3, 3).copy_from(&w);
        m.fixed_view_mut::<3, 3>(3, 0).copy_from(&skew(&self.lin));
        m
    }
    /// The 6x6 matrix of `self ×*` (tests and documentation only).
    pub fn cross_force_matrix(&self) -> Matrix6<T> {
        -self.cross_matrix().transpose()
    }
    /// Whether all six entries are finite.
    pub fn is_finite(&self) -> bool {
        self.ang
            .iter()
            .chain(self.lin.iter())
            .all(|x| x.is_finite())
    }
}

impl<T: Scalar> Add for Motion<T> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self {
            ang: self.ang + o.ang,
            lin: self.lin + o.lin,
        }
    }
}
impl<T: Scalar> Sub for Motion<T> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self {
            ang: self.ang - o.ang,
            lin: self.lin - o.lin,
        }
    }
}
impl<T: Scalar> AddAssign for Motion<T> {
    #[inline(always)]
    fn add_assign(&mut self, o: Self) {
        self.ang += o.ang;
        self.lin += o.lin;
    }
}
impl<T: Scalar> SubAssign for Motion<T> {
    #[inline(always)]
    fn sub_assign(&mut self, o: Self) {
        self.ang -= o.ang;
        self.lin -= o.lin;
    }
}
impl<T: Scalar> Neg for Motion<T> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self {
            ang: -self.ang,
            lin: -self.lin,
        }
    }
}
impl<T: Scalar> Mul<T> for Motion<T> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: T) -> Self {
        Self {
            ang: self.ang * s,
            lin: self.lin * s,
        }
    }
}
