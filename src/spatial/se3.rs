use super::ops::{add_cross, add_mat_vec, mat_mat, mat_tr_mat, mat_tr_vec, mat_vec};
use super::{skew, Force, Inertia, Motion, Scalar};
use nalgebra::{Matrix3, Matrix6, Vector3};
use std::ops::Mul;

/// A rigid transform `aMb`, stored as rotation + translation: `rot` maps
/// b-coordinates to a-coordinates and `trans` is b's origin seen from a
/// (`x_a = rot · x_b + trans`). As a spatial transform on motions it is
/// `aX̂b = [R 0; t*R R]` (docs/theory.md §"Plücker transforms"); on forces its dual
/// `[R t*R; 0 R]`.
/// Pinocchio's names: [`Se3::act_motion`] is `act`, [`Se3::inv_act_motion`] `actInv`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Se3<T: Scalar = f64> {
    /// Rotation `R`: b-coordinates to a-coordinates.
    pub rot: Matrix3<T>,
    /// Translation `t`: b's origin in a-coordinates (m).
    pub trans: Vector3<T>,
}

impl<T: Scalar> Default for Se3<T> {
    fn default() -> Self {
        Self::identity()
    }
}

impl<T: Scalar> Se3<T> {
    /// From rotation `R` and translation `t` (m); `R` is not checked to be a rotation.
    #[inline(always)]
    pub fn new(rot: Matrix3<T>, trans: Vector3<T>) -> Self {
        Self { rot, trans }
    }
    /// The identity transform (`R = 1`, `t = 0`).
    #[inline(always)]
    pub fn identity() -> Self {
        Self {
            rot: Matrix3::identity(),
            trans: Vector3::zeros(),
        }
    }
    /// A pure translation by `trans` (m).
    #[inline(always)]
    pub fn from_translation(trans: Vector3<T>) -> Self {
        Self {
            rot: Matrix3::identity(),
            trans,
        }
    }
    /// A pure rotation `rot` (no translation).
    #[inline(always)]
    pub fn from_rotation(rot: Matrix3<T>) -> Self {
        Self {
            rot,
            trans: Vector3::zeros(),
        }
    }
    /// `bMa = aMb⁻¹ = (Rᵀ, −Rᵀ t)`.
    #[inline(always)]
    pub fn inverse(&self) -> Self {
        Self {
            rot: self.rot.transpose(),
            trans: -mat_tr_vec(&self.rot, &self.trans),
        }
    }
    /// `aMc = aMb · bMc`.
    #[inline(always)]
    pub fn compose(&self, m: &Se3<T>) -> Se3<T> {
        Se3 {
            rot: mat_mat(&self.rot, &m.rot),
            trans: add_mat_vec(&self.trans, &self.rot, &m.trans),
        }
    }
    /// `bMc = aMb⁻¹ · aMc` without forming the inverse.
    #[inline(always)]
    pub fn inv_compose(&self, m: &Se3<T>) -> Se3<T> {
        Se3 {
            rot: mat_tr_mat(&self.rot, &m.rot),
            trans: mat_tr_vec(&self.rot, &(m.trans - self.trans)),
        }
    }
    /// A point of b in a: `R p + t`.
    #[inline(always)]
    pub fn act_point(&self, p: &Vector3<T>) -> Vector3<T> {
        add_mat_vec(&self.trans, &self.rot, p)
    }
    /// A point of a in b: `Rᵀ (p − t)`.
    #[inline(always)]
    pub fn inv_act_point(&self, p: &Vector3<T>) -> Vector3<T> {
        mat_tr_vec(&self.rot, &(p - self.trans))
    }
    /// Motion from b to a (docs/theory.md §"Plücker transforms"): `ω' = R ω`, `v' = R v + t × ω'`.
    #[inline(always)]
    pub fn act_motion(&self, m: &Motion<T>) -> Motion<T> {
        let ang = mat_vec(&self.rot, &m.ang);
        Motion {
            ang,
            lin: add_cross(&mat_vec(&self.rot, &m.lin), &self.trans, &ang),
        }
    }
    /// Motion from a to b: `ω' = Rᵀ ω`, `v' = Rᵀ (v − t × ω)`.
    #[inline(always)]
    pub fn inv_act_motion(&self, m: &Motion<T>) -> Motion<T> {
        Motion {
            ang: mat_tr_vec(&self.rot, &m.ang),
            lin: mat_tr_vec(&self.rot, &add_cross(&m.lin, &m.ang, &self.trans)),
        }
    }
    /// Force from b to a (the dual transform `aX̂b* = aX̂b⁻ᵀ`): `f' = R f`, `n' = R n + t × f'`.
    #[inline(always)]
    pub fn act_force(&self, f: &Force<T>) -> Force<T> {
        let lin = mat_vec(&self.rot, &f.lin);
        Force {
            ang: add_cross(&mat_vec(&self.rot, &f.ang), &self.trans, &lin),
            lin,
        }
    }
    /// Force from a to b: `f' = Rᵀ f`, `n' = Rᵀ (n − t × f)`.
    #[inline(always)]
    pub fn inv_act_force(&self, f: &Force<T>) -> Force<T> {
        Force {
            ang: mat_tr_vec(&self.rot, &add_cross(&f.ang, &f.lin, &self.trans)),
            lin: mat_tr_vec(&self.rot, &f.lin),
        }
    }
    /// Inertia from b to a (mass unchanged, centre of mass moved, `I_c' = R I_c Rᵀ`).
    #[inline(always)]
    pub fn act_inertia(&self, i: &Inertia<T>) -> Inertia<T> {
        Inertia {
            mass: i.mass,
            com: self.act_point(&i.com),
            inertia_c: self.rot * i.inertia_c * self.rot.transpose(),
        }
    }
    /// Inertia from a to b.
    #[inline(always)]
    pub fn inv_act_inertia(&self, i: &Inertia<T>) -> Inertia<T> {
        Inertia {
            mass: i.mass,
            com: self.inv_act_point(&i.com),
            inertia_c: self.rot.transpose() * i.inertia_c * self.rot,
        }
    }
    /// The 6x6 motion transform (docs/theory.md §"Plücker transforms"; tests and
    /// documentation only).
    pub fn to_motion_matrix(&self) -> Matrix6<T> {
        let mut x = Matrix6::zeros();
        x.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.rot);
        x.fixed_view_mut::<3, 3>(3, 3).copy_from(&self.rot);
        x.fixed_view_mut::<3, 3>(3, 0)
            .copy_from(&(skew(&self.trans) * self.rot));
        x
    }
    /// The 6x6 force transform `X* = X⁻ᵀ` (tests and documentation only).
    pub fn to_force_matrix(&self) -> Matrix6<T> {
        let mut x = Matrix6::zeros();
        x.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.rot);
        x.fixed_view_mut::<3, 3>(3, 3).copy_from(&self.rot);
        x.fixed_view_mut::<3, 3>(0, 3)
            .copy_from(&(skew(&self.trans) * self.rot));
        x
    }
}

impl<T: Scalar> Mul for Se3<T> {
    type Output = Se3<T>;
    #[inline(always)]
    fn mul(self, m: Se3<T>) -> Se3<T> {
        self.compose(&m)
    }
}
