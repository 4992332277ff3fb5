//! Rigid-body dynamics algorithms, one a file, all working on a preallocated
//! [`Data`](crate::model::Data): forward kinematics, recursive Newton–Euler
//! inverse dynamics (docs/theory.md §"Recursive Newton–Euler"), the course note's
//! forward dynamics by n+1 inverse dynamics calls (docs/theory.md §"Forward dynamics
//! by inverse dynamics"), energies; the fast path: CRBA for H, the tree-sparse LTDL
//! factorisation, the articulated-body algorithm (docs/theory.md §"Forward dynamics").

mod aba;
mod centroidal;
mod crba;
mod energy;
mod forward_rnea;
mod jacobian;
mod kinematics;
pub mod linalg;
pub mod ltdl;
mod rnea;

pub use crate::spatial::CompositeInertia;
pub use aba::aba;
pub use centroidal::{center_of_mass, centroidal_momentum};
pub use crba::{crba, crba_upper};

pub use energy::{kinetic_energy, kinetic_energy_from_placements, potential_energy};
pub use forward_rnea::{forward_dynamics_rnea, mass_matrix_rnea};
pub use jacobian::frame_jacobian;
pub use kinematics::{forward_kinematics, update_frames};
pub use rnea::{bias, rnea};

/// Why forward dynamics has no answer.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DynamicsError {
    /// A movable joint moves only massless links: H is singular for every q.
    #[error("joint \"{0}\" moves only massless links: the mass matrix is singular, there is no forward dynamics")]
    MasslessJoint(String),
    /// H is singular to working precision at this configuration (pivot index given).
    #[error("the mass matrix is singular to working precision (pivot {0})")]
    Singular(usize),
    /// The articulated-body algorithm cannot express mimic coupling.
    #[error("the articulated-body algorithm cannot handle mimic joints (use forward_dynamics)")]
    Mimic,
}

use crate::model::{Data, FdMethod, Model};
use crate::spatial::{Force, Scalar};
use nalgebra::DVector;

/// Forward dynamics is undefined where a moving joint carries no mass (H is
/// singular whatever the state): the error names the first such joint.
pub(crate) fn check_massless<T: Scalar>(model: &Model<T>) -> Result<(), DynamicsError> {
    match model.massless_joints.first() {
        Some(name) => Err(DynamicsError::MasslessJoint(name.clone())),
        None => Ok(()),
    }
}

/// The joint-space inertia matrix H(q), written to `data.h` (by [`crba`]).
pub fn mass_matrix<T: Scalar>(model: &Model<T>, data: &mut Data<T>, q: &DVector<T>) {
    crba(model, data, q);
}

/// Forward dynamics through H: `C` by RNEA (docs/theory.md §"Bias forces"), H by
/// [`crba`], then `H q̈ = τ − C` (docs/theory.md §"Equation of motion") by the
/// tree-sparse LTDL factorisation (docs/theory.md §"Tree-sparse LTDL")
/// ([`ltdl::ltdl`]), or, on a model with mimic joints (whose `Gᵀ H G` is not
/// tree-shaped), the dense Cholesky. Result in `data.qdd`; `data.h` (its upper
/// triangle, [`crba_upper`]; all of it with mimic joints), `data.bias` and the
/// factor in `data.chol` are left for reuse.
pub fn forward_dynamics_crba<'d, T: Scalar>(
    model: &Model<T>,
    data: &'d mut Data<T>,
    q: &DVector<T>,
    v: &DVector<T>,
    tau: &DVector<T>,
    fext: Option<&[Force<T>]>,
) -> Result<&'d DVector<T>, DynamicsError> {
    check_massless(model)?;
    bias(model, data, q, v, fext);
    if model.has_mimic {
        crba(model, data, q);
    } else {
        // LTDL reads H's upper triangle only
        crba_upper(model, data, q);
    }
    data.qdd.copy_from(tau);
    data.qdd -= &data.bias;
    if model.has_mimic {
        linalg::cholesky(&data.h, &mut data.chol).map_err(DynamicsError::Singular)?;
        linalg::cholesky_solve(&data.chol, &mut data.qdd);
    } else {
        ltdl::ltdl(&data.h, &model.dof_parent, &mut data.chol).map_err(DynamicsError::Singular)?;
        ltdl::ltdl_solve(&data.chol, &model.dof_parent, &mut data.qdd);
    }
    Ok(&data.qdd)
}

/// The engine's forward dynamics: `q̈` with `H q̈ = τ − C(q, q̇)`, written to `data.qdd`,
/// by the method `model.topology.fd_method` picked when the model was built
/// ([`crate::model::Topology::choose`]): [`aba`] on long chains and large trees,
/// [`forward_dynamics_crba`] where the tree is shallow enough for CRBA + LTDL to
/// win, and always on mimic models.
pub fn forward_dynamics<'d, T: Scalar>(
    model: &Model<T>,
    data: &'d mut Data<T>,
    q: &DVector<T>,
    v: &DVector<T>,
    tau: &DVector<T>,
    fext: Option<&[Force<T>]>,
) -> Result<&'d DVector<T>, DynamicsError> {
    match model.topology.fd_method {
        FdMethod::Aba if !model.has_mimic => aba(model, data, q, v, tau, fext),
        _ => forward_dynamics_crba(model, data, q, v, tau, fext),
    }
}
