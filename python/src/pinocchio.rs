//! Pinocchio's configuration layout (python.md §"Vectors and conventions"):
//! `to_pinocchio_q` and `from_pinocchio_q`, a continuous joint's angle as
//! (cos θ, sin θ), a planar joint's (x, y, θ) as (x, y, cos θ, sin θ).

use crate::args::{normalize_quaternion_at, quat_offsets, read_q, read_vec, value_error};
use crate::model::PyModel;
use numpy::PyArray1;
use pyo3::prelude::*;
use urdyn::nalgebra::DVector;
use urdyn::Model;

/// How a joint's coordinates map to Pinocchio's: a continuous revolute joint's
/// θ is (cos θ, sin θ) (`JointModelRUB`), a planar joint's (x, y, θ) is
/// (x, y, cos θ, sin θ) (`JointModelPlanar`); every other coordinate is copied.
enum PinBlock {
    /// `n` coordinates copied (the base, prismatic, revolute, spherical, free).
    Copy(usize),
    /// A continuous joint: θ ↔ (cos θ, sin θ).
    Angle,
    /// A planar joint: (x, y, θ) ↔ (x, y, cos θ, sin θ).
    Planar,
}

/// The blocks of q in order with their joint names (the base's first when the
/// model floats), each with its quaternion's offset inside the block (a free
/// joint's at 3, a spherical joint's at 0), and Pinocchio's nq.
fn pinocchio_layout(model: &Model) -> (Vec<(PinBlock, String, Option<usize>)>, usize) {
    use urdyn::model::JointKind;
    // (iq, nq, block, name, quaternion offset): the free joints (bases), then
    // every joint that owns coordinates, in q order
    let mut joints: Vec<(usize, usize, PinBlock, String, Option<usize>)> = model
        .free_joints
        .iter()
        .map(|f| (f.iq, 7, PinBlock::Copy(7), f.name.clone(), Some(3)))
        .collect();
    for d in &model.dofs {
        if joints.iter().any(|j| j.0 == d.iq) {
            continue;
        }
        let (b, quat) = match d.kind {
            JointKind::Planar => (PinBlock::Planar, None),
            JointKind::Spherical => (PinBlock::Copy(4), Some(0)),
            JointKind::Free => (PinBlock::Copy(7), Some(3)),
            JointKind::Revolute(_) if d.continuous => (PinBlock::Angle, None),
            ref k => (PinBlock::Copy(k.nq()), None),
        };
        joints.push((d.iq, d.kind.nq(), b, d.name.clone(), quat));
    }
    joints.sort_by_key(|j| j.0);
    let mut blocks = Vec::new();
    let mut at = 0;
    for (iq, n, b, name, quat) in joints {
        if iq > at {
            // coordinates no joint claims (none expected): copied
            blocks.push((PinBlock::Copy(iq - at), String::new(), None));
        }
        blocks.push((b, name, quat));
        at = iq + n;
    }
    if model.nq > at {
        blocks.push((PinBlock::Copy(model.nq - at), String::new(), None));
    }
    let nq_pin = blocks
        .iter()
        .map(|(b, _, _)| match b {
            PinBlock::Copy(n) => *n,
            PinBlock::Angle => 2,
            PinBlock::Planar => 4,
        })
        .sum();
    (blocks, nq_pin)
}

/// Pinocchio's q of urdyn's `q`: each continuous joint's angle θ becomes the pair
/// (cos θ, sin θ) (Pinocchio's `JointModelRUB`), each planar joint's (x, y, θ)
/// becomes (x, y, cos θ, sin θ) (`JointModelPlanar`); every other coordinate,
/// the floating base's and the spherical joints' quaternions included, is
/// copied. The joints are in the same order in both (`model.dof_names`).
#[pyfunction]
pub fn to_pinocchio_q<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    q: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let m = &model.model;
    let mut qv = DVector::zeros(m.nq);
    read_q(q, "q", &quat_offsets(m), &mut qv)?;
    let (blocks, nq_pin) = pinocchio_layout(m);
    let mut out = Vec::with_capacity(nq_pin);
    let qs = qv.as_slice();
    let mut k = 0;
    for (b, _, _) in &blocks {
        match b {
            PinBlock::Copy(n) => {
                out.extend_from_slice(&qs[k..k + n]);
                k += n;
            }
            PinBlock::Angle => {
                // (cos θ, sin θ)
                out.extend_from_slice(&[qs[k].cos(), qs[k].sin()]);
                k += 1;
            }
            PinBlock::Planar => {
                // (x, y, cos θ, sin θ)
                let t = qs[k + 2];
                out.extend_from_slice(&[qs[k], qs[k + 1], t.cos(), t.sin()]);
                k += 3;
            }
        }
    }
    Ok(PyArray1::from_vec(py, out))
}

/// urdyn's q of Pinocchio's `q_pin` (of length `nq` of the Pinocchio model of the
/// same URDF, `pin.buildModelFromUrdf(path, mimic=True)`, where a mimic joint has
/// no coordinate of its own, as here): each continuous joint's pair (cos θ,
/// sin θ) becomes θ = atan2(sin θ, cos θ) in (−π, π], each planar joint's
/// (x, y, cos θ, sin θ) becomes (x, y, θ) likewise; every other coordinate is
/// copied. A pair (0, 0), a wrong length, a non-finite entry or a quaternion
/// (a floating base's or a spherical joint's) off unit norm is a `ValueError`.
#[pyfunction]
pub fn from_pinocchio_q<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    q_pin: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let m = &model.model;
    let (blocks, nq_pin) = pinocchio_layout(m);
    let mut qp = DVector::zeros(nq_pin);
    read_vec(q_pin, "q_pin", "Pinocchio's nq", &mut qp)?;
    let mut out = Vec::with_capacity(m.nq);
    let mut k = 0;
    let angle = |qp: &DVector<f64>, k: usize, kind: &str, name: &str| -> PyResult<f64> {
        let (c, s) = (qp[k], qp[k + 1]);
        if c == 0.0 && s == 0.0 {
            return Err(value_error(format!(
                "q_pin[{k}:{}]: the (cos, sin) pair of {kind} joint \"{name}\" is (0, 0)",
                k + 2
            )));
        }
        // θ = atan2(sin θ, cos θ)
        Ok(s.atan2(c))
    };
    for (b, name, quat) in &blocks {
        match b {
            PinBlock::Copy(n) => {
                if let Some(o) = quat.filter(|o| o + 4 <= *n) {
                    normalize_quaternion_at(
                        &mut qp.as_mut_slice()[k + o..k + o + 4],
                        "q_pin",
                        k + o,
                    )?;
                }
                out.extend_from_slice(&qp.as_slice()[k..k + n]);
                k += n;
            }
            PinBlock::Angle => {
                out.push(angle(&qp, k, "continuous", name)?);
                k += 2;
            }
            PinBlock::Planar => {
                out.extend_from_slice(&[qp[k], qp[k + 1], angle(&qp, k + 2, "planar", name)?]);
                k += 4;
            }
        }
    }
    Ok(PyArray1::from_vec(py, out))
}
