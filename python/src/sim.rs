//! `urdyn.Simulation`: one simulation stepped from Python. It and `rollout`
//! (rollout.rs) go through [`prototype_any`], [`start_state`] and [`advance`],
//! so that a rollout's states equal, bit for bit, a `Simulation` stepped alone.

use crate::args::named;
use crate::args::{quat_offsets, read_count, read_q, read_threads, read_vec, value_error, Given};
use crate::prototype::{prototype_any, start_loops};
use crate::view::Frame;
use crate::SimulationError;
use numpy::{PyArray1, PyArray2, PyArray3};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::HashMap;
use std::path::PathBuf;
use urdyn::cli::view::ContactArrow;
use urdyn::model::Constraints;
use urdyn::nalgebra::DVector;
use urdyn::sim::{Integrator, SimError, Simulation};

/// The names `integrator=` accepts.
#[pyfunction]
pub fn integrators() -> Vec<&'static str> {
    Integrator::ALL.iter().map(|i| i.name()).collect()
}

/// A new start at (q, v), as `Simulation.set_state` and each rollout entry
/// make it: the library's `set_state`, then the loops `loops` (if any) started
/// again there (world anchors left out placed where side 1 is in this state;
/// the constraints in `off` switched off). Returns the start's warning lines.
pub(crate) fn start_state(
    sim: &mut Simulation,
    q: &DVector<f64>,
    v: &DVector<f64>,
    loops: Option<&Constraints>,
    off: &[String],
) -> Result<Vec<String>, SimError> {
    sim.set_state(q, v)?;
    match loops {
        Some(set) => start_loops(sim, set, off),
        None => Ok(Vec::new()),
    }
}

/// One step of `dt` of simulated time (an adaptive integrator may take several
/// steps of its own to get there; the last lands exactly). A fixed-step
/// integrator at its own step takes exactly `dt`, as `urdyn simulate` steps
/// (src/cli/simulate/record.rs), so the two agree bit for bit: landing on
/// `time + dt` would take `(time + dt) - time`, an ulp off `dt` once time is
/// not a multiple of it.
pub(crate) fn advance(sim: &mut Simulation, dt: f64) -> Result<(), SimError> {
    if dt == sim.dt() && !sim.integrator().is_adaptive() {
        sim.step()?;
        return Ok(());
    }
    let target = sim.time() + dt;
    while sim.time() < target {
        sim.step_until(target)?;
    }
    Ok(())
}

/// Constant joint torques (every free joint's part of `tau` ignored).
/// No allocation (rollout calls it every step with per-step torques).
pub(crate) fn set_torques(sim: &mut Simulation, tau: &[f64]) {
    let n = sim.torques().len();
    {
        let t = sim.torques_mut();
        for k in 0..n {
            t[k] = tau.get(k).copied().unwrap_or(0.0);
        }
    }
    // the free joints' six entries after, as sim.model and the torques are
    // borrowed apart
    for j in 0..sim.model.free_joints.len() {
        let iv = sim.model.free_joints[j].iv;
        let t = sim.torques_mut();
        for k in iv..(iv + 6).min(n) {
            t[k] = 0.0;
        }
    }
}

/// A `SimulationError` with `.q`, `.v` (and `.index`) attached.
pub(crate) fn sim_error(
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
    /// The simulation as constructed (`reset()` returns to it).
    start: Simulation,
    dt: f64,
    tau: DVector<f64>,
    /// `step(tau=None)`'s torques: zero, or a scene's `initial.tau`.
    tau0: DVector<f64>,
    /// The URDF links and their order (`contacts()` orders a pair's sides by it).
    frames: HashMap<String, usize>,
    /// What a page of this simulation is drawn from (`write_html`), made at
    /// the first `record(True)`.
    stage: Option<crate::view::Stage>,
    /// The model or scene given (a page's geometry is read from it).
    source: Py<PyAny>,
    /// The recording: `Some` while recording or after it stopped.
    frames_rec: Vec<Frame>,
    recording: bool,
    /// The loop constraints as given (world anchors not placed): `set_state`
    /// starts them again.
    loops: Option<Constraints>,
    /// The constraints switched off (`set_constraint_active`), kept across
    /// `set_state` and `reset`.
    off: Vec<String>,
    /// The start's warning lines (a constraint violated by more than 1 mm),
    /// given as `RuntimeWarning`s at the next `step`.
    pending: Vec<String>,
}

impl PySimulation {
    /// Adds the current state to the recording.
    fn record_frame(&mut self) {
        let arrows = self
            .sim
            .contact_forces()
            .iter()
            .map(|c| ContactArrow {
                point: c.point.point.into(),
                force: c.force.into(),
            })
            .collect();
        self.frames_rec.push(Frame {
            t: self.sim.time(),
            q: self.sim.q().clone(),
            plot: [
                self.sim.energy(),
                self.sim.active_contacts() as f64,
                self.sim.penetration(),
            ],
            arrows,
        });
    }
}

#[pymethods]
impl PySimulation {
    /// `ground=None`: no ground; `integrator=None`: the default for the scene
    /// (`urdyn.integrators()` lists the names). Of a `Scene`: its ground
    /// (height, friction, and the torsional and rolling friction of its
    /// `"torsion"`/`"rolling"` keys, as `urdyn simulate --scene` reads them),
    /// obstacles and start (`ground=`/`friction=` beside it are a ValueError:
    /// the file decides). A step is exactly `dt` (a fixed-step integrator's),
    /// as the CLI's, so the states equal its CSV's bit for bit. `sleep`, `threads` (scene.md §"Large
    /// scenes"): `None` takes the scene's settings (its `"sleep"`,
    /// `"threads"`, a model's own `"sleep": false`); a model alone is a
    /// one-model scene, so it sleeps by default on one thread, as `urdyn
    /// simulate ROBOT.urdf` does. `constraints` (a `urdyn.Constraints` made
    /// for `model`, or a list of mechanisms.md's constraint dicts): loops of a
    /// one-model simulation, no scene file needed (a scene's come from its
    /// file). A world anchor left out is placed where its link is at the start
    /// — construction, and each `set_state`, which starts a run anew.
    #[new]
    #[pyo3(signature = (model, dt=1e-3, integrator=None, ground=Given::Omitted, friction=Given::Omitted, package_dirs=None, sleep=None, threads=None, constraints=None))]
    #[pyo3(
        text_signature = "(model, dt=1e-3, integrator=None, ground=0.0, friction=1.0, package_dirs=None, sleep=None, threads=None, constraints=None)"
    )]
    #[allow(clippy::too_many_arguments)]
    fn new(
        model: &Bound<'_, PyAny>,
        #[pyo3(from_py_with = named::dt)] dt: f64,
        #[pyo3(from_py_with = named::integrator)] integrator: Option<String>,
        ground: Given,
        friction: Given,
        package_dirs: Option<Vec<PathBuf>>,
        #[pyo3(from_py_with = named::sleep)] sleep: Option<bool>,
        threads: Option<&Bound<'_, PyAny>>,
        constraints: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let threads = read_threads(threads)?;
        let proto = prototype_any(
            model,
            dt,
            integrator.as_deref(),
            &ground,
            &friction,
            package_dirs,
            sleep,
            threads,
            constraints,
        )?;
        let sim = proto.sim;
        let frames = sim
            .model
            .frames
            .iter()
            .enumerate()
            .map(|(i, f)| (f.name.clone(), i))
            .collect();
        Ok(Self {
            dt,
            tau: sim.torques().clone(),
            tau0: sim.torques().clone(),
            frames,
            start: sim.clone(),
            sim,
            stage: None,
            source: model.clone().unbind(),
            frames_rec: Vec::new(),
            recording: false,
            loops: proto.loops,
            off: Vec::new(),
            pending: proto.warnings,
        })
    }

    /// Sets the state (q: nq, v: nv; warm starts forgotten); the time stays
    /// unless `time` is given. The start `reset()` returns to does not move.
    /// With loop constraints a new start: world anchors left out are placed
    /// where their link is in this state.
    #[pyo3(signature = (q, v, time=None))]
    fn set_state(
        &mut self,
        q: &Bound<'_, PyAny>,
        v: &Bound<'_, PyAny>,
        #[pyo3(from_py_with = named::time)] time: Option<f64>,
    ) -> PyResult<()> {
        let m = &self.sim.model;
        let (mut qv, mut vv) = (DVector::zeros(m.nq), DVector::zeros(m.nv));
        read_q(q, "q", &quat_offsets(m), &mut qv)?;
        read_vec(v, "v", "nv", &mut vv)?;
        if let Some(t) = time {
            if !t.is_finite() {
                return Err(value_error(format!(
                    "time must be a finite number (got {t})"
                )));
            }
        }
        self.pending = start_state(&mut self.sim, &qv, &vv, self.loops.as_ref(), &self.off)
            .map_err(|e| value_error(e.to_string()))?;
        if let Some(t) = time {
            self.sim.set_time(t);
        }
        Ok(())
    }

    /// Back to the state and time the Simulation started from (a scene's
    /// start), warm starts cleared; gains, targets, the constraints switched
    /// off and the recording stay. The same inputs then replay the first run
    /// bit for bit.
    fn reset(&mut self) -> PyResult<()> {
        let (kp, kd) = self.sim.gains();
        let (kp, kd) = (kp.clone(), kd.clone());
        let (q_ref, v_ref) = self.sim.targets();
        let (q_ref, v_ref) = (q_ref.clone(), v_ref.clone());
        let mut sim = self.start.clone();
        sim.set_gains(&kp, &kd)
            .and_then(|_| sim.set_targets(&q_ref, Some(&v_ref)))
            .map_err(|e| value_error(e.to_string()))?;
        for name in &self.off {
            sim.set_constraint_active(name, false)
                .map_err(|e| value_error(e.to_string()))?;
        }
        crate::mjcf::keep_controls(&self.sim, &mut sim)?; // MJCF actuators (mjcf.rs)
        self.sim = sim;
        Ok(())
    }

    /// `n` steps of `dt` with constant joint torques `tau` (nv entries, the
    /// base's part ignored; None: zero, or a scene's `initial` torques). With
    /// servos (`set_gains`) tau is the feed-forward part. Each joint's torque,
    /// servo included, is clamped to its URDF `<limit effort>` (as the CLI
    /// does; `model.effort_limits`): a torque beyond it moves the joint as the
    /// limit would, and `applied_torques` shows what was applied.
    #[pyo3(signature = (tau=None, n=None))]
    #[pyo3(text_signature = "(self, tau=None, n=1)")]
    fn step(
        &mut self,
        py: Python<'_>,
        tau: Option<&Bound<'_, PyAny>>,
        n: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        let n = match n {
            Some(n) => read_count(n, "n", 0)?,
            None => 1,
        };
        // a start that violates a loop by more than 1 mm: one warning a constraint
        for line in std::mem::take(&mut self.pending) {
            let w = py.get_type::<pyo3::exceptions::PyRuntimeWarning>();
            let msg = std::ffi::CString::new(format!("warning: {line}")).unwrap_or_default();
            PyErr::warn(py, &w, &msg, 1)?;
        }
        match tau.filter(|t| !t.is_none()) {
            Some(t) => {
                read_vec(t, "tau", "nv", &mut self.tau)?;
                set_torques(&mut self.sim, self.tau.as_slice());
            }
            // zero, or a scene's constant forces (its bases' included), as rollout
            None => self.sim.torques_mut().copy_from(&self.tau0),
        }
        crate::mjcf::add_actuator_torques(&mut self.sim); // MJCF actuators (mjcf.rs)
        let (dt, recording) = (self.dt, self.recording);
        let mut r = Ok(());
        for _ in 0..n {
            let sim = &mut self.sim;
            // one call a step while recording, else all n without the GIL
            let k = if recording { 1 } else { n };
            r = py.detach(|| {
                for _ in 0..k {
                    advance(sim, dt)?;
                }
                Ok::<(), SimError>(())
            });
            if r.is_err() {
                break;
            }
            if recording {
                self.record_frame();
            } else {
                break;
            }
        }
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
    /// The number of awake models (with degrees of freedom) now (cli.md's
    /// `awake`).
    #[getter]
    fn awake(&self) -> usize {
        self.sim.awake()
    }
    /// Whether the model `model_name` sleeps now (a scene's model name; a lone
    /// model's is its `models[0]`). An unknown name is a `ValueError`.
    fn sleeping(
        &self,
        #[pyo3(from_py_with = named::model_name)] model_name: String,
    ) -> PyResult<bool> {
        let trees = &self.sim.model.trees;
        let key = if trees.len() == 1 && trees[0].name.is_empty() {
            // a lone model's one tree is named "" in the library
            ""
        } else {
            &model_name
        };
        let lone = trees.len() == 1 && trees[0].name.is_empty();
        if lone
            && !(model_name.is_empty()
                || model_name == "robot"
                || model_name == self.sim.model.name)
        {
            return Err(value_error(format!(
                "sleeping: unknown model \"{model_name}\" (one model: \"robot\")"
            )));
        }
        self.sim.sleeping(key).ok_or_else(|| {
            let names: Vec<&str> = trees.iter().map(|t| t.name.as_str()).collect();
            value_error(format!(
                "sleeping: unknown model \"{model_name}\" (models: {})",
                names.join(", ")
            ))
        })
    }
    /// Wakes every sleeping island now.
    fn wake(&mut self) {
        self.sim.wake();
    }
    /// The deepest penetration now (m, 0 if none), as the CSV's column.
    #[getter]
    fn penetration(&self) -> f64 {
        self.sim.penetration()
    }
    /// (nv,) the torques the last step applied: feed-forward plus servo, each
    /// clamped to its effort limit (implicit servos: their end-of-step value;
    /// an RK or adaptive step: its last stage's); base entries 0.
    #[getter]
    fn applied_torques<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let mut t = self.sim.applied_torques().clone();
        for f in &self.sim.model.free_joints {
            t.rows_mut(f.iv, 6).fill(0.0);
        }
        PyArray1::from_slice(py, t.as_slice())
    }
    /// Every contact point of the last step (within the contact margin, force
    /// possibly zero): dicts with "link", "other" (a link, an obstacle's name
    /// or "ground"), "point", "normal" (unit, from `other` into `link`),
    /// "force" (on `link`, N) and "depth" (m, > 0 penetrating, < 0 a gap, at
    /// the step's end as `penetration`), world frame.
    fn contacts<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        crate::contacts::contacts(&self.sim, &self.frames)
            .iter()
            .map(|c| crate::contacts::to_dict(py, c))
            .collect()
    }
    /// The entries of `contacts()` that carry a force (link, other, point,
    /// normal, force, depth).
    fn contact_forces<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        crate::contacts::contacts(&self.sim, &self.frames)
            .iter()
            .filter(|c| c.force != urdyn::nalgebra::Vector3::zeros())
            .map(|c| crate::contacts::to_dict(py, c))
            .collect()
    }

    /// `record(True)` starts a recording, the current state its first frame
    /// (starting again clears it); `record(False)` stops it (kept for
    /// `write_html`).
    fn record(
        &mut self,
        py: Python<'_>,
        #[pyo3(from_py_with = named::on)] on: bool,
    ) -> PyResult<()> {
        if on {
            if self.stage.is_none() {
                let ground = self.sim.options().ground;
                self.stage = Some(crate::view::stage(self.source.bind(py), ground)?);
            }
            self.frames_rec.clear();
            self.record_frame();
        }
        self.recording = on;
        Ok(())
    }
    /// Writes the recording's replay page to `path` (the recording is kept);
    /// returns the number of frames the page holds (thinned for size).
    fn write_html(&self, #[pyo3(from_py_with = named::path)] path: PathBuf) -> PyResult<usize> {
        let Some(stage) = &self.stage else {
            return Err(value_error(
                "write_html: nothing recorded (call sim.record(True) before stepping)",
            ));
        };
        crate::view::write(&path, stage, &self.frames_rec)
    }

    // --- Loop constraints (mechanisms.md §"Python"; constraints.rs) ---

    /// The largest violation over the active loop constraints now (m for
    /// `point`, the larger of m and rad for `frame`, |residual| for `joint`; 0
    /// without loops). An attribute; calling it (`sim.constraint_violation()`)
    /// gives the same number.
    #[getter]
    fn constraint_violation<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let x = self.sim.constraint_violation();
        py.import("urdyn")?.getattr("_Reading")?.call1((x,))
    }
    /// Each loop constraint's force in the last step (world): `{name:
    /// {"force": (3,), "torque": (3,)}}` on link1 at its point or frame origin
    /// (`point`: torque 0; on link2 the opposite), a `joint` constraint's
    /// generalized force on joint1 `{"torque": x}` (`{"force": x}` prismatic).
    fn constraint_forces<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        crate::constraints::forces_dict(py, &self.sim)
    }
    /// Switches the loop constraint `name` on or off (`on`: True or False);
    /// kept across `set_state` and `reset`. Switching one on wakes the run.
    fn set_constraint_active(
        &mut self,
        name: &Bound<'_, PyAny>,
        on: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let (name, on) = crate::constraints::read_switch(&self.sim, name, on)?;
        self.sim
            .set_constraint_active(&name, on)
            .map_err(|e| value_error(format!("name: {e}")))?;
        self.off.retain(|n| *n != name);
        if !on {
            self.off.push(name);
        }
        Ok(())
    }

    // --- MJCF actuators and keyframes (mjcf.md; python/src/mjcf.rs, the mjcfact block) ---

    /// The MJCF model's actuator controls (nu, in the file's order; each
    /// clamped into its ctrlrange), held until set again: position and
    /// velocity actuators are servos (integrated implicitly), a motor's force
    /// is added to `step`'s tau.
    fn set_controls(&mut self, u: &Bound<'_, PyAny>) -> PyResult<()> {
        crate::mjcf::set_controls(&mut self.sim, u)
    }
    /// Starts from the MJCF model's keyframe `name`: its q, v and controls.
    fn set_key(&mut self, name: &str) -> PyResult<()> {
        crate::mjcf::set_key(&mut self.sim, name)
    }
    /// The actuator controls as last set (nu).
    #[getter]
    fn controls<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        crate::mjcf::controls(py, &self.sim)
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
    /// current state, as a new Simulation with the same settings, gains and
    /// targets would step it; `sim` is not changed. x = (q, v) in the tangent
    /// space. `method="analytic"` differentiates the step with its contact set
    /// held: where contacts touch, A is the contact-held derivative (a resting
    /// foot stays on the ground), while "forward"/"central" (finite differences
    /// of the step, step `eps`, as MuJoCo's mjd_transitionFD) see a perturbation
    /// that lifts the foot leave the ground: one-sided, so they differ there.
    #[pyo3(
        signature = (tau=None, method=Given::Omitted, eps=1e-6),
        text_signature = "(self, tau=None, method='analytic', eps=1e-6)"
    )]
    #[allow(clippy::type_complexity)]
    fn transition_jacobians<'py>(
        &self,
        py: Python<'py>,
        tau: Option<&Bound<'py, PyAny>>,
        method: Given,
        #[pyo3(from_py_with = named::eps)] eps: f64,
    ) -> PyResult<(Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>)> {
        crate::control::transition_jacobians(py, &self.sim, tau, &method, eps)
    }
    /// (gyro, accel) of a link after the last step, link coordinates.
    #[allow(clippy::type_complexity)]
    fn imu<'py>(
        &mut self,
        py: Python<'py>,
        #[pyo3(from_py_with = named::link)] link: String,
    ) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>)> {
        crate::control::pair(py, self.sim.imu(&link))
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
        #[pyo3(from_py_with = named::link)] link: String,
    ) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>)> {
        crate::control::pair(py, self.sim.contact_wrench(&link))
    }
}

/// A and B at each of T states of a trajectory as `sim` would step them, in
/// parallel on `threads` cores with the GIL released (python.md §"Control").
#[pyfunction]
#[pyo3(
    signature = (sim, q, v, tau, threads=None, method=String::from("analytic"), eps=1e-6),
    text_signature = "(sim, q, v, tau, threads=None, method='analytic', eps=1e-6)"
)]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
pub fn linearize<'py>(
    py: Python<'py>,
    sim: PyRef<'py, PySimulation>,
    q: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
    tau: &Bound<'py, PyAny>,
    threads: Option<&Bound<'py, PyAny>>,
    #[pyo3(from_py_with = named::method)] method: String,
    #[pyo3(from_py_with = named::eps)] eps: f64,
) -> PyResult<(Bound<'py, PyArray3<f64>>, Bound<'py, PyArray3<f64>>)> {
    let threads = read_threads(threads)?;
    crate::control::linearize(py, &sim.sim, q, v, tau, threads, &method, eps)
}
