use super::{check_sizes, DynamicsError};
use crate::model::{Data, Model};
use crate::spatial::{Motion, Scalar};
use nalgebra::DVector;

/// Kinetic energy `½ Σ v̂ᵢᵀ Îᵢ v̂ᵢ` (also fills `data.v`, `data.li_m_i`).
pub fn kinetic_energy<T: Scalar>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &DVector<T>,
    v: &DVector<T>,
) -> Result<T, DynamicsError> {
    check_sizes(model, q, &[("v", v)], None)?;
    for i in 1..model.nbodies {
        let (x_j, _) = model.joints[i].calc(q, None);
        data.li_m_i[i] = model.placements[i].compose(&x_j);
    }
    kinetic_energy_from_placements(model, data, v)
}

/// [`kinetic_energy`] with the joint placements of the configuration already in
/// `data.li_m_i` (forward kinematics ran at this q): one pass of body velocities
/// (docs/theory.md §"Velocity recursion", into `data.v`), no joint transform.
pub fn kinetic_energy_from_placements<T: Scalar>(
    model: &Model<T>,
    data: &mut Data<T>,
    v: &DVector<T>,
) -> Result<T, DynamicsError> {
    crate::model::DimensionError::check("v", model.nv, v.len())?;
    let mut ke = T::zero();
    data.v[0] = Motion::zero();
    for i in 1..model.nbodies {
        let mut vi = data.li_m_i[i].inv_act_motion(&data.v[model.parent[i]]);
        model.joints[i].add_motion(&mut vi, v);
        data.v[i] = vi;
        ke += model.inertias[i].kinetic_energy(&vi);
    }
    Ok(ke)
}

/// Gravitational potential energy `−Σ mᵢ gᵀ cᵢ` over the bodies' world centres of
/// mass (zero at the world origin), from `data.o_m_i` (call forward kinematics first).
pub fn potential_energy<T: Scalar>(model: &Model<T>, data: &Data<T>) -> T {
    let mut pe = T::zero();
    for i in 1..model.nbodies {
        let inertia = &model.inertias[i];
        let c = data.o_m_i[i].act_point(&inertia.com);
        pe -= inertia.mass * model.gravity.dot(&c);
    }
    pe
}

/// Kinetic and potential energy `(T, V)` of the state (q, v) for a caller without
/// a [`Data`] (docs/theory.md §"Energies"): one pass of joint transforms and body
/// velocities into a per-body scratch allocated here (2 × nbodies small entries).
pub fn energies<T: Scalar>(
    model: &Model<T>,
    q: &DVector<T>,
    v: &DVector<T>,
) -> Result<(T, T), DynamicsError> {
    check_sizes(model, q, &[("v", v)], None)?;
    let mut pose = vec![crate::spatial::Se3::identity(); model.nbodies];
    let mut vel = vec![Motion::zero(); model.nbodies];
    let (mut ke, mut pe) = (T::zero(), T::zero());
    for i in 1..model.nbodies {
        let p = model.parent[i];
        let (x_j, v_j) = model.joints[i].calc(q, Some(v));
        let li = model.placements[i].compose(&x_j);
        pose[i] = pose[p].compose(&li);
        vel[i] = li.inv_act_motion(&vel[p]) + v_j;
        let inertia = &model.inertias[i];
        ke += inertia.kinetic_energy(&vel[i]);
        pe -= inertia.mass * model.gravity.dot(&pose[i].act_point(&inertia.com));
    }
    Ok((ke, pe))
}
