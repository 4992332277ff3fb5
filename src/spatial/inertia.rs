use super::ops::{add_cross, mat_vec};
use super::{skew, Force, Motion, Scalar};
use nalgebra::{Matrix3, Matrix6, Vector3};

/// A rigid body's spatial inertia: mass `m`, centre of mass `c` and the
/// rotational inertia `I_c` about the centre of mass, all in the body's frame.
///
/// As a 6x6 matrix (angular-first, docs/theory.md §"Spatial inertia"):
/// `Î = [I_c + m c* c*ᵀ, m c*; m c*ᵀ, m 1]`, the lower-left block being the
/// tensor form of the parallel-axis theorem (`I = I_c + m d²`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inertia<T: Scalar = f64> {
    /// Mass `m` (kg).
    pub mass: T,
    /// Centre of mass `c` in the body's frame (m).
    pub com: Vector3<T>,
    /// Rotational inertia `I_c` about the centre of mass, body-frame axes (kg·m²).
    pub inertia_c: Matrix3<T>,
}

impl<T: Scalar> Default for Inertia<T> {
    fn default() -> Self {
        Self::zero()
    }
}

impl<T: Scalar> Inertia<T> {
    /// From mass (kg), centre of mass (m, body frame) and the rotational
    /// inertia about the centre of mass (kg·m²), unchecked.
    pub fn new(mass: T, com: Vector3<T>, inertia_c: Matrix3<T>) -> Self {
        Self {
            mass,
            com,
            inertia_c,
        }
    }
    /// The zero inertia (a massless body; the world's).
    #[inline(always)]
    pub fn zero() -> Self {
        Self {
            mass: T::zero(),
            com: Vector3::zeros(),
            inertia_c: Matrix3::zeros(),
        }
    }
    /// `Î v = [I_c ω + c × f; f]` with `f = m (v − c × ω)` (docs/theory.md §"Spatial inertia").
    #[inline(always)]
    pub fn mul_motion(&self, v: &Motion<T>) -> Force<T> {
        let lin = add_cross(&v.lin, &v.ang, &self.com) * self.mass;
        Force {
            ang: add_cross(&mat_vec(&self.inertia_c, &v.ang), &self.com, &lin),
            lin,
        }
    }
    /// Whether the inertia is exactly zero (mass, centre of mass and
    /// rotational inertia): a body's own force `Î a + v ×* Î v` is then zero
    /// (each term a product with a zero; at most a zero's sign differs).
    #[inline(always)]
    pub fn is_zero(&self) -> bool {
        // (the mass first; then the twelve others' tests folded without early
        // exit: compared side by side, no branch an entry)
        let z = T::zero();
        self.mass == z
            && self.com.iter().fold(true, |all, x| all & (*x == z))
                & self.inertia_c.iter().fold(true, |all, x| all & (*x == z))
    }
    /// Kinetic energy `½ vᵀ Î v`.
    #[inline]
    pub fn kinetic_energy(&self, v: &Motion<T>) -> T {
        v.dot(&self.mul_motion(v)) * super::lit(0.5)
    }
    /// The rotational inertia about the frame origin, `I_c + m c*c*ᵀ` (parallel axis).
    #[inline]
    pub fn inertia_origin(&self) -> Matrix3<T> {
        let cx = skew(&self.com);
        self.inertia_c - cx * cx * self.mass
    }
    /// Sum of two inertias expressed in the same frame (composite body): the masses
    /// add, the centre of mass is the mass-weighted mean and each rotational inertia
    /// is moved to the new centre of mass by the parallel-axis theorem.
    pub fn add(&self, o: &Inertia<T>) -> Inertia<T> {
        let m = self.mass + o.mass;
        if m <= T::zero() {
            // Massless parts: keep any rotational inertia they carry.
            return Inertia {
                mass: m,
                com: Vector3::zeros(),
                inertia_c: self.inertia_c + o.inertia_c,
            };
        }
        let com = (self.com * self.mass + o.com * o.mass) / m;
        let d1 = skew(&(self.com - com));
        let d2 = skew(&(o.com - com));
        let inertia_c = self.inertia_c - d1 * d1 * self.mass + o.inertia_c - d2 * d2 * o.mass;
        Inertia {
            mass: m,
            com,
            inertia_c,
        }
    }
    /// The 6x6 angular-first matrix (tests and documentation only).
    pub fn to_matrix(&self) -> Matrix6<T> {
        let cx = skew(&self.com);
        let mut m = Matrix6::zeros();
        m.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(self.inertia_c - cx * cx * self.mass));
        m.fixed_view_mut::<3, 3>(0, 3).copy_from(&(cx * self.mass));
        m.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-cx * self.mass));
        m.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(Matrix3::identity() * self.mass));
        m
    }
}
