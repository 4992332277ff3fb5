//! The dynamics algorithms of [`crate::dynamics`] for `f64`, compiled once inside
//! urdyn. Rust's release builds do not share generic instantiations between crates:
//! every binary that calls the generic `dynamics::aba::<f64>` (a test binary, an
//! example, a program using urdyn) compiles and optimises the engine's algorithm
//! again. These are plain functions (same names, the signatures of their generic twins
//! with `T = f64`, each calling its twin: the same results), already compiled in the
//! library; a binary calling them only links them. Every other item of
//! [`crate::dynamics`] is re-exported unchanged, so `use urdyn::dynamics_f64 as
//! dynamics;` serves code written for `urdyn::dynamics` on `f64` models.

pub use crate::dynamics::*;

use crate::dynamics as generic;
use crate::model::{Data, FrameId, Model};
use crate::spatial::{Force, Motion, Se3};
use nalgebra::{DMatrix, DVector, Vector3};

type R<X> = Result<X, DynamicsError>;

/// [`crate::dynamics::aba`] for `f64`.
#[inline(never)]
pub fn aba<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &DVector<f64>,
    v: &DVector<f64>,
    tau: &DVector<f64>,
    fext: Option<&[Force<f64>]>,
) -> R<&'d DVector<f64>> {
    generic::aba(model, data, q, v, tau, fext)
}

/// [`crate::dynamics::aba_derivatives`] for `f64`.
#[inline(never)]
pub fn aba_derivatives(
    model: &Model,
    data: &mut Data,
    q: &DVector<f64>,
    v: &DVector<f64>,
    tau: &DVector<f64>,
    fext: Option<&[LinkWrench<f64>]>,
) -> R<()> {
    generic::aba_derivatives(model, data, q, v, tau, fext)
}

/// [`crate::dynamics::rnea`] for `f64`.
#[inline(never)]
pub fn rnea<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &DVector<f64>,
    v: &DVector<f64>,
    a: &DVector<f64>,
    fext: Option<&[Force<f64>]>,
) -> R<&'d DVector<f64>> {
    generic::rnea(model, data, q, v, a, fext)
}

/// [`crate::dynamics::bias`] for `f64`.
#[inline(never)]
pub fn bias<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &DVector<f64>,
    v: &DVector<f64>,
    fext: Option<&[Force<f64>]>,
) -> R<&'d DVector<f64>> {
    generic::bias(model, data, q, v, fext)
}

/// [`crate::dynamics::rnea_derivatives`] for `f64`.
#[inline(never)]
pub fn rnea_derivatives(
    model: &Model,
    data: &mut Data,
    q: &DVector<f64>,
    v: &DVector<f64>,
    a: &DVector<f64>,
    fext: Option<&[LinkWrench<f64>]>,
) -> R<()> {
    generic::rnea_derivatives(model, data, q, v, a, fext)
}

/// [`crate::dynamics::crba`] for `f64`.
#[inline(never)]
pub fn crba<'d>(model: &Model, data: &'d mut Data, q: &DVector<f64>) -> R<&'d DMatrix<f64>> {
    generic::crba(model, data, q)
}

/// [`crate::dynamics::crba_upper`] for `f64`.
#[inline(never)]
pub fn crba_upper<'d>(model: &Model, data: &'d mut Data, q: &DVector<f64>) -> R<&'d DMatrix<f64>> {
    generic::crba_upper(model, data, q)
}

/// [`crate::dynamics::mass_matrix`] for `f64`.
#[inline(never)]
pub fn mass_matrix<'d>(model: &Model, data: &'d mut Data, q: &DVector<f64>) -> R<&'d DMatrix<f64>> {
    generic::mass_matrix(model, data, q)
}

/// [`crate::dynamics::mass_matrix_rnea`] for `f64`.
#[inline(never)]
pub fn mass_matrix_rnea(model: &Model, data: &mut Data, q: &DVector<f64>) -> R<()> {
    generic::mass_matrix_rnea(model, data, q)
}

/// [`crate::dynamics::forward_dynamics`] for `f64`.
#[inline(never)]
pub fn forward_dynamics<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &DVector<f64>,
    v: &DVector<f64>,
    tau: &DVector<f64>,
    fext: Option<&[Force<f64>]>,
) -> R<&'d DVector<f64>> {
    generic::forward_dynamics(model, data, q, v, tau, fext)
}

/// [`crate::dynamics::forward_dynamics_crba`] for `f64`.
#[inline(never)]
pub fn forward_dynamics_crba<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &DVector<f64>,
    v: &DVector<f64>,
    tau: &DVector<f64>,
    fext: Option<&[Force<f64>]>,
) -> R<&'d DVector<f64>> {
    generic::forward_dynamics_crba(model, data, q, v, tau, fext)
}

/// [`crate::dynamics::forward_dynamics_rnea`] for `f64`.
#[inline(never)]
pub fn forward_dynamics_rnea<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &DVector<f64>,
    v: &DVector<f64>,
    tau: &DVector<f64>,
    fext: Option<&[Force<f64>]>,
) -> R<&'d DVector<f64>> {
    generic::forward_dynamics_rnea(model, data, q, v, tau, fext)
}

/// [`crate::dynamics::forward_kinematics`] for `f64`.
#[inline(never)]
pub fn forward_kinematics(model: &Model, data: &mut Data, q: &DVector<f64>) -> R<()> {
    generic::forward_kinematics(model, data, q)
}

/// [`crate::dynamics::forward_kinematics_second_order`] for `f64`.
#[inline(never)]
pub fn forward_kinematics_second_order(
    model: &Model,
    data: &mut Data,
    q: &DVector<f64>,
    v: &DVector<f64>,
    a: &DVector<f64>,
) -> R<()> {
    generic::forward_kinematics_second_order(model, data, q, v, a)
}

/// [`crate::dynamics::update_frames`] for `f64`.
#[inline(never)]
pub fn update_frames(model: &Model, data: &mut Data) {
    generic::update_frames(model, data)
}

/// [`crate::dynamics::frame_placement`] for `f64`.
#[inline(never)]
pub fn frame_placement(model: &Model, data: &Data, frame: FrameId) -> R<Se3<f64>> {
    generic::frame_placement(model, data, frame)
}

/// [`crate::dynamics::frame_velocity`] for `f64`.
#[inline(never)]
pub fn frame_velocity(
    model: &Model,
    data: &Data,
    frame: FrameId,
    reference: Reference,
) -> R<Motion<f64>> {
    generic::frame_velocity(model, data, frame, reference)
}

/// [`crate::dynamics::frame_classical_acceleration`] for `f64`.
#[inline(never)]
pub fn frame_classical_acceleration(
    model: &Model,
    data: &Data,
    frame: FrameId,
    reference: Reference,
) -> R<Motion<f64>> {
    generic::frame_classical_acceleration(model, data, frame, reference)
}

/// [`crate::dynamics::frame_jacobian`] for `f64`.
#[inline(never)]
pub fn frame_jacobian(
    model: &Model,
    data: &Data,
    frame: FrameId,
    reference: Reference,
    j: &mut DMatrix<f64>,
) -> R<()> {
    generic::frame_jacobian(model, data, frame, reference, j)
}

/// [`crate::dynamics::frame_jacobian_time_variation`] for `f64`.
#[inline(never)]
pub fn frame_jacobian_time_variation(
    model: &Model,
    data: &mut Data,
    q: &DVector<f64>,
    v: &DVector<f64>,
    frame: FrameId,
    reference: Reference,
    out: &mut DMatrix<f64>,
) -> R<()> {
    generic::frame_jacobian_time_variation(model, data, q, v, frame, reference, out)
}

/// [`crate::dynamics::joint_jacobians`] for `f64`.
#[inline(never)]
pub fn joint_jacobians<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &DVector<f64>,
) -> R<&'d DMatrix<f64>> {
    generic::joint_jacobians(model, data, q)
}

/// [`crate::dynamics::centroidal_momentum`] for `f64`.
#[inline(never)]
pub fn centroidal_momentum(
    model: &Model,
    data: &mut Data,
    q: &DVector<f64>,
    v: &DVector<f64>,
) -> R<(Vector3<f64>, Vector3<f64>)> {
    generic::centroidal_momentum(model, data, q, v)
}

/// [`crate::dynamics::center_of_mass`] for `f64`.
#[inline(never)]
pub fn center_of_mass(model: &Model, data: &Data) -> Vector3<f64> {
    generic::center_of_mass(model, data)
}

/// [`crate::dynamics::center_of_mass_velocity`] for `f64`.
#[inline(never)]
pub fn center_of_mass_velocity(model: &Model, data: &Data) -> Vector3<f64> {
    generic::center_of_mass_velocity(model, data)
}

/// [`crate::dynamics::center_of_mass_jacobian`] for `f64`.
#[inline(never)]
pub fn center_of_mass_jacobian(model: &Model, data: &Data, jc: &mut DMatrix<f64>) -> R<()> {
    generic::center_of_mass_jacobian(model, data, jc)
}

/// [`crate::dynamics::kinetic_energy`] for `f64`.
#[inline(never)]
pub fn kinetic_energy(
    model: &Model,
    data: &mut Data,
    q: &DVector<f64>,
    v: &DVector<f64>,
) -> R<f64> {
    generic::kinetic_energy(model, data, q, v)
}

/// [`crate::dynamics::kinetic_energy_from_placements`] for `f64`.
#[inline(never)]
pub fn kinetic_energy_from_placements(model: &Model, data: &mut Data, v: &DVector<f64>) -> R<f64> {
    generic::kinetic_energy_from_placements(model, data, v)
}

/// [`crate::dynamics::potential_energy`] for `f64`.
#[inline(never)]
pub fn potential_energy(model: &Model, data: &Data) -> f64 {
    generic::potential_energy(model, data)
}

/// [`crate::dynamics::energies`] for `f64`.
#[inline(never)]
pub fn energies(model: &Model, q: &DVector<f64>, v: &DVector<f64>) -> R<(f64, f64)> {
    generic::energies(model, q, v)
}

/// [`crate::dynamics::add_link_wrench`] for `f64`.
#[inline(never)]
pub fn add_link_wrench(
    model: &Model,
    data: &Data,
    frame: FrameId,
    force: &Vector3<f64>,
    torque: &Vector3<f64>,
    fext: &mut [Force<f64>],
) -> R<()> {
    generic::add_link_wrench(model, data, frame, force, torque, fext)
}
