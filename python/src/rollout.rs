//! `urdyn.rollout`: B simulations in parallel on rayon with the GIL released,
//! each with its own torques, servo gains and targets (python.md §"Batches on
//! every core", §"Introspection, contacts, batched control, pictures"); each
//! equals, bit for bit, a `Simulation` given the same calls and stepped alone
//! (the same [`prototype_any`], [`start_state`], [`set_torques`], `set_gains`,
//! `set_targets` and [`advance`]).

use crate::args::named;
use crate::args::{
    normalize_quaternion_at, read_array, read_count, read_threads, value_error, Given,
};
use crate::prototype::prototype_any;
use crate::sim::{advance, set_torques, sim_error, start_state};
use numpy::{PyArray3, PyArrayMethods};
use pyo3::prelude::*;
use rayon::prelude::*;
use urdyn::nalgebra::DVector;

/// A per-run input: none, one row per run (B, n), or one per step (B, nstep, n).
enum PerRun {
    None,
    Constant(Vec<f64>),
    PerStep(Vec<f64>),
}

impl PerRun {
    /// Reads `x` ((B, n) or (B, nstep, n); None: none).
    fn read(
        x: Option<&Bound<'_, PyAny>>,
        name: &str,
        b: usize,
        nstep: usize,
        n: usize,
    ) -> PyResult<Self> {
        let Some(x) = x.filter(|x| !x.is_none()) else {
            return Ok(PerRun::None);
        };
        let (shape, data) = read_array(x, name)?;
        if shape == [b, n] {
            Ok(PerRun::Constant(data))
        } else if shape == [b, nstep, n] {
            Ok(PerRun::PerStep(data))
        } else {
            Err(value_error(format!(
                "{name} has shape {shape:?}, expected ({b}, {n}) or ({b}, {nstep}, {n})"
            )))
        }
    }
    /// Run i's row at step k (`None`: none, or constant and k > 0 where
    /// `constant_once`).
    fn row(&self, i: usize, k: usize, nstep: usize, n: usize) -> Option<&[f64]> {
        match self {
            PerRun::None => None,
            PerRun::Constant(d) => Some(&d[i * n..(i + 1) * n]),
            PerRun::PerStep(d) => {
                let at = (i * nstep + k) * n;
                Some(&d[at..at + n])
            }
        }
    }
    fn per_step(&self) -> bool {
        matches!(self, PerRun::PerStep(_))
    }
}

/// Gains `kp`/`kd`: None, a number, (nv,) or (B, nv); per run, nv entries
/// (a number: every joint, a free joint's entries 0).
fn read_gains(
    x: Option<&Bound<'_, PyAny>>,
    name: &str,
    b: usize,
    model: &urdyn::Model,
) -> PyResult<Option<Vec<f64>>> {
    let nv = model.nv;
    let Some(x) = x.filter(|x| !x.is_none()) else {
        return Ok(None);
    };
    let scalar = if x.is_instance_of::<pyo3::types::PyBool>() {
        None
    } else {
        x.extract::<f64>().ok()
    };
    let (shape, data) = match scalar {
        Some(g) => (Vec::new(), vec![g]),
        None => read_array(x, name)?,
    };
    if let Some(g) = data.iter().find(|g| g.is_nan() || **g < 0.0) {
        return Err(value_error(format!(
            "{name} must be finite numbers ≥ 0 (got {g})"
        )));
    }
    let rows = if shape.is_empty() {
        let g = data[0];
        let row: Vec<f64> = (0..nv)
            .map(|k| model.dof_at_v(k).map_or(0.0, |_| g))
            .collect();
        row.repeat(b)
    } else if shape == [nv] {
        data.repeat(b)
    } else if shape == [b, nv] {
        data
    } else {
        return Err(value_error(format!(
            "{name} has shape {shape:?}, expected a number, ({nv},) or ({b}, {nv})"
        )));
    };
    Ok(Some(rows))
}

/// B simulations of `nstep` steps of `dt` from (q0[b], v0[b]) (q0 (B, nq),
/// v0 (B, nv)), in parallel with the GIL released. Returns q (B, nstep + 1,
/// nq) and v (B, nstep + 1, nv), initial states included. `tau`: None, (B, nv)
/// constant or (B, nstep, nv) (the base's part ignored, each torque clamped to
/// its effort limit as in `Simulation.step`). Servos as `set_gains` /
/// `set_targets`: `kp`, `kd` a number (every joint), (nv,) or (B, nv);
/// `q_ref` (B, nq) or (B, nstep, nq) (step k takes `q_ref[:, k]`); `v_ref`
/// (B, nv) or (B, nstep, nv). `controls`: an MJCF model's actuator controls,
/// (B, nu) or (B, nstep, nu), as `set_controls` before each step (they
/// replace the servos' gains and targets, as `set_controls` does).
/// `threads`: the batch's workers (None: every core), and each simulation's
/// island threads (None: the scene's setting, one for a model alone; scene.md
/// §"Large scenes"); `sleep`: whether still islands sleep (None: the scene's
/// setting; a model alone sleeps). `constraints`: a
/// model's loops, as `Simulation(model, constraints=...)` (a scene's come
/// from its file), started at each run's (q0[b], v0[b]) as `set_state` does.
/// Each batch entry equals, bit for bit, a `Simulation` with the same
/// arguments given the same calls and stepped alone. A wrong shape, a
/// negative count, or `ground=`/`friction=`/`constraints=` beside a scene is
/// a `ValueError` naming the argument; a run that turns non-finite raises
/// `urdyn.SimulationError` naming its batch index, with the partial results
/// as `.q` and `.v` (NaN after the failure).
#[pyfunction]
#[pyo3(signature = (model, q0, v0, tau=None, nstep=None, dt=1e-3, threads=None, integrator=None, ground=Given::Omitted, friction=Given::Omitted, kp=None, kd=None, q_ref=None, v_ref=None, sleep=None, constraints=None, controls=None))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
pub fn rollout<'py>(
    py: Python<'py>,
    model: &Bound<'py, PyAny>,
    q0: &Bound<'py, PyAny>,
    v0: &Bound<'py, PyAny>,
    tau: Option<&Bound<'py, PyAny>>,
    nstep: Option<&Bound<'py, PyAny>>,
    #[pyo3(from_py_with = named::dt)] dt: f64,
    threads: Option<&Bound<'py, PyAny>>,
    #[pyo3(from_py_with = named::integrator)] integrator: Option<String>,
    ground: Given,
    friction: Given,
    kp: Option<&Bound<'py, PyAny>>,
    kd: Option<&Bound<'py, PyAny>>,
    q_ref: Option<&Bound<'py, PyAny>>,
    v_ref: Option<&Bound<'py, PyAny>>,
    #[pyo3(from_py_with = named::sleep)] sleep: Option<bool>,
    constraints: Option<&Bound<'py, PyAny>>,
    controls: Option<&Bound<'py, PyAny>>,
) -> PyResult<(Bound<'py, PyArray3<f64>>, Bound<'py, PyArray3<f64>>)> {
    let nstep = match nstep {
        Some(n) if !n.is_none() => read_count(n, "nstep", 0)?,
        _ => 1000,
    };
    let threads = read_threads(threads)?;
    let start = prototype_any(
        model,
        dt,
        integrator.as_deref(),
        &ground,
        &friction,
        None,
        sleep,
        threads,
        constraints,
    )?;
    let (proto, loops) = (start.sim, start.loops);
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
    for at in crate::args::quat_offsets(&proto.model) {
        for i in 0..b {
            normalize_quaternion_at(
                &mut q0[i * nq + at..i * nq + at + 4],
                &format!("q0[{i}]"),
                at,
            )?;
        }
    }
    if vs != [b, nv] {
        return Err(value_error(format!(
            "v0 has shape {vs:?}, expected ({b}, {nv}) (B, nv)"
        )));
    }
    let torques = PerRun::read(tau, "tau", b, nstep, nv)?;
    let q_refs = PerRun::read(q_ref, "q_ref", b, nstep, nq)?;
    let v_refs = PerRun::read(v_ref, "v_ref", b, nstep, nv)?;
    let nu = proto.model.actuators.len();
    if nu == 0 && controls.is_some_and(|c| !c.is_none()) {
        return Err(value_error(
            "controls: the model has no actuators (nu = 0; MJCF <actuator> elements give them)",
        ));
    }
    let controls = PerRun::read(controls, "controls", b, nstep, nu)?;
    // with controls, each step's applied torques are made as `Simulation.step`
    // makes them: tau's row (or the start's torques) plus the actuators' forces
    let tau0 = proto.torques().clone();
    let kp = read_gains(kp, "kp", b, &proto.model)?;
    let kd = read_gains(kd, "kd", b, &proto.model)?;
    // the servo of run i, as `Simulation.set_gains` / `set_targets` set it
    let servo = |sim: &mut urdyn::sim::Simulation, i: usize, k: usize| -> Result<(), String> {
        if k == 0 && (kp.is_some() || kd.is_some()) {
            let zero = vec![0.0; nv];
            let row = |g: &Option<Vec<f64>>| {
                DVector::from_column_slice(
                    g.as_ref().map_or(&zero[..], |g| &g[i * nv..(i + 1) * nv]),
                )
            };
            sim.set_gains(&row(&kp), &row(&kd))
                .map_err(|e| format!("kp[{i}], kd[{i}]: {e}"))?;
        }
        let step_k = |p: &PerRun| k == 0 || p.per_step();
        if (q_refs.row(i, k, nstep, nq).is_some() && step_k(&q_refs))
            || (v_refs.row(i, k, nstep, nv).is_some() && step_k(&v_refs))
        {
            let q = match q_refs.row(i, k, nstep, nq) {
                Some(r) => DVector::from_column_slice(r),
                None => sim.targets().0.clone(),
            };
            let v = v_refs.row(i, k, nstep, nv).map(DVector::from_column_slice);
            sim.set_targets(&q, v.as_ref())
                .map_err(|e| format!("q_ref[{i}], v_ref[{i}]: {e}"))?;
        }
        Ok(())
    };
    // SAFETY: left uninitialised (no zeroing pass over memory every entry of
    // which is written below: each run writes its rows 0..=nstep, or NaN from
    // where it failed on); not seen by Python before that.
    let qa = unsafe { PyArray3::<f64>::new(py, [b, nstep + 1, nq], false) };
    let va = unsafe { PyArray3::<f64>::new(py, [b, nstep + 1, nv], false) };
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
                if let Err(e) = start_state(&mut sim, &q, &v, loops.as_ref(), &[]) {
                    return fail(qo, vo, 0, true, format!("q0[{i}], v0[{i}]: {e}"));
                }
                if let (PerRun::Constant(_), Some(t)) = (&torques, torques.row(i, 0, nstep, nv)) {
                    set_torques(&mut sim, t);
                }
                qo[..nq].copy_from_slice(sim.q().as_slice());
                vo[..nv].copy_from_slice(sim.v().as_slice());
                for k in 0..nstep {
                    if let Err(msg) = servo(&mut sim, i, k) {
                        return fail(qo, vo, k, true, msg);
                    }
                    if let Some(u) = controls.row(i, k, nstep, nu) {
                        if k == 0 || controls.per_step() {
                            let u = DVector::from_column_slice(u);
                            if let Err(e) = sim.set_controls(&u) {
                                return fail(qo, vo, k, true, format!("controls[{i}]: {e}"));
                            }
                        }
                        match torques.row(i, k, nstep, nv) {
                            Some(t) => set_torques(&mut sim, t),
                            None => sim.torques_mut().copy_from(&tau0),
                        }
                        let ff = sim.actuator_torques().clone();
                        *sim.torques_mut() += ff;
                    } else if let (true, Some(t)) =
                        (torques.per_step(), torques.row(i, k, nstep, nv))
                    {
                        set_torques(&mut sim, t);
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
                Some(n) => crate::pool::pool(n).map(|pool| pool.install(work)),
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
