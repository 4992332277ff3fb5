//! The derivatives of the dynamics and the configuration manifold
//! (python.md §"Configurations", §"Derivatives"): each checks its arguments,
//! calls the library, and returns new arrays.

use crate::args::named;
use crate::args::{read3, read_vec, value_error};
use crate::dynamics::{dyn_error, mat_out, read_qv, read_qvx, reference};
use crate::model::{PyData, PyModel};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PySequence};
use urdyn::dynamics::{self, LinkWrench};
use urdyn::model::{configuration, FrameId};
use urdyn::nalgebra::{DMatrix, DVector, Vector3};

/// Registers this file's functions.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(rnea_derivatives, m)?)?;
    m.add_function(wrap_pyfunction!(aba_derivatives, m)?)?;
    m.add_function(wrap_pyfunction!(frame_jacobian_time_variation, m)?)?;
    m.add_function(wrap_pyfunction!(integrate, m)?)?;
    m.add_function(wrap_pyfunction!(difference, m)?)?;
    m.add_function(wrap_pyfunction!(random_configuration, m)?)?;
    Ok(())
}

/// The `fext` dict `{link: (force3, torque3)}` (world frame, at the link origins)
/// as link wrenches, held fixed in world coordinates by the derivatives.
fn wrenches(model: &PyModel, fext: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<LinkWrench>> {
    let mut out = Vec::new();
    let Some(dict) = fext else { return Ok(out) };
    for (key, value) in dict.iter() {
        let name: String = key
            .extract()
            .map_err(|_| value_error("fext: keys must be link names (str)"))?;
        let fi = model.link(&name, "fext")?;
        let pair = value
            .cast::<PySequence>()
            .map_err(|_| value_error(format!("fext[\"{name}\"]: expected (force3, torque3)")))?;
        if pair.len().unwrap_or(0) != 2 {
            return Err(value_error(format!(
                "fext[\"{name}\"]: expected (force3, torque3)"
            )));
        }
        let f = read3(&pair.get_item(0)?, &format!("fext[\"{name}\"] force"))?;
        let t = read3(&pair.get_item(1)?, &format!("fext[\"{name}\"] torque"))?;
        out.push(LinkWrench {
            frame: FrameId(fi),
            force: Vector3::from(f),
            torque: Vector3::from(t),
        });
    }
    Ok(out)
}

type Mat<'py> = Bound<'py, PyArray2<f64>>;

/// `(dtau_dq, dtau_dv, M)`: the derivatives of inverse dynamics at (q, v, a), ∂/∂q
/// in the tangent space as `integrate` moves q (Pinocchio's
/// `computeRNEADerivatives`); `fext` held fixed in world coordinates.
#[pyfunction]
#[pyo3(signature = (model, data, q, v, a, fext=None))]
pub fn rnea_derivatives<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
    a: &Bound<'py, PyAny>,
    fext: Option<&Bound<'py, PyDict>>,
) -> PyResult<(Mat<'py>, Mat<'py>, Mat<'py>)> {
    let d = &mut *data;
    read_qvx(&model, d, q, v, a, "a")?;
    let w = wrenches(&model, fext)?;
    let wf = (!w.is_empty()).then_some(w.as_slice());
    dynamics::rnea_derivatives(&model.model, &mut d.data, &d.q, &d.v, &d.a, wf)
        .map_err(|e| dyn_error(&model, e))?;
    let x = &d.data;
    Ok((
        mat_out(py, &x.dtau_dq),
        mat_out(py, &x.dtau_dv),
        mat_out(py, &x.h),
    ))
}

/// `(dqdd_dq, dqdd_dv, Minv)`: the derivatives of forward dynamics at (q, v, tau)
/// (Pinocchio's `computeABADerivatives`), every model (mimic ones by the reduced
/// system); `fext` held fixed in world coordinates.
#[pyfunction]
#[pyo3(signature = (model, data, q, v, tau, fext=None))]
pub fn aba_derivatives<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
    tau: &Bound<'py, PyAny>,
    fext: Option<&Bound<'py, PyDict>>,
) -> PyResult<(Mat<'py>, Mat<'py>, Mat<'py>)> {
    let d = &mut *data;
    read_qvx(&model, d, q, v, tau, "tau")?;
    let w = wrenches(&model, fext)?;
    let wf = (!w.is_empty()).then_some(w.as_slice());
    dynamics::aba_derivatives(&model.model, &mut d.data, &d.q, &d.v, &d.a, wf)
        .map_err(|e| dyn_error(&model, e))?;
    let x = &d.data;
    Ok((
        mat_out(py, &x.dqdd_dq),
        mat_out(py, &x.dqdd_dv),
        mat_out(py, &x.minv),
    ))
}

/// The 6 × nv time variation of link `link`'s Jacobian at (q, v) (Pinocchio's
/// `getFrameJacobianTimeVariation`, LOCAL_WORLD_ALIGNED or LOCAL).
#[pyfunction]
#[pyo3(
    signature = (model, data, q, v, link, reference=String::from("world_aligned")),
    text_signature = "(model, data, q, v, link, reference='world_aligned')"
)]
pub fn frame_jacobian_time_variation<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
    #[pyo3(from_py_with = named::link)] link: String,
    #[pyo3(from_py_with = named::reference)] reference: String,
) -> PyResult<Mat<'py>> {
    let r = self::reference(&reference)?;
    let d = &mut *data;
    read_qv(&model, d, q, v)?;
    let i = model.link(&link, "link")?;
    let mut jd = DMatrix::zeros(6, model.model.nv);
    dynamics::frame_jacobian_time_variation(
        &model.model,
        &mut d.data,
        &d.q,
        &d.v,
        FrameId(i),
        r,
        &mut jd,
    )
    .map_err(|e| dyn_error(&model, e))?;
    Ok(mat_out(py, &jd))
}

fn vec_in(x: &Bound<'_, PyAny>, name: &str, what: &str, n: usize) -> PyResult<DVector<f64>> {
    let mut out = DVector::zeros(n);
    read_vec(x, name, what, &mut out)?;
    Ok(out)
}

/// `q ⊕ dq` (Pinocchio's `integrate`: a free base along SE(3)'s exponential by a
/// body-frame twist).
#[pyfunction]
pub fn integrate<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    q: &Bound<'py, PyAny>,
    dq: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let m = &model.model;
    let quats = crate::args::quat_offsets(m);
    let mut qv = DVector::zeros(m.nq);
    crate::args::read_q(q, "q", &quats, &mut qv)?;
    let dq = vec_in(dq, "dq", "nv", m.nv)?;
    let out = configuration::integrate(m, &qv, &dq).map_err(|e| value_error(e.to_string()))?;
    Ok(PyArray1::from_slice(py, out.as_slice()))
}

/// `dq` with `q0 ⊕ dq = q1` (Pinocchio's `difference`).
#[pyfunction]
pub fn difference<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    q0: &Bound<'py, PyAny>,
    q1: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let m = &model.model;
    let quats = crate::args::quat_offsets(m);
    let (mut a, mut b) = (DVector::zeros(m.nq), DVector::zeros(m.nq));
    crate::args::read_q(q0, "q0", &quats, &mut a)?;
    crate::args::read_q(q1, "q1", &quats, &mut b)?;
    let out = configuration::difference(m, &a, &b).map_err(|e| value_error(e.to_string()))?;
    Ok(PyArray1::from_slice(py, out.as_slice()))
}

/// A random configuration inside the joint limits with a unit base quaternion,
/// reproducible from `seed`.
#[pyfunction]
#[pyo3(signature = (model, seed=0))]
pub fn random_configuration<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    #[pyo3(from_py_with = named::seed)] seed: u64,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let q = configuration::random_configuration(&model.model, seed);
    Ok(PyArray1::from_slice(py, q.as_slice()))
}
