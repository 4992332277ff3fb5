use super::{center_of_mass, check_sizes, DynamicsError};
use crate::model::{Data, Model};
use crate::spatial::{Force, Scalar};
use nalgebra::{DVector, Vector3};

/// The centroidal momentum `h_G = [k_G; M ċ]`: the total spatial momentum
/// `Σ ⁰X*ᵢ Îᵢ v̂ᵢ` expressed at the centre of mass with world-aligned axes
/// (angular momentum about G, then linear momentum `M ċ`).
/// Computes kinematics and velocities itself (fills `data.li_m_i`, `o_m_i`, `v`).
pub fn centroidal_momentum<T: Scalar>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &DVector<T>,
    v: &DVector<T>,
) -> Result<(Vector3<T>, Vector3<T>), DynamicsError> {
    check_sizes(model, q, &[("v", v)], None)?;
    let mut h = Force::zero();
    for i in 1..model.nbodies {
        let p = model.parent[i];
        let (x_j, v_j) = model.joints[i].calc(q, Some(v));
        let li_m_i = model.placements[i].compose(&x_j);
        data.li_m_i[i] = li_m_i;
        data.o_m_i[i] = data.o_m_i[p].compose(&li_m_i);
        // docs/theory.md §"Velocity recursion"
        data.v[i] = li_m_i.inv_act_motion(&data.v[p]) + v_j;
        h += data.o_m_i[i].act_force(&model.inertias[i].mul_motion(&data.v[i]));
    }
    let c = center_of_mass(model, data);
    // moment about G: n_G = n_O − c × f
    Ok((h.ang - c.cross(&h.lin), h.lin))
}
