use super::DynamicsError;
use crate::model::{Data, DimensionError, Model};
use crate::spatial::{Inertia, Scalar};
use nalgebra::{DMatrix, Vector3};

/// The centre of mass of the moving bodies in the world frame,
/// `c = Σ mᵢ ⁰Xᵢ cᵢ / Σ mᵢ` (docs/theory.md §"Centre of mass"), from `data.o_m_i`
/// (call forward kinematics first). Returns the origin for a massless model.
pub fn center_of_mass<T: Scalar>(model: &Model<T>, data: &Data<T>) -> Vector3<T> {
    mass_weighted_mean(model, |i, inertia| data.o_m_i[i].act_point(&inertia.com))
}

/// The velocity of the centre of mass of the bodies that move (world axes),
/// `ċ = Σ mᵢ ⁰Rᵢ (vᵢ + ωᵢ × cᵢ) / Σ mᵢ` (docs/theory.md §"Centre of mass
/// Jacobian"; it is `J_c v`). Reads `data.o_m_i` and `data.v`
/// ([`super::forward_kinematics_second_order`] first). Zero for a massless model.
pub fn center_of_mass_velocity<T: Scalar>(model: &Model<T>, data: &Data<T>) -> Vector3<T> {
    mass_weighted_mean(model, |i, inertia| {
        let v = &data.v[i];
        data.o_m_i[i].rot * (v.lin + v.ang.cross(&inertia.com))
    })
}

/// `Σ mᵢ xᵢ / Σ mᵢ` over the bodies that move, `xᵢ = x(i, Iᵢ)` (zero if massless).
fn mass_weighted_mean<T: Scalar>(
    model: &Model<T>,
    x: impl Fn(usize, &Inertia<T>) -> Vector3<T>,
) -> Vector3<T> {
    let mut mx = Vector3::zeros();
    let mut m = T::zero();
    for i in 1..model.nbodies {
        let inertia = &model.inertias[i];
        mx += x(i, inertia) * inertia.mass;
        m += inertia.mass;
    }
    if m > T::zero() {
        mx / m
    } else {
        Vector3::zeros()
    }
}

/// The Jacobian `J_c` (3 × nv) of the centre of mass of the bodies that move, world
/// axes: `ċ = J_c v`, `J_c = Σᵢ (mᵢ / M) J_lin(cᵢ)` with `J_lin(p)` the linear rows
/// of the world-aligned Jacobian of a point p fixed on body i (docs/theory.md
/// §"Centre of mass Jacobian"); a mimic joint adds to its leader's column. Reads
/// `data.o_m_i` (forward kinematics first); `jc` must be 3 × nv and is overwritten
/// (zero for a massless model).
pub fn center_of_mass_jacobian<T: Scalar>(
    model: &Model<T>,
    data: &Data<T>,
    jc: &mut DMatrix<T>,
) -> Result<(), DynamicsError> {
    DimensionError::check("com jacobian rows", 3, jc.nrows())?;
    DimensionError::check("com jacobian columns", model.nv, jc.ncols())?;
    jc.as_mut_slice().fill(T::zero());
    let total = model.total_mass();
    if total <= T::zero() {
        return Ok(());
    }
    for i in 1..model.nbodies {
        let inertia = &model.inertias[i];
        if inertia.mass == T::zero() {
            continue;
        }
        let w = inertia.mass / total;
        let c = data.o_m_i[i].act_point(&inertia.com);
        let mut b = i;
        while b != 0 {
            let joint = &model.joints[b];
            for k in 0..joint.nv() {
                let s = data.o_m_i[b].act_motion(&joint.subspace_column(k));
                let lin = (s.lin + s.ang.cross(&c)) * w;
                for r in 0..3 {
                    jc[(r, joint.iv + k)] += lin[r];
                }
            }
            b = model.parent[b];
        }
    }
    Ok(())
}
