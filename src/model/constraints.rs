//! Loop constraints (mechanisms.md §"Loop constraints"): a typed set built
//! against a [`Model`] from the contract's JSON objects. `point` holds a point of
//! one link on a point of another (or of the world), `frame` a frame on a frame
//! (position and orientation), `joint` couples two 1-DoF joints
//! (`q₁ = ratio · q₂ + offset`). The dynamics of a model with constraints is in
//! `crate::dynamics::constraint_dynamics` (docs/theory.md §"Constrained dynamics").

use super::{Data, JointKind, Model};
use crate::spatial::Se3;
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use serde_json::Value;

/// One side of a `point` or `frame` constraint: a frame rigidly attached to a
/// body (body 0: the world).
#[derive(Clone, Debug, PartialEq)]
pub struct Attachment {
    /// The body the frame moves with (0: the world).
    pub body: usize,
    /// The URDF link named (`None`: the world).
    pub link: Option<String>,
    /// `body_M_c`: the constraint frame in the body frame (for the world: its
    /// world pose). A `point` reads its translation only.
    pub local: Se3<f64>,
}

/// What a constraint holds.
#[derive(Clone, Debug, PartialEq)]
pub enum ConstraintKind {
    /// The origin of `a`'s frame on the origin of `b`'s (3 rows).
    Point,
    /// `a`'s frame on `b`'s, position and orientation (6 rows: linear, angular).
    Frame,
    /// `q[joint1] − ratio · q[joint2] = offset` (1 row).
    Joint {
        /// The first joint's index in q (a 1-DoF joint).
        q1: usize,
        /// Its index in v.
        v1: usize,
        /// The second joint's indices in q and v, if any.
        second: Option<(usize, usize)>,
        /// `ratio`.
        ratio: f64,
        /// `offset`.
        offset: f64,
        /// Whether joint1 is prismatic (its generalized force is a force).
        prismatic: bool,
    },
}

/// One loop constraint.
#[derive(Clone, Debug, PartialEq)]
pub struct Constraint {
    /// Unique name (default `constraint_K`).
    pub name: String,
    /// Its kind and the joint data of a `joint` constraint.
    pub kind: ConstraintKind,
    /// Side 1 (`link1`, `point1`/`frame1`); unused by a `joint` constraint.
    pub a: Attachment,
    /// Side 2 (`link2` or the world); unused by a `joint` constraint.
    pub b: Attachment,
    /// Side 2 is the world and its point/frame was left out: it is where side 1
    /// is in the state ([`Constraints::place_holds`]).
    pub hold: bool,
}

impl Constraint {
    /// Number of rows: 3 (`point`), 6 (`frame`), 1 (`joint`).
    pub fn rows(&self) -> usize {
        match self.kind {
            ConstraintKind::Point => 3,
            ConstraintKind::Frame => 6,
            ConstraintKind::Joint { .. } => 1,
        }
    }
    /// The contract's kind name.
    pub fn kind_name(&self) -> &'static str {
        match self.kind {
            ConstraintKind::Point => "point",
            ConstraintKind::Frame => "frame",
            ConstraintKind::Joint { .. } => "joint",
        }
    }
}

/// A typed set of loop constraints for one model.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Constraints {
    /// The constraints, in the order given.
    pub items: Vec<Constraint>,
}

/// A bad constraint: names `constraints[K]` and the key.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("constraints[{index}].{key}: {message}")]
pub struct ConstraintError {
    /// K, the constraint's index in the list.
    pub index: usize,
    /// The offending key (`link1`, `joint2`, `point1[2]`, …).
    pub key: String,
    /// What is wrong.
    pub message: String,
}

fn err(index: usize, key: impl Into<String>, message: impl Into<String>) -> ConstraintError {
    ConstraintError {
        index,
        key: key.into(),
        message: message.into(),
    }
}

fn number(v: &Value, k: usize, key: &str) -> Result<f64, ConstraintError> {
    let x = v
        .as_f64()
        .ok_or_else(|| err(k, key, format!("expected a number, got {v}")))?;
    if !x.is_finite() {
        return Err(err(k, key, "not a finite number"));
    }
    Ok(x)
}

fn array<const N: usize>(v: &Value, k: usize, key: &str) -> Result<[f64; N], ConstraintError> {
    let a = v
        .as_array()
        .filter(|a| a.len() == N)
        .ok_or_else(|| err(k, key, format!("expected an array of {N} numbers")))?;
    let mut out = [0.0; N];
    for (i, x) in a.iter().enumerate() {
        out[i] = number(x, k, &format!("{key}[{i}]"))?;
    }
    Ok(out)
}

fn string<'a>(v: &'a Value, k: usize, key: &str) -> Result<&'a str, ConstraintError> {
    v.as_str()
        .ok_or_else(|| err(k, key, format!("expected a string, got {v}")))
}

/// A `frame1`/`frame2` object: `position` (origin), `orientation_xyzw` (identity).
fn frame_object(v: &Value, k: usize, key: &str) -> Result<Se3<f64>, ConstraintError> {
    let m = v
        .as_object()
        .ok_or_else(|| err(k, key, "expected an object with position and orientation_xyzw"))?;
    let mut out = Se3::identity();
    for (name, x) in m {
        let sub = format!("{key}.{name}");
        match name.as_str() {
            "position" => out.trans = Vector3::from(array::<3>(x, k, &sub)?),
            "orientation_xyzw" => {
                let [qx, qy, qz, qw] = array::<4>(x, k, &sub)?;
                let n = (qx * qx + qy * qy + qz * qz + qw * qw).sqrt();
                if (n - 1.0).abs() > 1e-3 {
                    return Err(err(k, sub, format!("quaternion norm {n} is not 1")));
                }
                let q = nalgebra::Quaternion::new(qw, qx, qy, qz);
                out.rot = *UnitQuaternion::from_quaternion(q).to_rotation_matrix().matrix();
            }
            _ => return Err(err(k, sub, "unknown key")),
        }
    }
    Ok(out)
}

/// A link by name (`"world"`: the world) as (body, `body_M_link`, name).
fn link(
    model: &Model,
    v: &Value,
    k: usize,
    key: &str,
) -> Result<(usize, Se3<f64>, Option<String>), ConstraintError> {
    let name = string(v, k, key)?;
    if name == "world" {
        return Ok((0, Se3::identity(), None));
    }
    let f = model
        .frame_id(name)
        .map_err(|e| err(k, key, e.to_string()))?;
    let fr = &model.frames[f.0];
    Ok((fr.body, fr.placement, Some(name.to_string())))
}

/// A joint of one degree of freedom by name: (iq, iv, prismatic).
fn dof_joint(
    model: &Model,
    v: &Value,
    k: usize,
    key: &str,
) -> Result<(usize, usize, bool), ConstraintError> {
    let name = string(v, k, key)?;
    let id = model
        .joint_id(name)
        .map_err(|e| err(k, key, e.to_string()))?;
    if model.is_mimic(id) {
        return Err(err(
            k,
            key,
            format!("joint \"{name}\" is a mimic joint, not a degree of freedom"),
        ));
    }
    let j = &model.joints[id.0];
    if j.nv() != 1 {
        return Err(err(
            k,
            key,
            format!(
                "joint \"{name}\" has {} degrees of freedom; a joint constraint couples 1-DoF joints",
                j.nv()
            ),
        ));
    }
    Ok((j.iq, j.iv, matches!(j.kind, JointKind::Prismatic(_))))
}

impl Constraints {
    /// No constraints.
    pub fn empty() -> Self {
        Self::default()
    }
    /// Total number of rows.
    pub fn rows(&self) -> usize {
        self.items.iter().map(Constraint::rows).sum()
    }
    /// Whether any constraint is held where it stands in the state.
    pub fn has_holds(&self) -> bool {
        self.items.iter().any(|c| c.hold)
    }
    /// The index of a constraint by name.
    pub fn index(&self, name: &str) -> Option<usize> {
        self.items.iter().position(|c| c.name == name)
    }

    /// Builds the set from the contract's JSON objects (mechanisms.md §"Loop
    /// constraints"): names, defaults, world anchors as the contract says; an
    /// unknown link or joint, a multi-DoF or mimic joint in a `joint`
    /// constraint, both sides on one body, a non-finite number, an unknown key
    /// or a duplicate name is an error naming `constraints[K]` and the key.
    pub fn from_json(model: &Model, items: &[Value]) -> Result<Self, ConstraintError> {
        let mut out = Vec::with_capacity(items.len());
        for (k, v) in items.iter().enumerate() {
            let c = Self::one(model, k, v)?;
            if out.iter().any(|o: &Constraint| o.name == c.name) {
                return Err(err(k, "name", format!("duplicate name \"{}\"", c.name)));
            }
            out.push(c);
        }
        Ok(Self { items: out })
    }

    /// [`Constraints::from_json`] of a JSON array (`"constraints": [...]`).
    pub fn from_value(model: &Model, v: &Value) -> Result<Self, ConstraintError> {
        let a = v.as_array().ok_or_else(|| ConstraintError {
            index: 0,
            key: String::new(),
            message: "expected a list of constraint objects".into(),
        })?;
        Self::from_json(model, a)
    }

    fn one(model: &Model, k: usize, v: &Value) -> Result<Constraint, ConstraintError> {
        let m = v
            .as_object()
            .ok_or_else(|| err(k, "kind", "expected a constraint object"))?;
        let get = |key: &str| m.get(key).filter(|x| !x.is_null());
        let kind = string(
            get("kind").ok_or_else(|| err(k, "kind", "missing (point, frame or joint)"))?,
            k,
            "kind",
        )?;
        let allowed: &[&str] = match kind {
            "point" => &["name", "kind", "link1", "point1", "link2", "point2"],
            "frame" => &["name", "kind", "link1", "frame1", "link2", "frame2"],
            "joint" => &["name", "kind", "joint1", "joint2", "ratio", "offset"],
            other => {
                return Err(err(
                    k,
                    "kind",
                    format!("unknown kind \"{other}\" (point, frame or joint)"),
                ))
            }
        };
        if let Some(bad) = m.keys().find(|key| !allowed.contains(&key.as_str())) {
            return Err(err(k, bad.as_str(), format!("unknown key for a {kind} constraint")));
        }
        let name = match get("name") {
            Some(n) => string(n, k, "name")?.to_string(),
            None => format!("constraint_{k}"),
        };
        let world = Attachment {
            body: 0,
            link: None,
            local: Se3::identity(),
        };
        if kind == "joint" {
            let j1 = get("joint1").ok_or_else(|| err(k, "joint1", "missing"))?;
            let (q1, v1, prismatic) = dof_joint(model, j1, k, "joint1")?;
            let second = match get("joint2") {
                Some(j2) => {
                    let (q2, v2, _) = dof_joint(model, j2, k, "joint2")?;
                    if v2 == v1 {
                        return Err(err(k, "joint2", "is joint1: both sides on one joint"));
                    }
                    Some((q2, v2))
                }
                None => None,
            };
            let ratio = get("ratio").map_or(Ok(1.0), |x| number(x, k, "ratio"))?;
            let offset = get("offset").map_or(Ok(0.0), |x| number(x, k, "offset"))?;
            return Ok(Constraint {
                name,
                kind: ConstraintKind::Joint {
                    q1,
                    v1,
                    second,
                    ratio,
                    offset,
                    prismatic,
                },
                a: world.clone(),
                b: world,
                hold: false,
            });
        }
        let point = kind == "point";
        let (key1, key2) = if point {
            ("point1", "point2")
        } else {
            ("frame1", "frame2")
        };
        let local = |x: Option<&Value>, key: &str| -> Result<Se3<f64>, ConstraintError> {
            match x {
                None => Ok(Se3::identity()),
                Some(x) if point => Ok(Se3::from_translation(Vector3::from(array::<3>(x, k, key)?))),
                Some(x) => frame_object(x, k, key),
            }
        };
        let l1 = get("link1").ok_or_else(|| err(k, "link1", "missing"))?;
        let (body1, place1, name1) = link(model, l1, k, "link1")?;
        let a = Attachment {
            body: body1,
            link: name1,
            local: place1.compose(&local(get(key1), key1)?),
        };
        let (b, hold) = match get("link2") {
            Some(l2) => {
                let (body2, place2, name2) = link(model, l2, k, "link2")?;
                let own = local(get(key2), key2)?;
                let hold = name2.is_none() && get(key2).is_none();
                (
                    Attachment {
                        body: body2,
                        link: name2,
                        local: place2.compose(&own),
                    },
                    hold,
                )
            }
            None => (
                Attachment {
                    body: 0,
                    link: None,
                    local: local(get(key2), key2)?,
                },
                get(key2).is_none(),
            ),
        };
        if a.body == b.body {
            let which = if b.body == 0 { "the world" } else { "one body" };
            return Err(err(
                k,
                if get("link2").is_some() { "link2" } else { "link1" },
                format!("both sides of the constraint are welded to {which}: it holds nothing"),
            ));
        }
        Ok(Constraint {
            name,
            kind: if point {
                ConstraintKind::Point
            } else {
                ConstraintKind::Frame
            },
            a,
            b,
            hold,
        })
    }

    /// Places every held world anchor (a world side whose point or frame was left
    /// out) where side 1 is: reads `data.o_m_i` (forward kinematics at the state
    /// first).
    pub fn place_holds(&mut self, data: &Data) {
        for c in self.items.iter_mut().filter(|c| c.hold) {
            c.b.local = data.o_m_i[c.a.body].compose(&c.a.local);
        }
    }

    /// The violation of each constraint in the state whose forward kinematics
    /// `data.o_m_i` holds (mechanisms.md: m for `point`; the larger of the
    /// distance in m and the angle in rad for `frame`; the signed residual
    /// `q₁ − ratio · q₂ − offset` for `joint`), written to `out` (one a constraint).
    pub fn violation(&self, data: &Data, q: &[f64], out: &mut [f64]) {
        for (c, o) in self.items.iter().zip(out.iter_mut()) {
            *o = match &c.kind {
                ConstraintKind::Joint {
                    q1,
                    second,
                    ratio,
                    offset,
                    ..
                } => q[*q1] - second.map_or(0.0, |(q2, _)| ratio * q[q2]) - offset,
                kind => {
                    let m1 = data.o_m_i[c.a.body].compose(&c.a.local);
                    let m2 = data.o_m_i[c.b.body].compose(&c.b.local);
                    let d = (m1.trans - m2.trans).norm();
                    if *kind == ConstraintKind::Point {
                        d
                    } else {
                        d.max(rotation_angle(&(m1.rot * m2.rot.transpose())))
                    }
                }
            };
        }
    }
}

/// The angle (rad, in [0, π]) of a rotation matrix.
fn rotation_angle(r: &Matrix3<f64>) -> f64 {
    // atan2(|axis·sin|, cos): accurate near 0 and π
    let s = Vector3::new(
        r[(2, 1)] - r[(1, 2)],
        r[(0, 2)] - r[(2, 0)],
        r[(1, 0)] - r[(0, 1)],
    )
    .norm()
        * 0.5;
    let c = (r.trace() - 1.0) * 0.5;
    s.atan2(c)
}
