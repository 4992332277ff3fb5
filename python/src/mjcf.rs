//! MJCF models (mjcf.md §"Entry points"): `Model.from_mjcf`,
//! `Model.from_mjcf_string` (model.rs calls these), and the MuJoCo state
//! converters `from_mujoco_qpos`, `from_mujoco_qvel`, `to_mujoco_qpos`,
//! `to_mujoco_qvel` (the library's `urdyn::mjcf::*`), and a Simulation's
//! `set_controls`, `set_key`, `controls` (sim.rs's marked block).

use crate::args::{not_found_error, read_vec, value_error};
use crate::model::PyModel;
use numpy::PyArray1;
use pyo3::prelude::*;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use urdyn::nalgebra::{DVector, Vector3};
use urdyn::sim::Simulation;

/// Registers this file's functions.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(from_mujoco_qpos, m)?)?;
    m.add_function(wrap_pyfunction!(from_mujoco_qvel, m)?)?;
    m.add_function(wrap_pyfunction!(to_mujoco_qpos, m)?)?;
    m.add_function(wrap_pyfunction!(to_mujoco_qvel, m)?)?;
    m.add_function(wrap_pyfunction!(_mjcf_model_from_state, m)?)?;
    Ok(())
}

/// `Model.from_mjcf(path)`: a missing file is `FileNotFoundError`, a bad one a
/// `ValueError` with the library's line (file, element, attribute).
pub fn from_mjcf(path: PathBuf) -> PyResult<PyModel> {
    if let Err(e) = std::fs::metadata(&path) {
        let msg = format!("{}: cannot read file: {e}", path.display());
        return Err(match e.kind() {
            std::io::ErrorKind::NotFound => not_found_error(msg),
            _ => value_error(msg),
        });
    }
    let model = urdyn::mjcf::load_file(&path).map_err(|e| value_error(e.to_string()))?;
    let text = std::fs::read_to_string(&path)
        .map_err(|e| value_error(format!("{}: cannot read file: {e}", path.display())))?;
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
        .to_path_buf();
    Ok(wrap(model, text, path.display().to_string(), dir))
}

/// `Model.from_mjcf_string(xml, base_dir)`.
pub fn from_mjcf_string(xml: String, file: String, base_dir: PathBuf) -> PyResult<PyModel> {
    let model =
        urdyn::mjcf::load_str(&xml, &file, &base_dir).map_err(|e| value_error(e.to_string()))?;
    Ok(wrap(model, xml, file, base_dir))
}

fn wrap(model: urdyn::Model, text: String, file: String, dir: PathBuf) -> PyModel {
    // an MJCF file has no URDF `<inertial>`s: link_mass/link_inertia read 0
    let mut m = PyModel::from_parts(model, file, Vec::new(), None, HashMap::new());
    m.text = text;
    m.mjcf_dir = Some(dir);
    m
}

/// Rebuilds a pickled MJCF `Model`.
#[pyfunction]
pub fn _mjcf_model_from_state(
    text: String,
    file: String,
    base_dir: PathBuf,
    gravity: [f64; 3],
) -> PyResult<PyModel> {
    let mut m = from_mjcf_string(text, file, base_dir)?;
    m.model.gravity = Vector3::new(gravity[0], gravity[1], gravity[2]);
    Ok(m)
}

fn read(x: &Bound<'_, PyAny>, name: &str, what: &str, n: usize) -> PyResult<DVector<f64>> {
    let mut out = DVector::zeros(n);
    read_vec(x, name, what, &mut out)?;
    Ok(out)
}

fn out<'py>(
    py: Python<'py>,
    r: Result<DVector<f64>, urdyn::model::DimensionError>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let v = r.map_err(|e| value_error(e.to_string()))?;
    Ok(PyArray1::from_slice(py, v.as_slice()))
}

/// urdyn's q of MuJoCo's `qpos` (each ball or free joint's quaternion w-first
/// there, `[qx, qy, qz, qw]` here; every other entry copied).
#[pyfunction]
pub fn from_mujoco_qpos<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    qpos: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let m = &model.model;
    let qpos = read(qpos, "qpos", "nq", m.nq)?;
    out(py, urdyn::mjcf::from_mujoco_qpos(m, &qpos))
}

/// MuJoCo's qpos of urdyn's `q`.
#[pyfunction]
pub fn to_mujoco_qpos<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    q: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let m = &model.model;
    let q = read(q, "q", "nq", m.nq)?;
    out(py, urdyn::mjcf::to_mujoco_qpos(m, &q))
}

/// urdyn's v of MuJoCo's `qpos` and `qvel` (a free joint's linear velocity is
/// world-frame in qvel, body-frame here: v_lin = Rᵀ qvel_lin).
#[pyfunction]
pub fn from_mujoco_qvel<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    qpos: &Bound<'py, PyAny>,
    qvel: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let m = &model.model;
    let qpos = read(qpos, "qpos", "nq", m.nq)?;
    let qvel = read(qvel, "qvel", "nv", m.nv)?;
    out(py, urdyn::mjcf::from_mujoco_qvel(m, &qpos, &qvel))
}

/// MuJoCo's qvel of urdyn's `q` and `v`.
#[pyfunction]
pub fn to_mujoco_qvel<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    q: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let m = &model.model;
    let q = read(q, "q", "nq", m.nq)?;
    let v = read(v, "v", "nv", m.nv)?;
    out(py, urdyn::mjcf::to_mujoco_qvel(m, &q, &v))
}

// --- A simulation's MJCF actuators and keyframes (sim.rs's marked block calls these) ---

/// `sim.set_controls(u)`: the model's actuators' controls (nu, in the file's
/// order, each clamped into its ctrlrange), held until set again.
pub(crate) fn set_controls(sim: &mut Simulation, u: &Bound<'_, PyAny>) -> PyResult<()> {
    let u = read(u, "u", "nu", sim.model.actuators.len())?;
    sim.set_controls(&u).map_err(|e| value_error(e.to_string()))
}

/// `sim.set_key(name)`: the state and controls of the model's keyframe `name`.
pub(crate) fn set_key(sim: &mut Simulation, name: &str) -> PyResult<()> {
    sim.set_key(name).map_err(|e| value_error(e.to_string()))
}

/// The controls as last set (nu).
pub(crate) fn controls<'py>(py: Python<'py>, sim: &Simulation) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_slice(py, sim.controls().as_slice())
}

/// After `step(tau)` replaced the applied torques: the actuators' constant
/// forces added back (the controls hold across steps).
pub(crate) fn add_actuator_torques(sim: &mut Simulation) {
    if sim.model.actuators.is_empty() {
        return;
    }
    let ff = sim.actuator_torques().clone();
    *sim.torques_mut() += ff;
}

/// `reset()`: the controls stay (their servo gains came back with the others;
/// their constant forces are added to the start's torques).
pub(crate) fn keep_controls(from: &Simulation, to: &mut Simulation) -> PyResult<()> {
    if from.model.actuators.is_empty() {
        return Ok(());
    }
    to.set_controls(from.controls())
        .map_err(|e| value_error(e.to_string()))
}
