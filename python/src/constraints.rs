//! Loop constraints (mechanisms.md §"Python"): `urdyn.Constraints(model, [dicts])`
//! and the constrained algorithms `constraint_dynamics`, its derivatives,
//! `constraint_jacobian` and `constraint_violation`, as eval's `"constrained"`
//! block computes them (src/cli/eval_constrained.rs): held world anchors placed
//! where side 1 is at the state's q, then the library's functions.

use crate::args::{read_vec, value_error};
use crate::dynamics::{dyn_error, mat_out, read_q, read_qv};
use crate::model::{PyData, PyModel};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use urdyn::dynamics::{self, ConstraintData, ConstraintDynamicsError, LinkWrench};
use urdyn::model::{Constraints, FrameId};
use urdyn::nalgebra::{DMatrix, Vector3};

/// Registers this file's class and functions.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyConstraints>()?;
    m.add_function(wrap_pyfunction!(constraint_dynamics, m)?)?;
    m.add_function(wrap_pyfunction!(constraint_dynamics_derivatives, m)?)?;
    m.add_function(wrap_pyfunction!(constraint_jacobian, m)?)?;
    m.add_function(wrap_pyfunction!(constraint_violation, m)?)?;
    Ok(())
}

/// A checked set of loop constraints for one model: `Constraints(model,
/// [{"kind": "point", "link1": …}, …])`, the JSON objects of mechanisms.md as
/// dicts. A bad entry is a `ValueError` with the library's one line
/// (`constraints[K].KEY: …`).
#[pyclass(name = "Constraints", module = "urdyn")]
#[derive(Clone)]
pub struct PyConstraints {
    pub constraints: Constraints,
    /// The model's shape (nq, nv, bodies) it was made for.
    shape: (usize, usize, usize),
}

#[pymethods]
impl PyConstraints {
    #[new]
    fn new(model: PyRef<'_, PyModel>, items: &Bound<'_, PyAny>) -> PyResult<Self> {
        Self::build(&model, items)
    }
    /// The constraints' names, in order.
    #[getter]
    fn names(&self) -> Vec<String> {
        self.constraints
            .items
            .iter()
            .map(|c| c.name.clone())
            .collect()
    }
    /// The number of rows of J_c (point 3, frame 6, joint 1 each).
    #[getter]
    fn rows(&self) -> usize {
        self.constraints.rows()
    }
    fn __len__(&self) -> usize {
        self.constraints.items.len()
    }
    fn __repr__(&self) -> String {
        format!(
            "urdyn.Constraints({:?}, rows={})",
            self.names(),
            self.constraints.rows()
        )
    }
}

impl PyConstraints {
    /// The set of the JSON objects `items` (a list of dicts) for `model`.
    pub(crate) fn build(model: &PyModel, items: &Bound<'_, PyAny>) -> PyResult<Self> {
        let py = items.py();
        let text: String = py
            .import("json")?
            .call_method1("dumps", (items,))
            .and_then(|t| t.extract())
            .map_err(|e| {
                value_error(format!(
                    "constraints: expected a list of dicts of numbers and strings ({e})"
                ))
            })?;
        let v: serde_json::Value = serde_json::from_str(&text)
            .map_err(|e| value_error(format!("constraints: not JSON-like ({e})")))?;
        let m = &model.model;
        let constraints = Constraints::from_value(m, &v)
            .map_err(|e| value_error(format!("{}: {e}", model.file)))?;
        Ok(Self {
            constraints,
            shape: (m.nq, m.nv, m.nbodies),
        })
    }
    /// A `ValueError` naming `arg` unless made for a model of `model`'s shape.
    pub(crate) fn check(&self, model: &PyModel, arg: &str) -> PyResult<()> {
        let m = &model.model;
        if self.shape != (m.nq, m.nv, m.nbodies) {
            return Err(value_error(format!(
                "{arg}: made for another model (nq = {}, nv = {}), this one has nq = {}, nv = {}",
                self.shape.0, self.shape.1, m.nq, m.nv
            )));
        }
        Ok(())
    }
    /// The constraints with held world anchors placed where side 1 is at q (as
    /// eval does at each state).
    fn placed(&self, model: &PyModel, d: &mut PyData) -> PyResult<Constraints> {
        let mut c = self.constraints.clone();
        if c.has_holds() {
            dynamics::forward_kinematics(&model.model, &mut d.data, &d.q)
                .map_err(|e| dyn_error(model, e))?;
            c.place_holds(&d.data);
        }
        Ok(c)
    }
}

fn cd_error(model: &PyModel, e: ConstraintDynamicsError) -> PyErr {
    match e {
        ConstraintDynamicsError::Dynamics(e) => dyn_error(model, e),
        e => value_error(format!("{}: {e}", model.file)),
    }
}

/// The wrenches `{link: (force3, torque3)}` (world, at the link origins).
fn wrenches(model: &PyModel, fext: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<LinkWrench>> {
    let mut out = Vec::new();
    if let Some(dict) = fext {
        for (key, value) in dict.iter() {
            let name: String = key
                .extract()
                .map_err(|_| value_error("fext: keys must be link names (str)"))?;
            let fi = model.link(&name, "fext")?;
            let pair: (Bound<'_, PyAny>, Bound<'_, PyAny>) = value.extract().map_err(|_| {
                value_error(format!("fext[\"{name}\"]: expected (force3, torque3)"))
            })?;
            let f = crate::args::read3(&pair.0, &format!("fext[\"{name}\"] force"))?;
            let t = crate::args::read3(&pair.1, &format!("fext[\"{name}\"] torque"))?;
            out.push(LinkWrench {
                frame: FrameId(fi),
                force: Vector3::from(f),
                torque: Vector3::from(t),
            });
        }
    }
    Ok(out)
}

/// The state's q, v, τ into `d` (checked), `c` checked against the model.
#[allow(clippy::too_many_arguments)]
fn read_state(
    model: &PyModel,
    d: &mut PyData,
    c: &PyConstraints,
    q: &Bound<'_, PyAny>,
    v: &Bound<'_, PyAny>,
    tau: &Bound<'_, PyAny>,
) -> PyResult<()> {
    c.check(model, "c")?;
    read_qv(model, d, q, v)?;
    read_vec(tau, "tau", "nv", &mut d.a)
}

/// Constrained forward dynamics (mechanisms.md §"Semantics"): `(qdd, lam)`,
/// q̈ (nv,) and λ (rows,) stacked in constraint order (point: force 3; frame:
/// force then torque 6; joint: the generalized force on joint1, 1), world
/// coordinates, least norm when rows are redundant; `fext` {link: (force3,
/// torque3)} world wrenches at the link origins. Held world anchors (a world
/// side without its point or frame) are placed where side 1 is at q, as eval
/// does. Inconsistent rows are a `ValueError` naming the constraints.
#[pyfunction]
#[pyo3(signature = (model, data, q, v, tau, c, fext=None))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
pub fn constraint_dynamics<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
    tau: &Bound<'py, PyAny>,
    c: PyRef<'py, PyConstraints>,
    fext: Option<&Bound<'py, PyDict>>,
) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>)> {
    let d = &mut *data;
    read_state(&model, d, &c, q, v, tau)?;
    let cons = c.placed(&model, d)?;
    let ws = wrenches(&model, fext)?;
    let m = &model.model;
    let fx = if ws.is_empty() {
        None
    } else {
        dynamics::forward_kinematics(m, &mut d.data, &d.q).map_err(|e| dyn_error(&model, e))?;
        d.fext
            .iter_mut()
            .for_each(|f| *f = urdyn::spatial::Force::zero());
        for w in &ws {
            dynamics::add_link_wrench(m, &d.data, w.frame, &w.force, &w.torque, &mut d.fext)
                .map_err(|e| dyn_error(&model, e))?;
        }
        Some(d.fext.as_slice())
    };
    let mut cd = ConstraintData::new(m, &cons);
    dynamics::constraint_dynamics(m, &mut d.data, &mut cd, &cons, &d.q, &d.v, &d.a, fx)
        .map_err(|e| cd_error(&model, e))?;
    Ok((
        PyArray1::from_slice(py, cd.qdd.as_slice()),
        PyArray1::from_slice(py, cd.lambda.as_slice()),
    ))
}

/// The derivatives of [`constraint_dynamics`]: `(dqdd_dq, dqdd_dv, dqdd_dtau)`,
/// each (nv, nv), ∂q̈/∂q in the tangent space (eval-contract.md
/// "Derivatives"); `fext` wrenches held fixed in world coordinates at their link
/// origins.
#[pyfunction]
#[pyo3(signature = (model, data, q, v, tau, c, fext=None))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
pub fn constraint_dynamics_derivatives<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
    tau: &Bound<'py, PyAny>,
    c: PyRef<'py, PyConstraints>,
    fext: Option<&Bound<'py, PyDict>>,
) -> PyResult<(
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
)> {
    let d = &mut *data;
    read_state(&model, d, &c, q, v, tau)?;
    let cons = c.placed(&model, d)?;
    let ws = wrenches(&model, fext)?;
    let m = &model.model;
    let w = (!ws.is_empty()).then_some(ws.as_slice());
    let mut cd = ConstraintData::new(m, &cons);
    dynamics::constraint_dynamics_derivatives(m, &mut d.data, &mut cd, &cons, &d.q, &d.v, &d.a, w)
        .map_err(|e| cd_error(&model, e))?;
    Ok((
        mat_out(py, &cd.dqdd_dq),
        mat_out(py, &cd.dqdd_dv),
        mat_out(py, &cd.dqdd_dtau),
    ))
}

/// J_c at q: (rows, nv), columns as v (the rows of [`constraint_dynamics`]).
#[pyfunction]
pub fn constraint_jacobian<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: &Bound<'py, PyAny>,
    c: PyRef<'py, PyConstraints>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let d = &mut *data;
    c.check(&model, "c")?;
    d.check(&model.model)?;
    read_q(d, q)?;
    let cons = c.placed(&model, d)?;
    let mut out = DMatrix::zeros(cons.rows(), model.model.nv);
    dynamics::constraint_jacobian(&model.model, &mut d.data, &cons, &d.q, &mut out)
        .map_err(|e| dyn_error(&model, e))?;
    Ok(mat_out(py, &out))
}

/// Each constraint's violation at q, as eval's (mechanisms.md: m for `point`;
/// the larger of the distance in m and the angle in rad for `frame`; the signed
/// residual q₁ − ratio · q₂ − offset for `joint`): (len(c),). A held world
/// anchor is placed at q, so its violation is 0.
#[pyfunction]
pub fn constraint_violation<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: &Bound<'py, PyAny>,
    c: PyRef<'py, PyConstraints>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let d = &mut *data;
    c.check(&model, "c")?;
    d.check(&model.model)?;
    read_q(d, q)?;
    let cons = c.placed(&model, d)?;
    let mut out = vec![0.0; cons.items.len()];
    dynamics::constraint_violation(&model.model, &mut d.data, &cons, &d.q, &mut out)
        .map_err(|e| dyn_error(&model, e))?;
    Ok(PyArray1::from_vec(py, out))
}

/// `sim.constraint_forces()`: each constraint's force in the last step (λ/Δt,
/// world), `{name: {"force": (3,), "torque": (3,)}}` for `point` (torque 0) and
/// `frame` (on link1 at its point or frame origin; on link2 the opposite), a
/// `joint` constraint's generalized force on joint1 as `{"torque": x}`
/// (revolute, continuous) or `{"force": x}` (prismatic). An inactive
/// constraint's is zero.
pub(crate) fn forces_dict<'py>(
    py: Python<'py>,
    sim: &urdyn::sim::Simulation,
) -> PyResult<Bound<'py, PyDict>> {
    use urdyn::model::ConstraintKind;
    let out = PyDict::new(py);
    let Some(set) = sim.constraints() else {
        return Ok(out);
    };
    for (c, f) in set.items.iter().zip(sim.constraint_forces()) {
        let d = PyDict::new(py);
        match c.kind {
            ConstraintKind::Joint { prismatic, .. } => {
                d.set_item(if prismatic { "force" } else { "torque" }, f.generalized)?;
            }
            _ => {
                d.set_item("force", PyArray1::from_slice(py, f.force.as_slice()))?;
                d.set_item("torque", PyArray1::from_slice(py, f.torque.as_slice()))?;
            }
        }
        out.set_item(&c.name, d)?;
    }
    Ok(out)
}

/// `sim.set_constraint_active(name, on)`'s arguments: a constraint of the run
/// (`name`, a `ValueError` naming the nearest otherwise) and a bool (`on`).
pub(crate) fn read_switch(
    sim: &urdyn::sim::Simulation,
    name: &Bound<'_, PyAny>,
    on: &Bound<'_, PyAny>,
) -> PyResult<(String, bool)> {
    let name: String = name.extract().map_err(|_| {
        value_error(format!(
            "name: expected a constraint's name (str), got {}",
            name.repr().map(|r| r.to_string()).unwrap_or_default()
        ))
    })?;
    let names: Vec<&str> = sim
        .constraints()
        .map(|s| s.items.iter().map(|c| c.name.as_str()).collect())
        .unwrap_or_default();
    if !names.contains(&name.as_str()) {
        let near = urdyn::model::nearest(&name, names.iter().copied())
            .map(|k| format!(" (nearest: \"{k}\")"))
            .unwrap_or_else(|| " (the simulation has no loop constraints)".into());
        return Err(value_error(format!(
            "name: no constraint named \"{name}\"{near}"
        )));
    }
    // True/False (numpy's bool_ too), not a number or a string
    let is_bool = on.is_instance_of::<pyo3::types::PyBool>()
        || on
            .get_type()
            .name()
            .map(|n| n == "bool" || n == "bool_")
            .unwrap_or(false);
    let value = if is_bool { on.is_truthy().ok() } else { None };
    let on = value.ok_or_else(|| {
        value_error(format!(
            "on: expected True or False, got {}",
            on.repr().map(|r| r.to_string()).unwrap_or_default()
        ))
    })?;
    Ok((name, on))
}
