//! Rigid-body dynamics algorithms, one a file, all working on a preallocated
//! [`Data`]: forward kinematics, recursive Newton–Euler
//! inverse dynamics (docs/theory.md §"Recursive Newton–Euler"), the course note's
//! forward dynamics by n+1 inverse dynamics calls (docs/theory.md §"Forward dynamics
//! by inverse dynamics"), energies; the fast path: CRBA for H, the tree-sparse LTDL
//! factorisation, the articulated-body algorithm (docs/theory.md §"Forward dynamics").

mod aba;
mod aba_derivatives;
mod aba_lone;
mod aba_low_rank;
mod centroidal;
mod com;
pub(crate) mod constraint_dynamics;
mod constraint_dynamics_derivatives;
mod constraint_rows;
mod crba;
mod energy;
mod external;
mod forward_rnea;
mod frames;
mod jacobian;
mod jacobian_dot;
mod joint_jacobians;
mod kinematics;
mod kkt;
mod kkt_blocks;
pub mod linalg;
pub mod ltdl;
mod minv;
mod rnea;
mod rnea_derivatives;
mod rnea_derivatives_rows;
mod rnea_lone;

pub use crate::spatial::CompositeInertia;
pub use aba::aba;
pub use aba_derivatives::aba_derivatives;
pub(crate) use aba_lone::{aba_lone_placed, same_bits};
pub use centroidal::centroidal_momentum;
pub use com::{center_of_mass, center_of_mass_jacobian, center_of_mass_velocity};
pub use constraint_dynamics::{
    constraint_dynamics, constraint_jacobian, constraint_violation, ConstraintData,
    ConstraintDynamicsError,
};
pub use constraint_dynamics_derivatives::constraint_dynamics_derivatives;
pub use crba::{crba, crba_upper};
pub(crate) use crba::{crba_at_placements, crba_packed};
pub use external::add_link_wrench;
pub use frames::{forward_kinematics_second_order, frame_classical_acceleration, frame_velocity};
pub use jacobian_dot::frame_jacobian_time_variation;
pub use joint_jacobians::joint_jacobians;
pub use rnea_derivatives::{rnea_derivatives, LinkWrench};

pub(crate) use energy::kinetic_energy_step_ahead;
pub use energy::{energies, kinetic_energy, kinetic_energy_from_placements, potential_energy};
pub use forward_rnea::{forward_dynamics_rnea, mass_matrix_rnea};
pub use jacobian::{frame_jacobian, Reference};
pub use kinematics::{forward_kinematics, frame_placement, update_frames};
pub(crate) use kinematics::{forward_kinematics_pass, forward_kinematics_unkeyed, plain_pose};
pub use rnea::{bias, rnea};
pub(crate) use rnea::{bias_at_placements, bias_at_placements_ahead};

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
    /// A vector or matrix argument of the wrong size (q: nq, v/a/tau: nv, fext: nbodies).
    #[error(transparent)]
    Dimension(#[from] DimensionError),
    /// A frame or joint id the model does not have.
    #[error(transparent)]
    Name(#[from] NameError),
}

use crate::model::{Data, DimensionError, FdMethod, Model, NameError};
use crate::spatial::{Force, Scalar};
use nalgebra::DVector;

/// The sizes every entry point checks, in O(1): `q` has nq entries, each of `vs`
/// nv, `fext` (if given) nbodies. The test is a few compares inline; the error is
/// built out of line ([`size_error`]), so the algorithms' hot code is unchanged.
#[inline(always)]
pub(crate) fn check_sizes<T: Scalar>(
    model: &Model<T>,
    q: &DVector<T>,
    vs: &[(&'static str, &DVector<T>)],
    fext: Option<&[Force<T>]>,
) -> Result<(), DimensionError> {
    let ok = q.len() == model.nq
        && vs.iter().all(|(_, x)| x.len() == model.nv)
        && fext.is_none_or(|f| f.len() == model.nbodies);
    if ok {
        Ok(())
    } else {
        Err(size_error(
            model,
            q.len(),
            &vs.iter().map(|(n, x)| (*n, x.len())).collect::<Vec<_>>(),
            fext.map(<[_]>::len),
        ))
    }
}

/// The error of [`check_sizes`]: the first argument of the wrong size.
#[cold]
#[inline(never)]
fn size_error<T: Scalar>(
    model: &Model<T>,
    q: usize,
    vs: &[(&'static str, usize)],
    fext: Option<usize>,
) -> DimensionError {
    let mut checks = vec![("q", model.nq, q)];
    checks.extend(vs.iter().map(|&(n, len)| (n, model.nv, len)));
    checks.extend(fext.map(|len| ("fext", model.nbodies, len)));
    checks
        .into_iter()
        .find_map(|(arg, expected, got)| DimensionError::check(arg, expected, got).err())
        .unwrap_or(DimensionError {
            arg: "q",
            expected: model.nq,
            got: q,
        })
}

/// Forward dynamics is undefined where a moving joint carries no mass (H is
/// singular whatever the state): the error names the first such joint.
pub(crate) fn check_massless<T: Scalar>(model: &Model<T>) -> Result<(), DynamicsError> {
    match model.massless_joints.first() {
        Some(name) => Err(DynamicsError::MasslessJoint(name.clone())),
        None => Ok(()),
    }
}

/// The joint-space inertia matrix H(q), written to `data.h` (by [`crba`]).
pub fn mass_matrix<'d, T: Scalar>(
    model: &Model<T>,
    data: &'d mut Data<T>,
    q: &DVector<T>,
) -> Result<&'d nalgebra::DMatrix<T>, DynamicsError> {
    crba(model, data, q)
}

/// Forward dynamics through H: `C` by RNEA (docs/theory.md §"Bias forces"), H by
/// [`crba`], then `H q̈ = τ − C` (docs/theory.md §"Equation of motion") by the
/// tree-sparse LTDL factorisation (docs/theory.md §"Tree-sparse LTDL")
/// ([`ltdl::ltdl`]), or, on a model with mimic joints whose `Gᵀ H G` is not
/// tree-shaped ([`dense_factor`]), the dense Cholesky. Result in `data.qdd`; `data.h` (its upper
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
    check_sizes(model, q, &[("v", v), ("tau", tau)], fext)?;
    check_massless(model)?;
    // sizes checked above: the unchecked passes
    factor_crba(model, data, q, v, fext)?;
    data.qdd.copy_from(tau);
    data.qdd -= &data.bias;
    if dense_factor(model) {
        linalg::cholesky_solve(&data.chol, &mut data.qdd);
    } else {
        ltdl::ltdl_solve(&data.chol, &model.dof_parent, &mut data.qdd);
    }
    Ok(&data.qdd)
}

/// The first half of [`forward_dynamics_crba`] (sizes checked by the caller):
/// `data.bias` = C (with the pass's body velocities and accelerations), H
/// (`data.h`) and its factor in `data.chol`, no solve.
pub(crate) fn factor_crba<T: Scalar>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &DVector<T>,
    v: &DVector<T>,
    fext: Option<&[Force<T>]>,
) -> Result<(), DynamicsError> {
    if dense_factor(model) {
        bias_and_crba(model, data, q, v, fext);
        linalg::cholesky(&data.h, &mut data.chol).map_err(DynamicsError::Singular)
    } else {
        let placed = bias_and_crba_factor(model, data, q, v, fext);
        ltdl::factor_placed(&data.h, &model.dof_parent, &mut data.chol, placed)
            .map_err(DynamicsError::Singular)
    }
}

/// [`bias_and_crba`] that, where the local-frame CRBA runs, also leaves H's
/// tree-pattern entries in `data.chol`'s upper triangle (returns true; the
/// tree-sparse LTDL then starts there, [`ltdl::factor_placed`]).
pub(crate) fn bias_and_crba_factor<T: Scalar>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &DVector<T>,
    v: &DVector<T>,
    fext: Option<&[Force<T>]>,
) -> bool {
    rnea::bias_pass(model, data, q, v, fext);
    if crba::crba_at_placements_factor(model, data) {
        return true;
    }
    crba::crba_dispatch(model, data, q, model.has_mimic);
    false
}

/// `data.bias` = C (with the pass's body velocities, accelerations and joint
/// placements) and H (`data.h`, the upper triangle at least): [`factor_crba`]
/// without the factor.
pub(crate) fn bias_and_crba<T: Scalar>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &DVector<T>,
    v: &DVector<T>,
    fext: Option<&[Force<T>]>,
) {
    rnea::bias_pass(model, data, q, v, fext);
    // the bias pass left the joint placements at q: the local-frame CRBA reads
    // them (no second sin/cos and transform per joint) where it runs; LTDL
    // reads H's upper triangle only (mirrored for the dense Cholesky)
    if !crba::crba_at_placements(model, data) {
        crba::crba_dispatch(model, data, q, model.has_mimic);
    }
}

/// Whether [`forward_dynamics_crba`] factorises H densely (Cholesky) rather
/// than by the tree-sparse LTDL: only with mimic joints whose reduced H leaves
/// the tree pattern ([`crate::model::Topology::mimic_tree`]).
#[inline]
pub(crate) fn dense_factor<T: Scalar>(model: &Model<T>) -> bool {
    model.has_mimic && !model.topology.mimic_tree
}

/// Solves `H X = B` for `m` right-hand sides stored coordinate-major (row k
/// of X at `x[k m..(k + 1) m]`) with the factor [`forward_dynamics_crba`] left
/// in `data.chol`: dense Cholesky or tree-sparse LTDL as [`dense_factor`] says.
pub(crate) fn factor_solve_rows<T: Scalar>(
    model: &Model<T>,
    data: &Data<T>,
    m: usize,
    x: &mut [T],
) {
    if dense_factor(model) {
        linalg::cholesky_solve_rows(&data.chol, m, x);
    } else {
        ltdl::ltdl_solve_rows(&data.chol, &model.dof_parent, m, x);
    }
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
