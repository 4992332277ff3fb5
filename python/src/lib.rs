//! `urdyn._urdyn`: the Python face of the urdyn engine (PyO3 + rust-numpy).
//!
//! A thin layer: every number is computed by the Rust library; this file only
//! checks and converts arguments (one-line `ValueError`s naming the argument),
//! releases the GIL around batches and lays results out in numpy arrays. The
//! names are fixed by `shared/spec/python.md` (Pinocchio's where it has one).

mod args;
mod constraints;
mod contacts;
mod control;
mod derivatives;
mod dynamics;
mod introspect;
mod mjcf;
mod model;
mod pinocchio;
mod pool;
mod prototype;
mod rollout;
mod scene;
mod sim;
mod view;

use pyo3::prelude::*;

pyo3::create_exception!(
    urdyn,
    SimulationError,
    pyo3::exceptions::PyRuntimeError,
    "A simulation that diverged or turned non-finite. From `rollout`, `.q` and `.v` \
     hold the partial results (NaN after the failure) and `.index` the batch index."
);

/// The extension module.
#[pymodule]
fn _urdyn(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<model::PyModel>()?;
    m.add_class::<model::PyData>()?;
    m.add_class::<sim::PySimulation>()?;
    m.add_class::<scene::PyScene>()?;
    m.add_function(wrap_pyfunction!(scene::_scene_from_state, m)?)?;
    m.add_function(wrap_pyfunction!(scene::_scene_model_from_state, m)?)?;
    m.add("SimulationError", m.py().get_type::<SimulationError>())?;
    m.add_function(wrap_pyfunction!(model::_model_from_state, m)?)?;
    m.add_function(wrap_pyfunction!(pinocchio::to_pinocchio_q, m)?)?;
    m.add_function(wrap_pyfunction!(pinocchio::from_pinocchio_q, m)?)?;
    dynamics::register(m)?;
    derivatives::register(m)?;
    constraints::register(m)?;
    mjcf::register(m)?;
    m.add_function(wrap_pyfunction!(rollout::rollout, m)?)?;
    m.add_function(wrap_pyfunction!(view::write_html, m)?)?;
    m.add_function(wrap_pyfunction!(sim::integrators, m)?)?;
    m.add_function(wrap_pyfunction!(sim::linearize, m)?)?;
    Ok(())
}
