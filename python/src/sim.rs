//! `urdyn.Simulation` and `urdyn.rollout`: one simulation stepped from Python,
//! and B of them in parallel on rayon with the GIL released. Both go through
//! [`prototype`] and [`advance`], so that a rollout's states equal, bit for bit,
//! a `Simulation` stepped alone.

use crate::args::{
    normalize_base_quaternion, not_found_error, quat_offsets, read_array, read_q, read_vec,
    value_error,
};
use crate::model::PyModel;
use crate::scene::PyScene;
use crate::SimulationError;
use numpy::{PyArray1, PyArray2, PyArray3, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;
use std::path::PathBuf;
use urdyn::contact::ContactError;
use urdyn::nalgebra::DVector;
use urdyn::sim::{Integrator, SimError, SimOptions, Simulation};

/// The names `integrator=` accepts.
#[pyfunction]
pub fn integrators() -> Vec<&'static str> {
    Integrator::ALL.iter().map(|i| i.name()).collect()
}

/// A simulation of `model` at its neutral configuration, at rest, with the
/// options of `Simulation(...)` / `rollout(...)`.
fn prototype(
    model: &PyModel,
    dt: f64,
    integrator: Option<&str>,
    ground: Option<f64>,
    friction: f64,
    package_dirs: Option<Vec<PathBuf>>,
) -> PyResult<Simulation> {
    if !(dt > 0.0 && dt.is_finite()) {
        return Err(value_error(format!(
            "dt must be a positive number (got {dt})"
        )));
    }
    if !(friction >= 0.0 && friction.is_finite()) {
        return Err(value_error(format!(
            "friction must be a finite number ≥ 0 (got {friction})"
        )));
    }
    if let Some(g) = ground {
        if !g.is_finite() {
            return Err(value_error(format!(
                "ground must be a finite number (got {g})"
            )));
        }
    }
    let integrator = match integrator {
        None => None,
        Some(name) => Some(Integrator::from_name(name).ok_or_else(|| {
            value_error(format!(
                "integrator: unknown \"{name}\" (one of: {})",
                integrators().join(", ")
            ))
        })?),
    };
    let mut opts = SimOptions {
        dt,
        integrator,
        ground,
        package_paths: package_dirs.unwrap_or_else(|| model.package_dirs.clone()),
        ..SimOptions::default()
    };
    opts.contact.friction = friction;
    Simulation::new(model.model.clone(), opts).map_err(|e| match e {
        // the library's message is neutral; the hint is Python's (the CLI names its flags)
        SimError::Contact(ContactError::MissingMesh { .. }) => not_found_error(format!(
            "{}: {e} (give its package root with package_dirs=[...] or ROS_PACKAGE_PATH, or pass ground=None for no contact)",
            model.file
        )),
        e => value_error(format!("{}: {e}", model.file)),
    })
}

/// A simulation of a scene at its starting state (poses, `pose`, `initial`),
/// with its ground, friction and obstacles; the scene's constant torques.
fn prototype_scene(
    scene: &PyScene,
    dt: f64,
    integrator: Option<&str>,
    package_dirs: Option<Vec<PathBuf>>,
) -> PyResult<Simulation> {
    let s = &scene.scene;
    let model = PyModel::from_scene(scene);
    let ground = s.ground.map(|g| g.height);
    let friction = s.ground.map_or(1.0, |g| g.friction);
    let mut sim = prototype(&model, dt, integrator, ground, friction, package_dirs)?;
    sim.set_state(&s.q0, &s.v0)
        .map_err(|e| value_error(format!("{}: {e}", s.file)))?;
    sim.torques_mut().copy_from(&s.tau0);
    Ok(sim)
}

/// The simulation `Simulation(...)` / `rollout(...)` start from: of a `Model`
/// (neutral, at rest) or of a `Scene` (its ground, friction and start; the
/// `ground` and `friction` arguments are the file's then).
fn prototype_any(
    source: &Bound<'_, PyAny>,
    dt: f64,
    integrator: Option<&str>,
    ground: Option<f64>,
    friction: f64,
    package_dirs: Option<Vec<PathBuf>>,
) -> PyResult<Simulation> {
    if let Ok(scene) = source.extract::<PyRef<'_, PyScene>>() {
        return prototype_scene(&scene, dt, integrator, package_dirs);
    }
    let model = source
        .extract::<PyRef<'_, PyModel>>()
        .map_err(|_| value_error("model: expected a urdyn.Model or a urdyn.Scene".to_string()))?;
    prototype(&model, dt, integrator, ground, friction, package_dirs)
}

/// One step of `dt` of simulated time (an adaptive integrator may take several
/// steps of its own to get there; the last lands exactly).
fn advance(sim: &mut Simulation, dt: f64) -> Result<(), SimError> {
    let target = sim.time() + dt;
    while sim.time() < target {
        sim.step_until(target)?;
    }
    Ok(())
}

/// Constant joint torques (every free joint's part of `tau` ignored).
fn set_torques(sim: &mut Simulation, tau: &[f64]) {
    let free: Vec<usize> = sim.model.free_joints.iter().map(|f| f.iv).collect();
    let t = sim.torques_mut();
    for k in 0..t.len() {
        t[k] = if free.iter().any(|&iv| (iv..iv + 6).contains(&k)) {
            0.0
        } else {
            tau.get(k).copied().unwrap_or(0.0)
        };
    }
}

/// A `SimulationError` with `.q`, `.v` (and `.index`) attached.
fn sim_error(
    py: Python<'_>,
    msg: String,
    q: Py<PyAny>,
    v: Py<PyAny>,
    index: Option<usize>,
) -> PyErr {
    let err = SimulationError::new_err(msg);
    let value = err.value(py);
    let _ = value.setattr("q", q);
    let _ = value.setattr("v", v);
    let _ = value.setattr("index", index);
    err
}

/// One simulation stepped from Python (`Simulation(model, dt=1e-3, ...)`).
#[pyclass(name = "Simulation", module = "urdyn")]
pub struct PySimulation {
    sim: Simulation,
    dt: f64,
    tau: DVector<f64>,
    /// `step(tau=None)`'s torques: zero, or a scene's `initial.tau`.
    tau0: DVector<f64>,
    links: Vec<String>,
}

#[pymethods]
impl PySimulation {
    /// `ground=None`: no ground; `integrator=None`: the default for the scene
    /// (`urdyn.integrators()` lists the names).
    #[new]
    #[pyo3(signature = (model, dt=1e-3, integrator=None, ground=Some(0.0), friction=1.0, package_dirs=None))]
    fn new(
        model: &Bound<'_, PyAny>,
        dt: f64,
        integrator: Option<&str>,
        ground: Option<f64>,
        friction: f64,
        package_dirs: Option<Vec<PathBuf>>,
    ) -> PyResult<Self> {
        let sim = prototype_any(model, dt, integrator, ground, friction, package_dirs)?;
        Ok(Self {
            dt,
            tau: sim.torques().clone(),
            tau0: sim.torques().clone(),
            links: sim.model.body_link_names.clone(),
            sim,
        })
    }

    /// Sets the state (q: nq, v: nv) and time 0's warm starts.
    fn set_state(&mut self, q: &Bound<'_, PyAny>, v: &Bound<'_, PyAny>) -> PyResult<()> {
        let m = &self.sim.model;
        let (mut qv, mut vv) = (DVector::zeros(m.nq), DVector::zeros(m.nv));
        read_q(q, "q", &quat_offsets(m), &mut qv)?;
        read_vec(v, "v", "nv", &mut vv)?;
        self.sim
            .set_state(&qv, &vv)
            .map_err(|e| value_error(e.to_string()))
    }

    /// `n` steps of `dt` with constant joint torques `tau` (nv entries, the
    /// base's part ignored; None: zero).
    #[pyo3(signature = (tau=None, n=1))]
    fn step(&mut self, py: Python<'_>, tau: Option<&Bound<'_, PyAny>>, n: usize) -> PyResult<()> {
        match tau {
            Some(t) => {
                read_vec(t, "tau", "nv", &mut self.tau)?;
                set_torques(&mut self.sim, self.tau.as_slice());
            }
            // zero, or a scene's constant forces (its bases' included), as rollout
            None => self.sim.torques_mut().copy_from(&self.tau0),
        }
        let (sim, dt) = (&mut self.sim, self.dt);
        let r = py.detach(|| {
            for _ in 0..n {
                advance(sim, dt)?;
            }
            Ok::<(), SimError>(())
        });
        r.map_err(|e| {
            let q = PyArray1::from_slice(py, self.sim.q().as_slice())
                .into_any()
                .unbind();
            let v = PyArray1::from_slice(py, self.sim.v().as_slice())
                .into_any()
                .unbind();
            sim_error(py, e.to_string(), q, v, None)
        })
    }

    /// The configuration (a copy).
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.sim.q().as_slice())
    }
    /// The velocity (a copy).
    #[getter]
    fn v<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.sim.v().as_slice())
    }
    /// Simulated time (s).
    #[getter]
    fn time(&self) -> f64 {
        self.sim.time()
    }
    /// Kinetic plus gravitational potential energy (J), as the CSV's column.
    fn energy(&mut self) -> f64 {
        self.sim.energy()
    }
    /// The last step's contact points: dicts with `link`, `point`, `normal` and
    /// `force` (world frame, N).
    fn contact_forces<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        self.sim
            .contact_forces()
            .iter()
            .map(|c| {
                let d = PyDict::new(py);
                let link = self.links.get(c.point.body).cloned().unwrap_or_default();
                d.set_item("link", link)?;
                d.set_item("point", PyArray1::from_slice(py, c.point.point.as_slice()))?;
                d.set_item("normal", PyArray1::from_slice(py, &[0.0, 0.0, 1.0]))?;
                d.set_item("force", PyArray1::from_slice(py, c.force.as_slice()))?;
                Ok(d)
            })
            .collect()
    }

    // --- Control and sensors (python.md §"Control", §"Sensors"; control.rs) ---

    /// Servo gains per degree of freedom (nv; base entries 0) or scalars.
    fn set_gains(&mut self, kp: &Bound<'_, PyAny>, kd: &Bound<'_, PyAny>) -> PyResult<()> {
        crate::control::set_gains(&mut self.sim, kp, kd)
    }
    /// Servo targets (q_ref: nq, its base part ignored; v_ref: nv, None: 0).
    #[pyo3(signature = (q_ref, v_ref=None))]
    fn set_targets(
        &mut self,
        q_ref: &Bound<'_, PyAny>,
        v_ref: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        crate::control::set_targets(&mut self.sim, q_ref, v_ref)
    }
    /// A = ∂x'/∂x (2nv × 2nv), B = ∂x'/∂τ_ff (2nv × nv) of one step from the
    /// current state (as a new Simulation would step it); `sim` is not changed.
    #[pyo3(signature = (tau=None, method="analytic", eps=1e-6))]
    #[allow(clippy::type_complexity)]
    fn transition_jacobians<'py>(
        &self,
        py: Python<'py>,
        tau: Option<&Bound<'py, PyAny>>,
        method: &str,
        eps: f64,
    ) -> PyResult<(Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>)> {
        crate::control::transition_jacobians(py, &self.sim, tau, method, eps)
    }
    /// (gyro, accel) of a link after the last step, link coordinates.
    #[allow(clippy::type_complexity)]
    fn imu<'py>(
        &mut self,
        py: Python<'py>,
        link: &str,
    ) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>)> {
        crate::control::pair(py, self.sim.imu(link))
    }
    /// (force, torque) the parent exerts on a joint's child link, child link coordinates.
    #[allow(clippy::type_complexity)]
    fn joint_wrench<'py>(
        &mut self,
        py: Python<'py>,
        joint: &str,
    ) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>)> {
        crate::control::pair(py, self.sim.joint_wrench(joint))
    }
    /// (force, torque about the link origin) of the last step's contacts on a link, world.
    #[allow(clippy::type_complexity)]
    fn contact_wrench<'py>(
        &mut self,
        py: Python<'py>,
        link: &str,
    ) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>)> {
        crate::control::pair(py, self.sim.contact_wrench(link))
    }
}

/// A and B at each of T states of a trajectory as `sim` would step them, in
/// parallel on `threads` cores with the GIL released (python.md §"Control").
#[pyfunction]
#[pyo3(signature = (sim, q, v, tau, threads=None, method="analytic", eps=1e-6))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
pub fn linearize<'py>(
    py: Python<'py>,
    sim: PyRef<'py, PySimulation>,
    q: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
    tau: &Bound<'py, PyAny>,
    threads: Option<usize>,
    method: &str,
    eps: f64,
) -> PyResult<(Bound<'py, PyArray3<f64>>, Bound<'py, PyArray3<f64>>)> {
    crate::control::linearize(py, &sim.sim, q, v, tau, threads, method, eps)
}

/// The torques of a rollout: none, constant per run (B, nv), or per step
/// (B, nstep, nv).
enum Torques {
    Zero,
    Constant(Vec<f64>),
    PerStep(Vec<f64>),
}

/// B simulations of `nstep` steps of `dt` from (q0[b], v0[b]), in parallel.
/// Returns q (B, nstep + 1, nq) and v (B, nstep + 1, nv), initial states included.
#[pyfunction]
#[pyo3(signature = (model, q0, v0, tau=None, nstep=1000, dt=1e-3, threads=None, integrator=None, ground=Some(0.0), friction=1.0))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
pub fn rollout<'py>(
    py: Python<'py>,
    model: &Bound<'py, PyAny>,
    q0: &Bound<'py, PyAny>,
    v0: &Bound<'py, PyAny>,
    tau: Option<&Bound<'py, PyAny>>,
    nstep: usize,
    dt: f64,
    threads: Option<usize>,
    integrator: Option<&str>,
    ground: Option<f64>,
    friction: f64,
) -> PyResult<(Bound<'py, PyArray3<f64>>, Bound<'py, PyArray3<f64>>)> {
    let proto = prototype_any(model, dt, integrator, ground, friction, None)?;
    let (nq, nv) = (proto.model.nq, proto.model.nv);
    let (qs, q0) = read_array(q0, "q0")?;
    let (vs, v0) = read_array(v0, "v0")?;
    if qs.len() != 2 || qs[1] != nq {
        return Err(value_error(format!(
            "q0 has shape {qs:?}, expected (B, {nq}) (nq = {nq})"
        )));
    }
    let b = qs[0];
    let mut q0 = q0;
    for f in &proto.model.free_joints {
        let at = f.iq + 3;
        for i in 0..b {
            normalize_base_quaternion(&mut q0[i * nq + at..i * nq + at + 4], &format!("q0[{i}]"))?;
        }
    }
    if vs != [b, nv] {
        return Err(value_error(format!(
            "v0 has shape {vs:?}, expected ({b}, {nv}) (B, nv)"
        )));
    }
    let torques = match tau {
        None => Torques::Zero,
        Some(t) if t.is_none() => Torques::Zero,
        Some(t) => {
            let (ts, tv) = read_array(t, "tau")?;
            if ts == [b, nv] {
                Torques::Constant(tv)
            } else if ts == [b, nstep, nv] {
                Torques::PerStep(tv)
            } else {
                return Err(value_error(format!(
                    "tau has shape {ts:?}, expected ({b}, {nv}) or ({b}, {nstep}, {nv})"
                )));
            }
        }
    };
    if threads == Some(0) {
        return Err(value_error("threads must be at least 1 (None: all cores)"));
    }
    let qa = PyArray3::<f64>::zeros(py, [b, nstep + 1, nq], false);
    let va = PyArray3::<f64>::zeros(py, [b, nstep + 1, nv], false);
    let failures = {
        // SAFETY: fresh C-contiguous arrays that no Python code has seen yet; the
        // GIL is released below but nothing else holds them.
        let qo = unsafe { qa.as_slice_mut() }.map_err(|e| value_error(e.to_string()))?;
        let vo = unsafe { va.as_slice_mut() }.map_err(|e| value_error(e.to_string()))?;
        // a failure: (batch index, whether the input was bad, message)
        let run =
            |(i, (qo, vo)): (usize, (&mut [f64], &mut [f64]))| -> Option<(usize, bool, String)> {
                let mut sim = proto.clone();
                let q = DVector::from_column_slice(&q0[i * nq..(i + 1) * nq]);
                let v = DVector::from_column_slice(&v0[i * nv..(i + 1) * nv]);
                let fail =
                    |qo: &mut [f64], vo: &mut [f64], from: usize, input: bool, msg: String| {
                        qo[from * nq..].fill(f64::NAN);
                        vo[from * nv..].fill(f64::NAN);
                        Some((i, input, msg))
                    };
                if let Err(e) = sim.set_state(&q, &v) {
                    return fail(qo, vo, 0, true, format!("q0[{i}], v0[{i}]: {e}"));
                }
                if let Torques::Constant(t) = &torques {
                    set_torques(&mut sim, &t[i * nv..(i + 1) * nv]);
                }
                qo[..nq].copy_from_slice(sim.q().as_slice());
                vo[..nv].copy_from_slice(sim.v().as_slice());
                for k in 0..nstep {
                    if let Torques::PerStep(t) = &torques {
                        let at = (i * nstep + k) * nv;
                        set_torques(&mut sim, &t[at..at + nv]);
                    }
                    if let Err(e) = advance(&mut sim, dt) {
                        return fail(qo, vo, k + 1, false, format!("batch index {i}: {e}"));
                    }
                    qo[(k + 1) * nq..(k + 2) * nq].copy_from_slice(sim.q().as_slice());
                    vo[(k + 1) * nv..(k + 2) * nv].copy_from_slice(sim.v().as_slice());
                }
                None
            };
        let (sq, sv) = ((nstep + 1) * nq, (nstep + 1) * nv);
        py.detach(|| {
            let mut work = move || -> Vec<(usize, bool, String)> {
                qo.par_chunks_mut(sq.max(1))
                    .zip(vo.par_chunks_mut(sv.max(1)))
                    .enumerate()
                    .filter_map(run)
                    .collect()
            };
            match threads {
                None => Ok(work()),
                Some(n) => rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .build()
                    .map(|pool| pool.install(work))
                    .map_err(|e| e.to_string()),
            }
        })
        .map_err(|e| value_error(format!("threads: cannot start a thread pool: {e}")))?
    };
    if let Some((_, _, msg)) = failures.iter().find(|f| f.1) {
        return Err(value_error(msg.clone()));
    }
    if let Some((i, _, msg)) = failures.into_iter().min_by_key(|f| f.0) {
        return Err(sim_error(
            py,
            msg,
            qa.clone().into_any().unbind(),
            va.clone().into_any().unbind(),
            Some(i),
        ));
    }
    Ok((qa, va))
}
