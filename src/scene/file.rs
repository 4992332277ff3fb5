//! The SCENE.json document (`../shared/spec/scene.md`): every object's keys
//! checked (`deny_unknown_fields` at every level), key paths from
//! `serde_path_to_error`. These are also the types a program fills to build a
//! scene in code.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// A whole SCENE.json.
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    /// Gravity in the world frame (default `[0, 0, -9.81]`).
    #[serde(default)]
    pub gravity: Option<[f64; 3]>,
    /// The ground plane; absent or `null`: none.
    #[serde(default)]
    pub ground: Option<GroundSpec>,
    /// The URDF models, at least one, in file order (the order of q and v).
    pub models: Vec<ModelSpec>,
    /// Static shapes welded to the world.
    #[serde(default)]
    pub obstacles: Vec<ObstacleSpec>,
    /// Pairs never in contact: `MODEL/LINK`, `MODEL` or an obstacle's name on each side.
    #[serde(default)]
    pub exclude: Vec<[String; 2]>,
    /// Still islands sleep (default true; scene.md §"Large scenes").
    #[serde(default)]
    pub sleep: Option<bool>,
    /// The speed under which a shape's points count as still (m/s, default 1e-3).
    #[serde(default)]
    pub sleep_velocity: Option<f64>,
    /// How long an island is still before it sleeps (s, default 0.5).
    #[serde(default)]
    pub sleep_time: Option<f64>,
    /// Threads the islands are solved on (0: every core; default 1).
    #[serde(default)]
    pub threads: Option<usize>,
    /// Loop constraints (mechanisms.md §"Loop constraints"), links and joints
    /// named `MODEL/NAME`.
    #[serde(default)]
    pub constraints: Vec<serde_json::Value>,
}

/// The ground plane `z = height`.
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct GroundSpec {
    /// Height of the plane (m, default 0).
    #[serde(default)]
    pub height: Option<f64>,
    /// Coulomb friction coefficient on the ground's side (default 1.0).
    #[serde(default)]
    pub friction: Option<f64>,
    /// Torsional friction coefficient of contacts with the ground (m; default
    /// the contact model's, `ContactParams::torsion`).
    #[serde(default)]
    pub torsion: Option<f64>,
    /// Rolling friction coefficient of contacts with the ground (m; default
    /// the contact model's, `ContactParams::rolling`).
    #[serde(default)]
    pub rolling: Option<f64>,
}

/// How a model's root link is attached to the world.
#[derive(Debug, Clone, Copy, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum BaseSpec {
    /// Welded at the model's pose.
    #[default]
    Fixed,
    /// A free joint starting at the model's pose.
    Floating,
}

/// One model of the scene: a URDF, or an MJCF file's whole world (mjcf.md
/// §"Entry points").
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ModelSpec {
    /// Unique among models and obstacles, no `/`.
    pub name: String,
    /// The URDF file, relative to the scene file (exactly one of `urdf`, `mjcf`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub urdf: Option<String>,
    /// The MJCF file, relative to the scene file: its whole world (bodies,
    /// static geoms and ground plane) placed by `position`/`orientation_xyzw`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mjcf: Option<String>,
    /// `"fixed"` (default) or `"floating"` (a URDF's only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base: Option<BaseSpec>,
    /// World position of the URDF's root frame (m, default the origin).
    #[serde(default)]
    pub position: Option<[f64; 3]>,
    /// Orientation of the root frame, quaternion x, y, z, w (default identity).
    #[serde(default)]
    pub orientation_xyzw: Option<[f64; 4]>,
    /// The starting state (as `--initial` of cli.md).
    #[serde(default)]
    pub initial: Option<InitialSpec>,
    /// The model's SRDF file, relative to the scene file.
    #[serde(default)]
    pub srdf: Option<String>,
    /// A `<group_state>` of the SRDF whose joint values start the model.
    #[serde(default)]
    pub pose: Option<String>,
    /// Contact between two links of this model (default true).
    #[serde(default)]
    pub self_collision: Option<bool>,
    /// This model's links' friction coefficient (default 1.0).
    #[serde(default)]
    pub friction: Option<f64>,
    /// `false`: this model never sleeps (wins over the scene's `"sleep": true`).
    #[serde(default)]
    pub sleep: Option<bool>,
}

/// A model's starting state: joint maps keyed by the URDF's joint names (without
/// the model prefix), the floating base's pose and body-frame velocities, and
/// constant generalized forces.
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct InitialSpec {
    /// Joint positions (rad or m; an array for a ball or free joint).
    #[serde(default)]
    pub q: Option<BTreeMap<String, InitialValue>>,
    /// Joint velocities.
    #[serde(default)]
    pub v: Option<BTreeMap<String, InitialValue>>,
    /// Constant joint torques (N·m or N).
    #[serde(default)]
    pub tau: Option<BTreeMap<String, InitialValue>>,
    /// The floating base.
    #[serde(default)]
    pub base: Option<InitialBaseSpec>,
}

/// A joint's value in `initial`: a number for a 1-DoF joint, an array for a
/// joint of several degrees of freedom (mechanisms.md §"In `eval`").
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(untagged)]
pub enum InitialValue {
    /// A revolute, prismatic or continuous joint's value.
    Number(f64),
    /// A ball, planar or free joint's values.
    Array(Vec<f64>),
}

/// The floating base's part of a model's starting state.
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct InitialBaseSpec {
    /// World position of the root frame (replaces the model's `position`).
    #[serde(default)]
    pub position: Option<[f64; 3]>,
    /// Orientation x, y, z, w (replaces the model's `orientation_xyzw`).
    #[serde(default)]
    pub orientation_xyzw: Option<[f64; 4]>,
    /// Body-frame linear velocity (m/s).
    #[serde(default)]
    pub linear_velocity: Option<[f64; 3]>,
    /// Body-frame angular velocity (rad/s).
    #[serde(default)]
    pub angular_velocity: Option<[f64; 3]>,
    /// Constant force at the root origin, body frame (N).
    #[serde(default)]
    pub force: Option<[f64; 3]>,
    /// Constant torque, body frame (N·m).
    #[serde(default)]
    pub torque: Option<[f64; 3]>,
}

/// A cylinder's or capsule's size.
#[derive(Debug, Clone, Copy, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RoundSpec {
    /// Radius (m).
    pub radius: f64,
    /// Length along z (m; a capsule's between its hemisphere centres).
    pub length: f64,
}

/// A height field: `heights[row][col]`, rows along y from −y to +y, each row along
/// x from −x to +x, metres above the obstacle's frame.
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct HeightFieldSpec {
    /// The grid of heights (m).
    pub heights: Vec<Vec<f64>>,
    /// Extents along x and y (m), centred on the frame.
    pub size: [f64; 2],
}

/// A static obstacle: a name, exactly one shape key, a pose and a friction.
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ObstacleSpec {
    /// Unique among obstacles and models.
    pub name: String,
    /// Edge lengths (m).
    #[serde(default, rename = "box")]
    pub box_: Option<[f64; 3]>,
    /// Radius (m).
    #[serde(default)]
    pub sphere: Option<f64>,
    /// Along its z.
    #[serde(default)]
    pub cylinder: Option<RoundSpec>,
    /// Along its z.
    #[serde(default)]
    pub capsule: Option<RoundSpec>,
    /// An STL, OBJ or DAE file relative to the scene file (collides as the triangle mesh it is).
    #[serde(default)]
    pub mesh: Option<String>,
    /// The mesh's per-axis scale (default 1).
    #[serde(default)]
    pub scale: Option<[f64; 3]>,
    /// A height field.
    #[serde(default)]
    pub heightfield: Option<HeightFieldSpec>,
    /// World position (m, default the origin).
    #[serde(default)]
    pub position: Option<[f64; 3]>,
    /// Orientation x, y, z, w (default identity).
    #[serde(default)]
    pub orientation_xyzw: Option<[f64; 4]>,
    /// Friction coefficient (default 1.0).
    #[serde(default)]
    pub friction: Option<f64>,
}

impl ObstacleSpec {
    /// The shape keys present, in scene.md's order.
    pub fn shape_keys(&self) -> Vec<&'static str> {
        let mut k = Vec::new();
        if self.box_.is_some() {
            k.push("box");
        }
        if self.sphere.is_some() {
            k.push("sphere");
        }
        if self.cylinder.is_some() {
            k.push("cylinder");
        }
        if self.capsule.is_some() {
            k.push("capsule");
        }
        if self.mesh.is_some() {
            k.push("mesh");
        }
        if self.heightfield.is_some() {
            k.push("heightfield");
        }
        k
    }
}

/// Parses SCENE.json text: `Err((key path, message))` on malformed JSON, an
/// unknown key at any level or a value of the wrong type.
pub(crate) fn parse_spec(text: &str) -> Result<SceneSpec, (String, String)> {
    let de = &mut serde_json::Deserializer::from_str(text);
    let spec: SceneSpec = serde_path_to_error::deserialize(&mut *de).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.inner();
        let syntax = inner.is_syntax() || inner.is_eof();
        let key = if path == "." || path == "?" || path.is_empty() {
            "(top level)".to_string()
        } else {
            path
        };
        let msg = inner.to_string();
        let msg = if syntax {
            format!("not valid JSON: {msg}")
        } else {
            msg
        };
        (key, msg)
    })?;
    de.end().map_err(|e| {
        (
            "(top level)".to_string(),
            format!("unexpected data after the JSON document: {e}"),
        )
    })?;
    Ok(spec)
}
