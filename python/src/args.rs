//! Argument conversion: array-likes in, checked lengths and finite numbers, one
//! clear `ValueError` line naming the argument otherwise.

use numpy::{AllowTypeChange, PyArrayLike1, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{PyFileNotFoundError, PyValueError};
use pyo3::prelude::*;
use urdyn::nalgebra::DVector;

/// A `ValueError` with this message.
pub fn value_error(msg: impl Into<String>) -> PyErr {
    PyValueError::new_err(msg.into())
}

/// A `FileNotFoundError` with this message (a URDF, mesh or scene file that does
/// not exist; the message names the path).
pub fn not_found_error(msg: impl Into<String>) -> PyErr {
    PyFileNotFoundError::new_err(msg.into())
}

/// The largest distance from unit norm a base quaternion may have: the CLI's
/// tolerance for `base.orientation_xyzw` (src/cli/state.rs).
pub const QUATERNION_TOLERANCE: f64 = 1e-3;

/// Normalises `quat` (a floating base's `[qx, qy, qz, qw]`, entries 3..7 of
/// `name`) in place, as the CLI does; a `ValueError` with the CLI's message
/// ("not a unit quaternion (norm N)") unless its norm is within
/// [`QUATERNION_TOLERANCE`] of 1.
pub fn normalize_base_quaternion(quat: &mut [f64], name: &str) -> PyResult<()> {
    // |q| = sqrt(qx² + qy² + qz² + qw²)
    let n = quat.iter().map(|x| x * x).sum::<f64>().sqrt();
    if (n - 1.0).abs() <= QUATERNION_TOLERANCE {
        quat.iter_mut().for_each(|x| *x /= n);
        Ok(())
    } else {
        Err(value_error(format!(
            "{name}[3:7] (the base orientation qx, qy, qz, qw): not a unit quaternion (norm {n})"
        )))
    }
}

/// Copies q (length nq) into `out` and checks each free joint's quaternion
/// (`quats`: their offsets in q, from [`quat_offsets`]) with
/// [`normalize_base_quaternion`]. Every q of the package is read here.
pub fn read_q(
    x: &Bound<'_, PyAny>,
    name: &str,
    quats: &[usize],
    out: &mut DVector<f64>,
) -> PyResult<()> {
    read_vec(x, name, "nq", out)?;
    for &at in quats {
        normalize_base_quaternion(&mut out.as_mut_slice()[at..at + 4], name)?;
    }
    Ok(())
}

/// The offsets in q of every free joint's quaternion (`iq + 3`).
pub fn quat_offsets(model: &urdyn::Model) -> Vec<usize> {
    model.free_joints.iter().map(|f| f.iq + 3).collect()
}

/// Copies the 1-D array-like `x` into `out` (length `n`, the model's `what`):
/// a wrong length, another shape or a non-finite entry is a `ValueError`
/// naming `name`.
pub fn read_vec(
    x: &Bound<'_, PyAny>,
    name: &str,
    what: &str,
    out: &mut DVector<f64>,
) -> PyResult<()> {
    let n = out.len();
    let arr: PyArrayLike1<'_, f64, AllowTypeChange> = x.extract().map_err(|_| {
        value_error(format!(
            "{name}: expected a 1-D array of {n} numbers ({what} = {n})"
        ))
    })?;
    if arr.len() != n {
        return Err(value_error(format!(
            "{name} has {} entries, the model has {what} = {n}",
            arr.len()
        )));
    }
    let view = arr.as_array();
    for (i, (o, &x)) in out.iter_mut().zip(view.iter()).enumerate() {
        if !x.is_finite() {
            return Err(value_error(format!(
                "{name}[{i}] is not a finite number ({x})"
            )));
        }
        *o = x;
    }
    Ok(())
}

/// A 3-vector (`name` in messages).
pub fn read3(x: &Bound<'_, PyAny>, name: &str) -> PyResult<[f64; 3]> {
    let mut v = DVector::zeros(3);
    read_vec(x, name, "length", &mut v)?;
    Ok([v[0], v[1], v[2]])
}

/// A contiguous float64 copy of an array-like of any dimension, with its shape
/// (`name` in messages).
pub fn read_array(x: &Bound<'_, PyAny>, name: &str) -> PyResult<(Vec<usize>, Vec<f64>)> {
    let py = x.py();
    let np = py.import("numpy")?;
    let arr = np
        .call_method1("ascontiguousarray", (x, "float64"))
        .map_err(|e| value_error(format!("{name}: not an array of numbers ({e})")))?;
    let arr = arr
        .cast::<numpy::PyArrayDyn<f64>>()
        .map_err(|_| value_error(format!("{name}: not an array of numbers")))?;
    let ro = arr.readonly();
    let shape = ro.shape().to_vec();
    let data = ro
        .as_slice()
        .map_err(|_| value_error(format!("{name}: not a contiguous array")))?
        .to_vec();
    if let Some(i) = data.iter().position(|x| !x.is_finite()) {
        return Err(value_error(format!(
            "{name}: entry {i} (flat index) is not a finite number ({})",
            data[i]
        )));
    }
    Ok((shape, data))
}
