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

/// [`kinetic_energy_from_placements`] for the simulation's energy guard at
/// (q, v) (sizes the simulation's own): when a step asked for the bias at
/// placements since the last call (`data.step_bias_wanted`), the bias pass runs
/// here instead, its C kept in `data.step_bias` for the next step
/// (`rnea::bias_at_placements_ahead`), and T = ½ Σ v̂ᵢᵀ Îᵢ v̂ᵢ is summed there
/// over its body velocities and their products Îᵢ v̂ᵢ (docs/theory.md
/// §"Velocity recursion": the same velocities as the velocity pass, its
/// rotations about joint axes skipping only products with exact zeros and
/// ones).
///
/// `skip`: bodies of sleeping trees (at v = 0, held), left out of the bias
/// pass ([`super::rnea::bias_at_placements_energy`]: T the same, their C
/// entries zero); the caller drops the C computed ahead when one of them
/// wakes before the step (`data.step_bias_ok = false`).
pub(crate) fn kinetic_energy_step_ahead(
    model: &Model<f64>,
    data: &mut Data<f64>,
    q: &DVector<f64>,
    v: &DVector<f64>,
    skip: &[bool],
) -> f64 {
    if !data.step_bias_wanted || q.len() != model.nq || v.len() != model.nv {
        data.step_bias_ok = false;
        return kinetic_energy_from_placements(model, data, v).unwrap_or(f64::NAN);
    }
    // (lone free bodies: one pass, C written where it is kept; `data.bias`
    // is not read before the step swaps `step_bias` into it)
    let mut c = std::mem::replace(&mut data.step_bias, DVector::zeros(0));
    let lone =
        super::rnea_lone::lone_bias_energy(model, data, v.as_slice(), skip, c.as_mut_slice());
    data.step_bias = c;
    let ke = match lone {
        Some(ke) => ke,
        None => {
            let ke = super::rnea::bias_at_placements_energy(model, data, v, skip);
            data.step_bias.copy_from(&data.bias);
            ke
        }
    };
    data.step_bias_q.copy_from(q);
    data.step_bias_v.copy_from(v);
    data.step_bias_ok = true;
    data.step_bias_wanted = false;
    ke
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
