//! States JSON (eval-contract.md): parsing with every key checked, and conversion
//! of one state into the engine's q, v, a, τ vectors.

use crate::model::{FrameId, Model};
use nalgebra::{DVector, Vector3};
use serde::Deserialize;
use std::collections::BTreeMap;

/// A bad states file: names the file and the key.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}: {key}: {message}")]
pub struct StateError {
    /// The file.
    pub file: String,
    /// The key path in it (`states[3].q.elbow`).
    pub key: String,
    /// What is wrong with it.
    pub message: String,
}

impl StateError {
    fn new(file: &str, key: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            file: file.into(),
            key: key.into(),
            message: message.into(),
        }
    }
}

/// The `base` object of a state (body-frame quantities of the root link's origin).
#[derive(Debug, Clone, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BaseState {
    /// World position of the root link's origin (m).
    pub position: Option<[f64; 3]>,
    /// Orientation, quaternion x, y, z, w (normalised if within 1e-3 of unit norm).
    pub orientation_xyzw: Option<[f64; 4]>,
    /// Body-frame linear velocity of the root origin (m/s).
    pub linear_velocity: Option<[f64; 3]>,
    /// Body-frame angular velocity (rad/s).
    pub angular_velocity: Option<[f64; 3]>,
    /// Body-frame spatial linear acceleration (m/s², the derivative of `linear_velocity`).
    pub linear_acceleration: Option<[f64; 3]>,
    /// Body-frame angular acceleration (rad/s²).
    pub angular_acceleration: Option<[f64; 3]>,
    /// The base's generalized force: a force at the root origin, body frame (N).
    pub force: Option<[f64; 3]>,
    /// The base's generalized torque, body frame (N·m).
    pub torque: Option<[f64; 3]>,
}

/// An external wrench on a URDF link (eval-contract.md, "fext"): world
/// coordinates, the force acting at the link frame's origin, the torque a pure couple.
#[derive(Debug, Clone, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LinkWrench {
    /// Force (N), world coordinates, at the link frame's origin (zero if left out).
    pub force: Option<[f64; 3]>,
    /// Couple (N·m), world coordinates (zero if left out).
    pub torque: Option<[f64; 3]>,
}

/// A joint's value in a state's `q`, `v`, `a` or `tau`: a number for a 1-DoF joint,
/// an array for a joint of several degrees of freedom (mechanisms.md "In `eval`
/// (version 4)").
#[derive(Debug, Clone, PartialEq)]
pub enum JointValue {
    /// One number (revolute, continuous, prismatic).
    Scalar(f64),
    /// Several numbers (spherical, planar, floating).
    Array(Vec<f64>),
}

impl<'de> Deserialize<'de> for JointValue {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = JointValue;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number or an array of numbers")
            }
            fn visit_f64<E>(self, x: f64) -> Result<JointValue, E> {
                Ok(JointValue::Scalar(x))
            }
            fn visit_i64<E>(self, x: i64) -> Result<JointValue, E> {
                Ok(JointValue::Scalar(x as f64))
            }
            fn visit_u64<E>(self, x: u64) -> Result<JointValue, E> {
                Ok(JointValue::Scalar(x as f64))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut a: A,
            ) -> Result<JointValue, A::Error> {
                let mut out = Vec::new();
                while let Some(x) = a.next_element::<f64>()? {
                    out.push(x);
                }
                Ok(JointValue::Array(out))
            }
        }
        d.deserialize_any(V)
    }
}

/// One state: joint maps keyed by URDF joint name, the base, external wrenches by
/// link and the links whose kinematics the result reports.
#[derive(Debug, Clone, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct State {
    /// Joint positions by joint name (rad or m; an array for a joint of several
    /// degrees of freedom).
    pub q: Option<BTreeMap<String, JointValue>>,
    /// Joint velocities by joint name.
    pub v: Option<BTreeMap<String, JointValue>>,
    /// Joint accelerations by joint name.
    pub a: Option<BTreeMap<String, JointValue>>,
    /// Joint efforts by joint name (N·m or N).
    pub tau: Option<BTreeMap<String, JointValue>>,
    /// The floating base (read with `--floating-base` only).
    pub base: Option<BaseState>,
    /// External wrenches keyed by URDF link name.
    pub fext: Option<BTreeMap<String, LinkWrench>>,
    /// URDF links whose frame kinematics the result reports.
    pub frames: Option<Vec<String>>,
    /// Whether the result carries the derivatives (contract version 3).
    pub derivatives: Option<bool>,
}

/// A whole `STATES.json`.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct StatesFile {
    /// Gravity in the world frame (default `[0, 0, -9.81]`).
    pub gravity: Option<[f64; 3]>,
    /// The states to evaluate.
    pub states: Vec<State>,
    /// Loop constraints for every state (mechanisms.md §"In `eval` (version 4)").
    #[serde(default)]
    pub constraints: Option<serde_json::Value>,
}

/// The vectors of one state, in engine order.
#[derive(Debug, Clone, PartialEq)]
pub struct StateVectors {
    /// Configuration (nq).
    pub q: DVector<f64>,
    /// Velocity (nv).
    pub v: DVector<f64>,
    /// Acceleration (nv).
    pub a: DVector<f64>,
    /// Generalized forces: joint `tau` and, with a floating base, `base.force/torque`.
    pub tau: DVector<f64>,
    /// External wrenches: link, force, torque (world coordinates), in key order.
    pub fext: Vec<(FrameId, Vector3<f64>, Vector3<f64>)>,
    /// The links asked for in `frames`, in the file's order.
    pub frames: Vec<FrameId>,
    /// Whether the state asked for the derivatives (`"derivatives": true`).
    pub derivatives: bool,
}

fn parse_json<'a, D: Deserialize<'a>>(text: &'a str, file: &str) -> Result<D, StateError> {
    let de = &mut serde_json::Deserializer::from_str(text);
    let value: D = serde_path_to_error::deserialize(&mut *de).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.inner();
        let syntax = inner.is_syntax() || inner.is_eof();
        let key = if path == "." || path == "?" || path.is_empty() {
            "(top level)".to_string()
        } else {
            path
        };
        let msg = inner.to_string();
        let msg = if msg.starts_with("trailing characters") && key != "(top level)" {
            // A fixed-size array with too many elements.
            format!("too many elements: {msg}")
        } else if syntax {
            format!("not valid JSON: {msg}")
        } else {
            msg
        };
        StateError::new(file, key, msg)
    })?;
    de.end().map_err(|e| {
        StateError::new(
            file,
            "(top level)",
            format!("unexpected data after the JSON document: {e}"),
        )
    })?;
    Ok(value)
}

/// The document as a JSON value: syntax errors and trailing data are reported
/// here, before the shape and the keys are checked.
/// `T` is the typed document: on a syntax error its reader names the key path.
fn parse_value<'a, T: Deserialize<'a>>(
    text: &'a str,
    file: &str,
) -> Result<serde_json::Value, StateError> {
    serde_json::from_str(text).map_err(|e| match parse_json::<T>(text, file) {
        Err(typed) => typed,
        Ok(_) => StateError::new(file, "(top level)", format!("not valid JSON: {e}")),
    })
}

/// serde reads a struct from a JSON array too (fields in order): the contract's
/// objects must be objects. `path` names `v` in errors.
fn require_object(v: &serde_json::Value, file: &str, path: &str) -> Result<(), StateError> {
    if v.is_object() {
        Ok(())
    } else {
        Err(StateError::new(file, path, "expected a JSON object"))
    }
}

fn check_state_shape(v: &serde_json::Value, file: &str, key: &str) -> Result<(), StateError> {
    require_object(v, file, key)?;
    let sub = |name: &str| {
        if key.starts_with('(') {
            name.to_string()
        } else {
            format!("{key}.{name}")
        }
    };
    if let Some(b) = v.get("base") {
        require_object(b, file, &sub("base"))?;
    }
    if let Some(d) = v.get("derivatives") {
        if !d.is_boolean() {
            return Err(StateError::new(
                file,
                sub("derivatives"),
                format!("expected true or false, found {d}"),
            ));
        }
    }
    if let Some(f) = v.get("fext") {
        let fkey = sub("fext");
        require_object(f, file, &fkey)?;
        if let Some(map) = f.as_object() {
            for (link, w) in map {
                require_object(w, file, &format!("{fkey}.{link}"))?;
            }
        }
    }
    Ok(())
}

/// Parses a states file; unknown keys at any level are errors naming the key.
pub fn parse_states(text: &str, file: &str) -> Result<StatesFile, StateError> {
    let v = parse_value::<StatesFile>(text, file)?;
    require_object(&v, file, "(top level)")?;
    if let Some(states) = v.get("states").and_then(|s| s.as_array()) {
        for (i, st) in states.iter().enumerate() {
            check_state_shape(st, file, &format!("states[{i}]"))?;
        }
    }
    drop(v);
    let s: StatesFile = parse_json(text, file)?;
    if let Some(g) = s.gravity {
        if g.iter().any(|x| !x.is_finite()) {
            return Err(StateError::new(file, "gravity", "non-finite number"));
        }
    }
    Ok(s)
}

/// Parses one state object (simulate's `--initial`, cli.md: `fext` and `frames`
/// are not allowed there).
pub fn parse_state(text: &str, file: &str) -> Result<State, StateError> {
    check_state_shape(&parse_value::<State>(text, file)?, file, "(top level)")?;
    let st: State = parse_json(text, file)?;
    for (present, key) in [
        (st.fext.is_some(), "fext"),
        (st.frames.is_some(), "frames"),
        (st.derivatives.is_some(), "derivatives"),
    ] {
        if present {
            return Err(StateError::new(
                file,
                key,
                "not allowed in --initial (eval only)",
            ));
        }
    }
    Ok(st)
}

/// Reads a file into a string, naming it on error.
pub fn read_text(path: &std::path::Path) -> Result<String, StateError> {
    let name = path.display().to_string();
    if path.is_dir() {
        return Err(StateError::new(&name, "(file)", "is a directory"));
    }
    let bytes = std::fs::read(path)
        .map_err(|e| StateError::new(&name, "(file)", format!("cannot read: {e}")))?;
    String::from_utf8(bytes).map_err(|_| StateError::new(&name, "(file)", "not UTF-8 text"))
}

/// The coordinates `x` gives joint `dof` in `map` (`q`, `v`, `a`, `tau`): its
/// kind's number of them, finite; a quaternion within 1e-3 of unit norm,
/// normalised. The error says what is wrong (the caller names the key).
fn joint_values(
    dof: &crate::model::DofInfo,
    map: &str,
    x: &JointValue,
) -> Result<Vec<f64>, String> {
    use crate::model::JointKind;
    let kind = dof.kind;
    let n = if map == "q" { kind.nq() } else { kind.nv() };
    let layout = match (kind, map == "q") {
        (JointKind::Spherical, true) => "[qx, qy, qz, qw]",
        (JointKind::Spherical, false) => "[wx, wy, wz]",
        (JointKind::Planar, true) => "[x, y, theta]",
        (JointKind::Planar, false) => "[vx, vy, wz]",
        (JointKind::Free, true) => "[x, y, z, qx, qy, qz, qw]",
        (JointKind::Free, false) => "[vx, vy, vz, wx, wy, wz]",
        _ => "",
    };
    let mut vals = match (x, n) {
        (JointValue::Scalar(x), 1) => vec![*x],
        (JointValue::Array(_), 1) => {
            return Err(format!(
                "a {} joint takes a number, found an array",
                kind.name()
            ))
        }
        (JointValue::Scalar(_), _) => {
            return Err(format!(
                "a {} joint takes an array of {n} numbers {layout}, found a number",
                kind.name()
            ))
        }
        (JointValue::Array(a), _) if a.len() != n => {
            return Err(format!(
                "a {} joint takes an array of {n} numbers {layout}, found {}",
                kind.name(),
                a.len()
            ))
        }
        (JointValue::Array(a), _) => a.clone(),
    };
    if vals.iter().any(|x| !x.is_finite()) {
        return Err("non-finite number".into());
    }
    let quat = match (kind, map) {
        (JointKind::Spherical, "q") => Some(0),
        (JointKind::Free, "q") => Some(3),
        _ => None,
    };
    if let Some(at) = quat {
        let norm = vals[at..at + 4].iter().map(|x| x * x).sum::<f64>().sqrt();
        if (norm - 1.0).abs() > 1e-3 {
            return Err(format!(
                "not a unit quaternion (norm {norm}; within 1e-3 of 1 is normalised)"
            ));
        }
        for x in &mut vals[at..at + 4] {
            *x /= norm;
        }
    }
    Ok(vals)
}

impl State {
    /// The engine's vectors for this state. `key` prefixes error keys (e.g. `states[3]`).
    pub fn to_vectors(
        &self,
        model: &Model,
        file: &str,
        key: &str,
    ) -> Result<StateVectors, StateError> {
        let mut q = model.neutral();
        let mut v = DVector::zeros(model.nv);
        let mut a = DVector::zeros(model.nv);
        let mut tau = DVector::zeros(model.nv);
        let maps = [
            (&self.q, "q"),
            (&self.v, "v"),
            (&self.a, "a"),
            (&self.tau, "tau"),
        ];
        for (map, name) in maps {
            let Some(map) = map else { continue };
            for (joint, x) in map {
                let k = format!("{key}.{name}.{joint}");
                let Some(dof) = model.dofs.iter().find(|d| &d.name == joint) else {
                    let why = if model.body_joint_names.iter().any(|n| n == joint) {
                        "is a mimic joint (it follows its leader and is not a key)".to_string()
                    } else {
                        let near = crate::model::nearest(joint, model.dof_names())
                            .map(|n| format!("; nearest: \"{n}\""))
                            .unwrap_or_default();
                        format!(
                            "unknown joint (not a movable, non-mimic joint of this robot{near})"
                        )
                    };
                    return Err(StateError::new(file, k, why));
                };
                let vals = joint_values(dof, name, x).map_err(|m| StateError::new(file, &k, m))?;
                let (dst, at) = match name {
                    "q" => (&mut q, dof.iq),
                    "v" => (&mut v, dof.iv),
                    "a" => (&mut a, dof.iv),
                    _ => (&mut tau, dof.iv),
                };
                dst.rows_mut(at, vals.len()).copy_from_slice(&vals);
            }
        }
        if let (Some(b), true) = (&self.base, model.floating_base) {
            let fin = |arr: &[f64], field: &str| -> Result<(), StateError> {
                if arr.iter().all(|x| x.is_finite()) {
                    Ok(())
                } else {
                    Err(StateError::new(
                        file,
                        format!("{key}.base.{field}"),
                        "non-finite number",
                    ))
                }
            };
            let three: [(&Option<[f64; 3]>, &str); 7] = [
                (&b.position, "position"),
                (&b.linear_velocity, "linear_velocity"),
                (&b.angular_velocity, "angular_velocity"),
                (&b.linear_acceleration, "linear_acceleration"),
                (&b.angular_acceleration, "angular_acceleration"),
                (&b.force, "force"),
                (&b.torque, "torque"),
            ];
            for (x, field) in three {
                if let Some(x) = x {
                    fin(x, field)?;
                }
            }
            if let Some(p) = b.position {
                q.rows_mut(0, 3).copy_from_slice(&p);
            }
            if let Some(o) = b.orientation_xyzw {
                fin(&o, "orientation_xyzw")?;
                let n = o.iter().map(|x| x * x).sum::<f64>().sqrt();
                if (n - 1.0).abs() > 1e-3 {
                    return Err(StateError::new(
                        file,
                        format!("{key}.base.orientation_xyzw"),
                        format!("not a unit quaternion (norm {n})"),
                    ));
                }
                for k in 0..4 {
                    q[3 + k] = o[k] / n;
                }
            }
            let put = |dst: &mut DVector<f64>, at: usize, x: &Option<[f64; 3]>| {
                if let Some(x) = x {
                    dst.rows_mut(at, 3).copy_from_slice(x);
                }
            };
            put(&mut v, 0, &b.linear_velocity);
            put(&mut v, 3, &b.angular_velocity);
            put(&mut a, 0, &b.linear_acceleration);
            put(&mut a, 3, &b.angular_acceleration);
            put(&mut tau, 0, &b.force);
            put(&mut tau, 3, &b.torque);
        }
        let mut fext = Vec::new();
        for (link, w) in self.fext.iter().flatten() {
            let k = format!("{key}.fext.{link}");
            let f = model
                .frame_id(link)
                .map_err(|e| StateError::new(file, k.as_str(), e.to_string()))?;
            let mut fv = [Vector3::zeros(), Vector3::zeros()];
            for (slot, x, field) in [(0, &w.force, "force"), (1, &w.torque, "torque")] {
                if let Some(x) = x {
                    if !x.iter().all(|c| c.is_finite()) {
                        return Err(StateError::new(
                            file,
                            format!("{k}.{field}"),
                            "non-finite number",
                        ));
                    }
                    fv[slot] = Vector3::from(*x);
                }
            }
            fext.push((f, fv[0], fv[1]));
        }
        let mut frames = Vec::new();
        for (i, link) in self.frames.iter().flatten().enumerate() {
            let f = model
                .frame_id(link)
                .map_err(|e| StateError::new(file, format!("{key}.frames[{i}]"), e.to_string()))?;
            frames.push(f);
        }
        Ok(StateVectors {
            q,
            v,
            a,
            tau,
            fext,
            frames,
            derivatives: self.derivatives.unwrap_or(false),
        })
    }
}
