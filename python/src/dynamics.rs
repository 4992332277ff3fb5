//! The dynamics and kinematics functions (Pinocchio's names where it has one):
//! each checks its arguments, calls the library, and returns new arrays.

use crate::args::{read_vec, value_error};
use crate::model::{PyData, PyModel};
use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use urdyn::dynamics::{self, DynamicsError, Reference};
use urdyn::model::FrameId;
use urdyn::nalgebra::DMatrix;

/// Registers this file's functions.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(rnea, m)?)?;
    m.add_function(wrap_pyfunction!(nonlinear_effects, m)?)?;
    m.add_function(wrap_pyfunction!(crba, m)?)?;
    m.add_function(wrap_pyfunction!(aba, m)?)?;
    m.add_function(wrap_pyfunction!(forward_dynamics, m)?)?;
    m.add_function(wrap_pyfunction!(forward_dynamics_rnea, m)?)?;
    m.add_function(wrap_pyfunction!(frame_placement, m)?)?;
    m.add_function(wrap_pyfunction!(frame_jacobian, m)?)?;
    m.add_function(wrap_pyfunction!(frame_velocity, m)?)?;
    m.add_function(wrap_pyfunction!(center_of_mass, m)?)?;
    m.add_function(wrap_pyfunction!(center_of_mass_jacobian, m)?)?;
    m.add_function(wrap_pyfunction!(centroidal_momentum, m)?)?;
    m.add_function(wrap_pyfunction!(kinetic_energy, m)?)?;
    m.add_function(wrap_pyfunction!(potential_energy, m)?)?;
    Ok(())
}

pub(crate) fn dyn_error(model: &PyModel, e: DynamicsError) -> PyErr {
    match e {
        DynamicsError::Mimic => {
            let name = model
                .model
                .joints
                .iter()
                .enumerate()
                .skip(1)
                // a mimic joint shares its leader's velocity coordinate
                .find(|&(b, j)| model.model.joints[1..b].iter().any(|o| o.iv == j.iv))
                .map(|(b, _)| b)
                .and_then(|b| model.model.body_joint_names.get(b).cloned())
                .unwrap_or_default();
            value_error(format!(
                "{}: the articulated-body algorithm cannot handle mimic joints (joint \"{name}\"); use forward_dynamics",
                model.file
            ))
        }
        e => value_error(format!("{}: {e}", model.file)),
    }
}

/// q into the workspace's q, checked.
pub(crate) fn read_q(d: &mut PyData, q: &Bound<'_, PyAny>) -> PyResult<()> {
    d.read_q(q)
}

/// The prologue of every call at a state: `data` checked against `model`, q into
/// `d.q` (every quaternion checked, [`read_q`]), v into `d.v`.
pub(crate) fn read_qv(
    model: &PyModel,
    d: &mut PyData,
    q: &Bound<'_, PyAny>,
    v: &Bound<'_, PyAny>,
) -> PyResult<()> {
    d.check(&model.model)?;
    read_q(d, q)?;
    read_vec(v, "v", "nv", &mut d.v)
}

/// [`read_qv`] and a third nv vector (`a` or `tau`, named `name`) into `d.a`.
pub(crate) fn read_qvx(
    model: &PyModel,
    d: &mut PyData,
    q: &Bound<'_, PyAny>,
    v: &Bound<'_, PyAny>,
    x: &Bound<'_, PyAny>,
    name: &str,
) -> PyResult<()> {
    read_qv(model, d, q, v)?;
    read_vec(x, name, "nv", &mut d.a)
}

/// The optional `fext` dict as per-body forces in `d.fext` (kinematics at `d.q`
/// computed first); `false` when there is none.
fn read_fext(m: &PyModel, d: &mut PyData, fext: Option<&Bound<'_, PyDict>>) -> PyResult<bool> {
    match fext {
        Some(f) if !f.is_empty() => {
            dynamics::forward_kinematics(&m.model, &mut d.data, &d.q)
                .map_err(|e| dyn_error(m, e))?;
            let PyData { data, fext, .. } = d;
            m.fext(f, data, fext)?;
            Ok(true)
        }
        _ => Ok(false),
    }
}

fn vec_out<'py>(py: Python<'py>, x: &[f64]) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_slice(py, x)
}

pub(crate) fn mat_out<'py>(py: Python<'py>, m: &DMatrix<f64>) -> Bound<'py, PyArray2<f64>> {
    let (r, c) = m.shape();
    let a = unsafe { PyArray2::<f64>::new(py, [r, c], false) };
    // SAFETY: a fresh C-contiguous array of r·c entries, not shared yet
    let s = unsafe { a.as_slice_mut() }.expect("fresh contiguous array");
    for i in 0..r {
        for j in 0..c {
            s[i * c + j] = m[(i, j)];
        }
    }
    a
}

/// Inverse dynamics: the generalized forces that produce `a` at (q, v), with
/// optional external wrenches `fext` {link: (force3, torque3)} (world frame, at
/// the link origins).
#[pyfunction]
#[pyo3(signature = (model, data, q, v, a, fext=None))]
pub fn rnea<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
    a: &Bound<'py, PyAny>,
    fext: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let d = &mut *data;
    read_qvx(&model, d, q, v, a, "a")?;
    let has = read_fext(&model, d, fext)?;
    let f = has.then_some(&d.fext[..]);
    let mut tau = dynamics::rnea(&model.model, &mut d.data, &d.q, &d.v, &d.a, f)
        .map_err(|e| dyn_error(&model, e))?
        .clone();
    // an MJCF joint's armature is in H (MuJoCo's qM), as eval: τ + A a
    if let Some(arm) = model.model.armature() {
        tau += arm.component_mul(&d.a);
    }
    Ok(vec_out(py, tau.as_slice()))
}

/// C(q, v): Coriolis, centrifugal and gravity forces (and `fext`), i.e. inverse
/// dynamics with a = 0.
#[pyfunction]
#[pyo3(signature = (model, data, q, v, fext=None))]
pub fn nonlinear_effects<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
    fext: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let d = &mut *data;
    read_qv(&model, d, q, v)?;
    let has = read_fext(&model, d, fext)?;
    let f = has.then_some(&d.fext[..]);
    let c = dynamics::bias(&model.model, &mut d.data, &d.q, &d.v, f)
        .map_err(|e| dyn_error(&model, e))?;
    Ok(vec_out(py, c.as_slice()))
}

/// The joint-space inertia matrix H(q), the whole symmetric matrix.
#[pyfunction]
pub fn crba<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let d = &mut *data;
    d.check(&model.model)?;
    read_q(d, q)?;
    let mut h = dynamics::crba(&model.model, &mut d.data, &d.q)
        .map_err(|e| dyn_error(&model, e))?
        .clone();
    // an MJCF joint's armature is in H (MuJoCo's qM), as eval: H + A
    if let Some(arm) = model.model.armature() {
        for k in 0..arm.len() {
            h[(k, k)] += arm[k];
        }
    }
    Ok(mat_out(py, &h))
}

/// The three forward-dynamics entry points differ only in the algorithm.
#[derive(Clone, Copy)]
enum Fd {
    Aba,
    Fastest,
    Rnea,
}

#[allow(clippy::too_many_arguments)]
fn forward<'py>(
    py: Python<'py>,
    model: &PyModel,
    d: &mut PyData,
    q: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
    tau: &Bound<'py, PyAny>,
    fext: Option<&Bound<'py, PyDict>>,
    algo: Fd,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    read_qvx(model, d, q, v, tau, "tau")?;
    let has = read_fext(model, d, fext)?;
    let f = has.then_some(&d.fext[..]);
    let m = &model.model;
    if let Some(arm) = m.armature() {
        // an MJCF joint's armature is in H (MuJoCo's qM), as eval: whichever
        // algorithm, q̈ = (H + A)⁻¹ (τ − C) by H + A's Cholesky factor
        let mut h = dynamics::crba(m, &mut d.data, &d.q)
            .map_err(|e| dyn_error(model, e))?
            .clone();
        for k in 0..arm.len() {
            h[(k, k)] += arm[k];
        }
        let bias = dynamics::bias(m, &mut d.data, &d.q, &d.v, f)
            .map_err(|e| dyn_error(model, e))?
            .clone();
        if let Err(k) = dynamics::linalg::cholesky(&h, &mut d.data.chol) {
            return Err(dyn_error(model, DynamicsError::Singular(k)));
        }
        let mut x = &d.a - &bias;
        dynamics::linalg::cholesky_solve(&d.data.chol, &mut x);
        return Ok(vec_out(py, x.as_slice()));
    }
    let r = match algo {
        Fd::Aba => dynamics::aba(m, &mut d.data, &d.q, &d.v, &d.a, f),
        Fd::Fastest => dynamics::forward_dynamics(m, &mut d.data, &d.q, &d.v, &d.a, f),
        Fd::Rnea => dynamics::forward_dynamics_rnea(m, &mut d.data, &d.q, &d.v, &d.a, f),
    };
    let qdd = r.map_err(|e| dyn_error(model, e))?;
    Ok(vec_out(py, qdd.as_slice()))
}

/// Forward dynamics by the articulated-body algorithm (a model with mimic
/// joints raises ValueError: use `forward_dynamics`).
#[pyfunction]
#[pyo3(signature = (model, data, q, v, tau, fext=None))]
pub fn aba<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
    tau: &Bound<'py, PyAny>,
    fext: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    forward(py, &model, &mut data, q, v, tau, fext, Fd::Aba)
}

/// Forward dynamics by the engine's fastest method for this model.
#[pyfunction]
#[pyo3(signature = (model, data, q, v, tau, fext=None))]
pub fn forward_dynamics<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
    tau: &Bound<'py, PyAny>,
    fext: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    forward(py, &model, &mut data, q, v, tau, fext, Fd::Fastest)
}

/// Forward dynamics by the course note's n + 1 inverse-dynamics calls (the
/// reference method).
#[pyfunction]
pub fn forward_dynamics_rnea<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
    tau: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    forward(py, &model, &mut data, q, v, tau, None, Fd::Rnea)
}

/// World pose of a link frame (kinematics at `d.q` computed here).
fn link_pose(model: &PyModel, d: &mut PyData, link: usize) -> PyResult<urdyn::spatial::Se3<f64>> {
    let m = &model.model;
    dynamics::forward_kinematics(m, &mut d.data, &d.q).map_err(|e| dyn_error(model, e))?;
    dynamics::frame_placement(m, &d.data, FrameId(link)).map_err(|e| dyn_error(model, e))
}

/// The 4×4 homogeneous world pose of URDF link `link` at q.
#[pyfunction]
pub fn frame_placement<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: &Bound<'py, PyAny>,
    #[pyo3(from_py_with = crate::args::named::link)] link: String,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let d = &mut *data;
    d.check(&model.model)?;
    read_q(d, q)?;
    let i = model.link(&link, "link")?;
    let x = link_pose(&model, d, i)?;
    let mut m = DMatrix::identity(4, 4);
    for r in 0..3 {
        for c in 0..3 {
            m[(r, c)] = x.rot[(r, c)];
        }
        m[(r, 3)] = x.trans[r];
    }
    Ok(mat_out(py, &m))
}

/// The reference of a Jacobian's rows.
pub(crate) fn reference(s: &str) -> PyResult<Reference> {
    match s {
        "world_aligned" => Ok(Reference::WorldAligned),
        "local" => Ok(Reference::Local),
        _ => Err(value_error(format!(
            "reference: \"{s}\" is neither \"world_aligned\" nor \"local\""
        ))),
    }
}

/// The 6 × nv Jacobian of link `link` at q into `j`: rows linear velocity of
/// its origin then angular velocity, world-aligned or in the link's frame.
fn jacobian(
    model: &PyModel,
    d: &mut PyData,
    link: usize,
    reference: Reference,
) -> PyResult<DMatrix<f64>> {
    let m = &model.model;
    dynamics::forward_kinematics(m, &mut d.data, &d.q).map_err(|e| dyn_error(model, e))?;
    let mut j = DMatrix::zeros(6, m.nv);
    dynamics::frame_jacobian(m, &d.data, FrameId(link), reference, &mut j)
        .map_err(|e| dyn_error(model, e))?;
    Ok(j)
}

/// The 6 × nv Jacobian of URDF link `link` at q; `reference` "world_aligned"
/// (the contract's `jacobian`) or "local" (`jacobian_local`).
#[pyfunction]
#[pyo3(
    signature = (model, data, q, link, reference=String::from("world_aligned")),
    text_signature = "(model, data, q, link, reference='world_aligned')"
)]
pub fn frame_jacobian<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: &Bound<'py, PyAny>,
    #[pyo3(from_py_with = crate::args::named::link)] link: String,
    #[pyo3(from_py_with = crate::args::named::reference)] reference: String,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let local = self::reference(&reference)?;
    let d = &mut *data;
    d.check(&model.model)?;
    read_q(d, q)?;
    let i = model.link(&link, "link")?;
    let j = jacobian(&model, d, i, local)?;
    Ok(mat_out(py, &j))
}

/// The 6-vector [linear velocity of the link origin; angular velocity] of URDF
/// link `link` at (q, v), world-aligned or local.
#[pyfunction]
#[pyo3(
    signature = (model, data, q, v, link, reference=String::from("world_aligned")),
    text_signature = "(model, data, q, v, link, reference='world_aligned')"
)]
pub fn frame_velocity<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
    #[pyo3(from_py_with = crate::args::named::link)] link: String,
    #[pyo3(from_py_with = crate::args::named::reference)] reference: String,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let local = self::reference(&reference)?;
    let d = &mut *data;
    read_qv(&model, d, q, v)?;
    let i = model.link(&link, "link")?;
    let j = jacobian(&model, d, i, local)?;
    let vel = j * &d.v;
    Ok(vec_out(py, vel.as_slice()))
}

/// Centre of mass of the links that move, world frame.
#[pyfunction]
pub fn center_of_mass<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let d = &mut *data;
    d.check(&model.model)?;
    read_q(d, q)?;
    dynamics::forward_kinematics(&model.model, &mut d.data, &d.q)
        .map_err(|e| dyn_error(&model, e))?;
    let c = dynamics::center_of_mass(&model.model, &d.data);
    Ok(vec_out(py, c.as_slice()))
}

/// The 3 × nv Jacobian of the centre of mass of the links that move
/// (`urdyn::dynamics::center_of_mass_jacobian`).
#[pyfunction]
pub fn center_of_mass_jacobian<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let d = &mut *data;
    d.check(&model.model)?;
    read_q(d, q)?;
    let m = &model.model;
    dynamics::forward_kinematics(m, &mut d.data, &d.q).map_err(|e| dyn_error(&model, e))?;
    let mut j = DMatrix::zeros(3, m.nv);
    dynamics::center_of_mass_jacobian(m, &d.data, &mut j).map_err(|e| dyn_error(&model, e))?;
    Ok(mat_out(py, &j))
}

/// The centroidal momentum of the links that move: [linear; angular about the
/// centre of mass], world frame.
#[pyfunction]
pub fn centroidal_momentum<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let d = &mut *data;
    read_qv(&model, d, q, v)?;
    let (k, l) = dynamics::centroidal_momentum(&model.model, &mut d.data, &d.q, &d.v)
        .map_err(|e| dyn_error(&model, e))?;
    Ok(vec_out(py, &[l.x, l.y, l.z, k.x, k.y, k.z]))
}

/// Kinetic energy ½ vᵀ H v of the links that move (J).
#[pyfunction]
pub fn kinetic_energy(
    model: PyRef<'_, PyModel>,
    mut data: PyRefMut<'_, PyData>,
    q: &Bound<'_, PyAny>,
    v: &Bound<'_, PyAny>,
) -> PyResult<f64> {
    let d = &mut *data;
    read_qv(&model, d, q, v)?;
    dynamics::kinetic_energy(&model.model, &mut d.data, &d.q, &d.v)
        .map_err(|e| dyn_error(&model, e))
}

/// Gravitational potential energy −Σ mᵢ gᵀcᵢ of the links that move (J).
#[pyfunction]
pub fn potential_energy(
    model: PyRef<'_, PyModel>,
    mut data: PyRefMut<'_, PyData>,
    q: &Bound<'_, PyAny>,
) -> PyResult<f64> {
    let d = &mut *data;
    d.check(&model.model)?;
    read_q(d, q)?;
    dynamics::forward_kinematics(&model.model, &mut d.data, &d.q)
        .map_err(|e| dyn_error(&model, e))?;
    Ok(dynamics::potential_energy(&model.model, &d.data))
}
