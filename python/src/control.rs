//! Control from Python (python.md §"Control", §"Sensors"): the work behind
//! `Simulation.set_gains`, `set_targets`, `transition_jacobians`, the sensors
//! and `urdyn.linearize` (the methods themselves are thin, in `sim.rs`).

use crate::args::{named, read_array, read_vec, value_error, Given};
use numpy::{PyArray1, PyArray2, PyArray3, PyArrayMethods};
use pyo3::intern;
use pyo3::prelude::*;
use rayon::prelude::*;
use urdyn::nalgebra::{DMatrix, DVector, Vector3};
use urdyn::sim::{JacobianMethod, Simulation};

/// Gains: a number (every joint, base entries 0) or nv numbers.
fn read_gains(sim: &Simulation, x: &Bound<'_, PyAny>, name: &str) -> PyResult<DVector<f64>> {
    let nv = sim.model.nv;
    if let Ok(g) = x.extract::<f64>() {
        if !(g.is_finite() && g >= 0.0) {
            return Err(value_error(format!(
                "{name} must be a finite number ≥ 0 (got {g})"
            )));
        }
        // a free joint's six entries 0
        let m = &sim.model;
        return Ok(DVector::from_fn(nv, |k, _| {
            m.dof_at_v(k).map_or(0.0, |_| g)
        }));
    }
    let mut out = DVector::zeros(nv);
    read_vec(x, name, "nv", &mut out)?;
    Ok(out)
}

/// `sim.set_gains(kp, kd)`.
pub fn set_gains(
    sim: &mut Simulation,
    kp: &Bound<'_, PyAny>,
    kd: &Bound<'_, PyAny>,
) -> PyResult<()> {
    let kp = read_gains(sim, kp, "kp")?;
    let kd = read_gains(sim, kd, "kd")?;
    sim.set_gains(&kp, &kd)
        .map_err(|e| value_error(e.to_string()))
}

/// `sim.set_targets(q_ref, v_ref=None)`.
pub fn set_targets(
    sim: &mut Simulation,
    q_ref: &Bound<'_, PyAny>,
    v_ref: Option<&Bound<'_, PyAny>>,
) -> PyResult<()> {
    let (nq, nv) = (sim.model.nq, sim.model.nv);
    let mut q = DVector::zeros(nq);
    read_vec(q_ref, "q_ref", "nq", &mut q)?;
    let v = match v_ref {
        Some(x) if !x.is_none() => {
            let mut v = DVector::zeros(nv);
            read_vec(x, "v_ref", "nv", &mut v)?;
            Some(v)
        }
        _ => None,
    };
    sim.set_targets(&q, v.as_ref())
        .map_err(|e| value_error(e.to_string()))
}

/// The method of `method=`.
pub fn method(name: &str) -> PyResult<JacobianMethod> {
    JacobianMethod::from_name(name).ok_or_else(|| {
        value_error(format!(
            "method: unknown \"{name}\" (one of: analytic, forward, central)"
        ))
    })
}

/// A numpy copy of a matrix (C order): the matrix's contiguous columns
/// scattered into a new array's rows, every entry written once (no zeroing).
pub fn mat_out<'py>(py: Python<'py>, m: &DMatrix<f64>) -> Bound<'py, PyArray2<f64>> {
    let (r, c) = m.shape();
    // SAFETY: uninitialised, but every one of its r·c entries is written below
    // before Python can see it
    let a = unsafe { PyArray2::<f64>::new(py, [r, c], false) };
    // SAFETY: a fresh C-contiguous array of r·c entries, not shared yet
    if let Ok(s) = unsafe { a.as_slice_mut() } {
        if r > 0 {
            for (j, col) in m.as_slice().chunks_exact(r).enumerate() {
                for (x, out) in col.iter().zip(s[j..].iter_mut().step_by(c)) {
                    *out = *x;
                }
            }
        }
    }
    a
}

/// `method=` of `transition_jacobians`: omitted → analytic; the three names
/// matched by identity with interned strings first (a literal in Python code
/// is interned: no text is read), any other value through [`method`].
pub fn jacobian_method(py: Python<'_>, x: &Given) -> PyResult<JacobianMethod> {
    let Given::Value(obj) = x else {
        return Ok(JacobianMethod::Analytic);
    };
    let obj = obj.bind(py);
    if obj.is(intern!(py, "analytic")) {
        return Ok(JacobianMethod::Analytic);
    }
    if obj.is(intern!(py, "forward")) {
        return Ok(JacobianMethod::Forward);
    }
    if obj.is(intern!(py, "central")) {
        return Ok(JacobianMethod::Central);
    }
    method(&named::method(obj)?)
}

/// `tau=` of `transition_jacobians` into `out` (nv): a float64 numpy vector
/// read directly, anything else through [`read_vec`].
fn read_tau(x: &Bound<'_, PyAny>, out: &mut DVector<f64>) -> PyResult<()> {
    if let Ok(a) = x.cast::<PyArray1<f64>>() {
        // SAFETY: the GIL is held and the entries are copied out at once; no
        // Rust code of this package keeps a mutable view of a caller's array
        if let Ok(s) = unsafe { a.as_slice() } {
            if s.len() == out.len() && s.iter().all(|x| x.is_finite()) {
                out.as_mut_slice().copy_from_slice(s);
                return Ok(());
            }
        }
    }
    read_vec(x, "tau", "nv", out)
}

/// The most degrees of freedom for which an analytic call keeps the GIL: a
/// fixed-base arm's call takes a few µs, less than releasing and re-taking
/// the GIL is worth; longer calls (more dofs, finite differences) release it.
const HOLD_GIL_MAX_NV: usize = 12;

/// `sim.transition_jacobians(tau=None, method="analytic", eps=1e-6)`.
#[allow(clippy::type_complexity)]
pub fn transition_jacobians<'py>(
    py: Python<'py>,
    sim: &Simulation,
    tau: Option<&Bound<'py, PyAny>>,
    method_arg: &Given,
    eps: f64,
) -> PyResult<(Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>)> {
    let m = jacobian_method(py, method_arg)?;
    let mut t = DVector::zeros(sim.model.nv);
    if let Some(x) = tau.filter(|x| !x.is_none()) {
        read_tau(x, &mut t)?;
    }
    if !(eps > 0.0 && eps.is_finite()) {
        return Err(value_error(format!(
            "eps must be a positive number (got {eps})"
        )));
    }
    let j = if m == JacobianMethod::Analytic && sim.model.nv <= HOLD_GIL_MAX_NV {
        sim.transition_jacobians(&t, m, eps)
    } else {
        py.detach(|| sim.transition_jacobians(&t, m, eps))
    }
    .map_err(|e| value_error(e.to_string()))?;
    Ok((mat_out(py, &j.a), mat_out(py, &j.b)))
}

/// A pair of 3-vectors as numpy arrays.
#[allow(clippy::type_complexity)]
pub fn pair<'py>(
    py: Python<'py>,
    r: Result<(Vector3<f64>, Vector3<f64>), urdyn::sim::SimError>,
) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>)> {
    let (a, b) = r.map_err(|e| value_error(e.to_string()))?;
    Ok((
        PyArray1::from_slice(py, a.as_slice()),
        PyArray1::from_slice(py, b.as_slice()),
    ))
}

/// `urdyn.linearize(sim, q, v, tau, threads=None)`: A, B at each of T states,
/// in parallel (one workspace per rayon task), the GIL released.
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
pub fn linearize<'py>(
    py: Python<'py>,
    sim: &Simulation,
    q: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
    tau: &Bound<'py, PyAny>,
    threads: Option<usize>,
    method_name: &str,
    eps: f64,
) -> PyResult<(Bound<'py, PyArray3<f64>>, Bound<'py, PyArray3<f64>>)> {
    let m = method(method_name)?;
    let (nq, nv) = (sim.model.nq, sim.model.nv);
    let (qs, qd) = read_array(q, "q")?;
    let (vs, vd) = read_array(v, "v")?;
    let (ts, td) = read_array(tau, "tau")?;
    if qs.len() != 2 || qs[1] != nq {
        return Err(value_error(format!(
            "q has shape {qs:?}, expected (T, {nq}) (nq = {nq})"
        )));
    }
    let t = qs[0];
    if vs != [t, nv] {
        return Err(value_error(format!(
            "v has shape {vs:?}, expected ({t}, {nv}) (T, nv)"
        )));
    }
    if ts != [t, nv] {
        return Err(value_error(format!(
            "tau has shape {ts:?}, expected ({t}, {nv}) (T, nv)"
        )));
    }
    if threads == Some(0) {
        return Err(value_error("threads must be at least 1 (None: all cores)"));
    }
    if !(eps > 0.0 && eps.is_finite()) {
        return Err(value_error(format!(
            "eps must be a positive number (got {eps})"
        )));
    }
    let n = 2 * nv;
    let aa = PyArray3::<f64>::zeros(py, [t, n, n], false);
    let ba = PyArray3::<f64>::zeros(py, [t, n, nv], false);
    // SAFETY: fresh C-contiguous arrays no Python code has seen yet; the GIL
    // is released below but nothing else holds them.
    let ao = unsafe { aa.as_slice_mut() }.map_err(|e| value_error(e.to_string()))?;
    let bo = unsafe { ba.as_slice_mut() }.map_err(|e| value_error(e.to_string()))?;
    let run = |work: &mut Simulation,
               (i, (ao, bo)): (usize, (&mut [f64], &mut [f64]))|
     -> Result<(), String> {
        let qi = DVector::from_column_slice(&qd[i * nq..(i + 1) * nq]);
        let vi = DVector::from_column_slice(&vd[i * nv..(i + 1) * nv]);
        let ti = DVector::from_column_slice(&td[i * nv..(i + 1) * nv]);
        let j = work
            .transition_jacobians_at(&qi, &vi, &ti, m, eps)
            .map_err(|e| format!("state {i}: {e}"))?;
        for r in 0..n {
            for c in 0..n {
                ao[r * n + c] = j.a[(r, c)];
            }
            for c in 0..nv {
                bo[r * nv + c] = j.b[(r, c)];
            }
        }
        Ok(())
    };
    let r = py.detach(|| {
        // one workspace (a copy of the simulation) per thread: each takes a
        // contiguous run of states
        let mut work = move || -> Result<(), String> {
            let per = t.div_ceil(rayon::current_num_threads()).max(1);
            ao.par_chunks_mut((n * n * per).max(1))
                .zip(bo.par_chunks_mut((n * nv * per).max(1)))
                .enumerate()
                .try_for_each(|(ci, (ac, bc))| {
                    let mut w = sim.derivative_workspace();
                    ac.chunks_mut((n * n).max(1))
                        .zip(bc.chunks_mut((n * nv).max(1)))
                        .enumerate()
                        .try_for_each(|(k, pair)| run(&mut w, (ci * per + k, pair)))
                })
        };
        match threads {
            None => work(),
            Some(k) => crate::pool::pool(k)
                .map_err(|e| format!("threads: cannot start a thread pool: {e}"))
                .and_then(|pool| pool.install(work)),
        }
    });
    r.map_err(value_error)?;
    Ok((aa, ba))
}
