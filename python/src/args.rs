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

/// Normalises the quaternion `quat` (`[qx, qy, qz, qw]`, entries `name[at:at + 4]`:
/// a floating base's orientation, a scene's later floating model's, a spherical
/// joint's) in place, as the CLI does; a `ValueError` with the CLI's message
/// ("not a unit quaternion (norm N)") unless its norm is within
/// [`QUATERNION_TOLERANCE`] of 1.
pub fn normalize_quaternion_at(quat: &mut [f64], name: &str, at: usize) -> PyResult<()> {
    // |q| = sqrt(qx² + qy² + qz² + qw²)
    let n = quat.iter().map(|x| x * x).sum::<f64>().sqrt();
    if (n - 1.0).abs() <= QUATERNION_TOLERANCE {
        quat.iter_mut().for_each(|x| *x /= n);
        Ok(())
    } else {
        Err(value_error(format!(
            "{name}[{at}:{}] (a quaternion qx, qy, qz, qw: a floating base's orientation or a spherical joint's): not a unit quaternion (norm {n})",
            at + 4
        )))
    }
}

/// `repr(x)` for an error message ("?" if it fails).
pub fn shown(x: &Bound<'_, PyAny>) -> String {
    x.repr()
        .map(|r| r.to_string())
        .unwrap_or_else(|_| "?".into())
}

/// A count (`n`, `nstep`, `threads`): a whole number ≥ `min`; a negative number,
/// a float (`2.5`, even `2.0`), a bool or anything else is a `ValueError` naming
/// `name`.
pub fn read_count(x: &Bound<'_, PyAny>, name: &str, min: i64) -> PyResult<usize> {
    let bad = |what: String| {
        value_error(format!(
            "{name} must be a whole number ≥ {min} (got {what})"
        ))
    };
    let shown = || shown(x);
    if x.is_instance_of::<pyo3::types::PyBool>() || x.is_instance_of::<pyo3::types::PyFloat>() {
        return Err(bad(shown()));
    }
    let k: i64 = x.extract().map_err(|_| bad(shown()))?;
    if k < min {
        return Err(bad(k.to_string()));
    }
    usize::try_from(k).map_err(|_| bad(k.to_string()))
}

/// `threads=None` or a count ≥ 1.
pub fn read_threads(x: Option<&Bound<'_, PyAny>>) -> PyResult<Option<usize>> {
    match x {
        Some(t) if !t.is_none() => {
            let n = read_count(t, "threads", 1)?;
            // the library's bound (a batch's pool is started here, before any
            // simulation checks its own options)
            if n > urdyn::sim::MAX_THREADS {
                return Err(value_error(format!(
                    "threads must be at most {} (got {n})",
                    urdyn::sim::MAX_THREADS
                )));
            }
            Ok(Some(n))
        }
        _ => Ok(None),
    }
}

/// A keyword whose omission is told apart from every value it may be given,
/// `None` included (`ground=` beside a scene is an error even at its default).
pub enum Given {
    /// Not passed.
    Omitted,
    /// Passed, with this value.
    Value(Py<PyAny>),
}

impl<'a, 'py> FromPyObject<'a, 'py> for Given {
    type Error = PyErr;
    fn extract(obj: pyo3::Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        Ok(Given::Value(obj.to_owned().unbind()))
    }
}

impl Given {
    /// Whether the keyword was passed.
    pub fn given(&self) -> bool {
        matches!(self, Given::Value(_))
    }
    /// `ground=`: omitted → 0.0, `None` → no ground, else a number.
    pub fn ground(&self, py: Python<'_>) -> PyResult<Option<f64>> {
        match self {
            Given::Omitted => Ok(Some(0.0)),
            Given::Value(v) if v.is_none(py) => Ok(None),
            Given::Value(v) => v.extract::<f64>(py).map(Some).map_err(|_| {
                value_error("ground must be a number (the plane's height, m) or None (no ground)")
            }),
        }
    }
    /// `friction=`: omitted → 1.0, else a number.
    pub fn friction(&self, py: Python<'_>) -> PyResult<f64> {
        match self {
            Given::Omitted => Ok(1.0),
            Given::Value(v) => v
                .extract::<f64>(py)
                .map_err(|_| value_error("friction must be a number (the Coulomb coefficient)")),
        }
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
        normalize_quaternion_at(&mut out.as_mut_slice()[at..at + 4], name, at)?;
    }
    Ok(())
}

/// The offsets in q of every quaternion: each free joint's (`iq + 3`, the
/// floating base's and an MJCF body's inner free joint alike) and each
/// spherical joint's (`iq`), in q order.
pub fn quat_offsets(model: &urdyn::Model) -> Vec<usize> {
    use urdyn::model::JointKind;
    let mut out: Vec<usize> = model.free_joints.iter().map(|f| f.iq + 3).collect();
    out.extend(model.joints.iter().skip(1).filter_map(|j| match j.kind {
        JointKind::Free => Some(j.iq + 3),
        JointKind::Spherical => Some(j.iq),
        _ => None,
    }));
    out.sort_unstable();
    out.dedup();
    out
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

/// A number argument `name`: an int or a float (not a bool), else a `ValueError`
/// naming `name` (pyo3's own conversion would raise a `TypeError`).
pub fn read_real(x: &Bound<'_, PyAny>, name: &str) -> PyResult<f64> {
    let bad = || {
        let shown = shown(x);
        value_error(format!("{name} must be a number (got {shown})"))
    };
    if x.is_instance_of::<pyo3::types::PyBool>() {
        return Err(bad());
    }
    x.extract::<f64>().map_err(|_| bad())
}

/// A flag argument `name`: `True` or `False` (a numpy bool too), else a
/// `ValueError` naming `name`.
pub fn read_flag(x: &Bound<'_, PyAny>, name: &str) -> PyResult<bool> {
    let is_bool = x.is_instance_of::<pyo3::types::PyBool>()
        || x.get_type()
            .name()
            .map(|n| n.to_string() == "bool" || n.to_string() == "bool_")
            .unwrap_or(false);
    let bad = || {
        let shown = shown(x);
        value_error(format!("{name} must be True or False (got {shown})"))
    };
    if !is_bool {
        return Err(bad());
    }
    x.is_truthy().map_err(|_| bad())
}

/// A string argument `name` (a `str`, numpy's too), else a `ValueError` naming it.
pub fn read_text(x: &Bound<'_, PyAny>, name: &str) -> PyResult<String> {
    if !x.is_instance_of::<pyo3::types::PyString>() {
        let shown = shown(x);
        return Err(value_error(format!(
            "{name} must be a string (got {shown})"
        )));
    }
    x.extract::<String>()
        .map_err(|e| value_error(format!("{name}: {e}")))
}

/// A path argument `name` (a `str` or an `os.PathLike`), else a `ValueError`
/// naming it.
pub fn read_path(x: &Bound<'_, PyAny>, name: &str) -> PyResult<std::path::PathBuf> {
    x.extract::<std::path::PathBuf>().map_err(|_| {
        let shown = shown(x);
        value_error(format!(
            "{name} must be a path: a str or os.PathLike (got {shown})"
        ))
    })
}

/// Readers of single keyword arguments for `#[pyo3(from_py_with = ...)]`: a
/// wrong type is a `ValueError` naming the argument (python.md §"Introspection,
/// contacts, batched control, pictures"), not pyo3's `TypeError`.
pub mod named {
    use super::{read_count, read_flag, read_path, read_real, read_text, shown};
    use pyo3::prelude::*;
    use std::path::PathBuf;

    macro_rules! real {
        ($f:ident, $name:literal) => {
            pub fn $f(x: &Bound<'_, PyAny>) -> PyResult<f64> {
                read_real(x, $name)
            }
        };
    }
    macro_rules! real_or_none {
        ($f:ident, $name:literal) => {
            pub fn $f(x: &Bound<'_, PyAny>) -> PyResult<Option<f64>> {
                if x.is_none() {
                    return Ok(None);
                }
                read_real(x, $name).map(Some)
            }
        };
    }
    macro_rules! flag {
        ($f:ident, $name:literal) => {
            pub fn $f(x: &Bound<'_, PyAny>) -> PyResult<bool> {
                read_flag(x, $name)
            }
        };
    }
    macro_rules! flag_or_none {
        ($f:ident, $name:literal) => {
            pub fn $f(x: &Bound<'_, PyAny>) -> PyResult<Option<bool>> {
                if x.is_none() {
                    return Ok(None);
                }
                read_flag(x, $name).map(Some)
            }
        };
    }
    macro_rules! text {
        ($f:ident, $name:literal) => {
            pub fn $f(x: &Bound<'_, PyAny>) -> PyResult<String> {
                read_text(x, $name)
            }
        };
    }
    macro_rules! text_or_none {
        ($f:ident, $name:literal) => {
            pub fn $f(x: &Bound<'_, PyAny>) -> PyResult<Option<String>> {
                if x.is_none() {
                    return Ok(None);
                }
                read_text(x, $name).map(Some)
            }
        };
    }
    macro_rules! path {
        ($f:ident, $name:literal) => {
            pub fn $f(x: &Bound<'_, PyAny>) -> PyResult<PathBuf> {
                read_path(x, $name)
            }
        };
    }
    text!(link, "link");
    text!(reference, "reference");
    text!(method, "method");
    text!(name, "name");
    text!(model_name, "model_name");
    text!(xml, "xml");
    text!(text, "text");
    text_or_none!(integrator, "integrator");
    path!(path, "path");
    path!(base_dir, "base_dir");
    /// `base_dir=None` or a path.
    pub fn base_dir_or_none(x: &Bound<'_, PyAny>) -> PyResult<Option<PathBuf>> {
        if x.is_none() {
            return Ok(None);
        }
        read_path(x, "base_dir").map(Some)
    }
    /// `package_dirs=None` or a list of paths.
    pub fn package_dirs(x: &Bound<'_, PyAny>) -> PyResult<Option<Vec<PathBuf>>> {
        if x.is_none() {
            return Ok(None);
        }
        let bad = || {
            let shown = shown(x);
            super::value_error(format!(
                "package_dirs must be a list of paths (got {shown})"
            ))
        };
        if x.is_instance_of::<pyo3::types::PyString>() {
            return Err(bad());
        }
        let mut out = Vec::new();
        for item in x.try_iter().map_err(|_| bad())? {
            let item = item.map_err(|_| bad())?;
            out.push(read_path(&item, "package_dirs[...]")?);
        }
        Ok(Some(out))
    }
    real!(dt, "dt");
    real!(eps, "eps");
    real_or_none!(time, "time");
    flag!(on, "on");
    flag!(floating_base, "floating_base");
    flag_or_none!(sleep, "sleep");
    /// `seed`: a whole number ≥ 0.
    pub fn seed(x: &Bound<'_, PyAny>) -> PyResult<u64> {
        read_count(x, "seed", 0).map(|k| k as u64)
    }
}
