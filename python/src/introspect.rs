//! What a model says about itself (python.md §"Introspection, contacts, batched
//! control, pictures"): where each joint's and each scene model's coordinates
//! sit in q and v, the limits, the joint dynamics the simulation uses, and each
//! link's own `<inertial>`. The `Model` getters in `model.rs` call these.

use crate::args::value_error;
use pyo3::prelude::*;
use std::collections::HashMap;
use std::ops::Range;
use urdyn::nalgebra::{Matrix3, Rotation3, Vector3};
use urdyn::Model;

/// A link's own `<inertial>`: mass (kg), centre of mass (m) and the inertia
/// about it (kg·m²), both in the link frame.
#[derive(Clone, Debug)]
pub struct LinkInertial {
    pub mass: f64,
    pub com: Vector3<f64>,
    pub inertia: Matrix3<f64>,
}

/// Every link's `<inertial>` of the URDF `text`, names prefixed by `prefix`
/// (a scene's `MODEL/`). The origin's rotation R turns the URDF's inertia
/// (about the centre of mass, in the inertial frame) into the link frame:
/// I_link = R I Rᵀ, R = Rz(yaw) Ry(pitch) Rx(roll) as URDF's rpy. A text urdyn
/// cannot read gives none (the model's import read it already).
pub fn link_inertials(text: &str, prefix: &str) -> HashMap<String, LinkInertial> {
    let Ok(robot) = urdyn::urdf::read_robot(text, "") else {
        return HashMap::new();
    };
    robot
        .links
        .iter()
        .map(|l| {
            let i = &l.inertial;
            let [r, p, y] = i.origin.rpy.0;
            let rot = Rotation3::from_euler_angles(r, p, y);
            let a = &i.inertia;
            let local = Matrix3::new(
                a.ixx, a.ixy, a.ixz, a.ixy, a.iyy, a.iyz, a.ixz, a.iyz, a.izz,
            );
            let inertia = rot.matrix() * local * rot.matrix().transpose();
            (
                format!("{prefix}{}", l.name),
                LinkInertial {
                    mass: i.mass.value,
                    com: Vector3::from(i.origin.xyz.0),
                    inertia,
                },
            )
        })
        .collect()
}

/// Every body's own inertial of the MJCF `text` (includes and meshes read
/// under `dir`), as MuJoCo compiles it (`body_mass`, `body_ipos`, and the
/// inertia about the centre of mass, `body_iquat`·diag(`body_inertia`), in the
/// body frame): from `<inertial>`, or from the geoms where there is none. A
/// text that does not compile gives none (the model's import read it already).
pub fn mjcf_inertials(
    text: &str,
    file: &str,
    dir: &std::path::Path,
) -> HashMap<String, LinkInertial> {
    let Ok(world) = urdyn::mjcf::compile_str(text, file, dir) else {
        return HashMap::new();
    };
    world
        .bodies
        .iter()
        .skip(1)
        .map(|b| {
            (
                b.name.clone(),
                LinkInertial {
                    mass: b.mass,
                    com: b.com,
                    inertia: b.inertia,
                },
            )
        })
        .collect()
}

/// The name a lone URDF's one model goes by in `model.models` and
/// `model_q_slice` (a scene's models by their own names).
pub const LONE_MODEL: &str = "robot";

/// The models of `model` in q order, with their q and v ranges.
pub fn models(model: &Model) -> Vec<(String, Range<usize>, Range<usize>)> {
    model
        .trees
        .iter()
        .map(|t| {
            let name = if t.name.is_empty() {
                LONE_MODEL.to_string()
            } else {
                t.name.clone()
            };
            (name, t.q.clone(), t.v.clone())
        })
        .collect()
}

/// The q and v ranges of the model `name` (a lone URDF: `"robot"` or its
/// robot's name).
pub fn model_ranges(model: &Model, name: &str) -> PyResult<(Range<usize>, Range<usize>)> {
    let all = models(model);
    let lone = all.len() == 1 && model.trees[0].name.is_empty();
    all.iter()
        .find(|(n, _, _)| n == name || (lone && name == model.name))
        .map(|(_, q, v)| (q.clone(), v.clone()))
        .ok_or_else(|| {
            let names: Vec<&str> = all.iter().map(|m| m.0.as_str()).collect();
            value_error(format!(
                "unknown model \"{name}\" (the models: {})",
                names.join(", ")
            ))
        })
}

/// The q and v ranges of joint `name`: a floating base's free joint (`"base"`,
/// a scene's `"MODEL/base"`) 7 and 6 entries, any other joint its own
/// (mechanisms.md: a 1-DoF joint one each, a spherical 4 and 3, ...). A mimic
/// joint (no coordinate of its own) or an unknown name is a `ValueError`.
pub fn joint_ranges(model: &Model, name: &str) -> PyResult<(Range<usize>, Range<usize>)> {
    if let Some(f) = model.free_joints.iter().find(|f| f.name == name) {
        return Ok((f.iq..f.iq + 7, f.iv..f.iv + 6));
    }
    if let Some(d) = model.dofs.iter().find(|d| d.name == name) {
        return Ok((d.iq..d.iq + d.kind.nq(), d.iv..d.iv + d.kind.nv()));
    }
    if let Ok(id) = model.joint_id(name) {
        if model.is_mimic(id) {
            return Err(value_error(format!(
                "joint \"{name}\" is a mimic joint: it follows its leader and has no coordinate of its own"
            )));
        }
    }
    let names = model
        .free_joints
        .iter()
        .map(|f| f.name.as_str())
        .chain(model.dofs.iter().map(|d| d.name.as_str()));
    let near = urdyn::model::nearest(name, names)
        .map(|k| format!(" (nearest: \"{k}\")"))
        .unwrap_or_default();
    Err(value_error(format!(
        "unknown joint \"{name}\" (not a degree of freedom of the model){near}"
    )))
}

/// (lower, upper) position limits per q entry: a 1-DoF joint's `<limit>`
/// (−∞/+∞ where none, and always for a continuous joint), ±∞ on a free joint's 7.
pub fn position_limits(model: &Model) -> (Vec<f64>, Vec<f64>) {
    let mut lo = vec![f64::NEG_INFINITY; model.nq];
    let mut hi = vec![f64::INFINITY; model.nq];
    for (d, iq, _) in model.dof_indices() {
        let info = &model.dofs[d];
        if info.continuous {
            continue;
        }
        lo[iq] = info.limits.lower.unwrap_or(f64::NEG_INFINITY);
        hi[iq] = info.limits.upper.unwrap_or(f64::INFINITY);
    }
    (lo, hi)
}

/// A per-v value of each degree of freedom (`fill` on a free joint's 6).
pub fn per_dof(model: &Model, fill: f64, f: impl Fn(&urdyn::model::DofInfo) -> f64) -> Vec<f64> {
    let mut out = vec![fill; model.nv];
    for (d, _, iv) in model.dof_indices() {
        out[iv] = f(&model.dofs[d]);
    }
    out
}

/// `slice(range.start, range.end)` (step None, as Python's own).
pub fn py_slice<'py>(py: Python<'py>, r: &Range<usize>) -> PyResult<Bound<'py, PyAny>> {
    py.get_type::<pyo3::types::PySlice>()
        .call1((r.start, r.end))
}
