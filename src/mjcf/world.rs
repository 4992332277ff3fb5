//! MuJoCo's compiled world as the importer keeps it: bodies, joints and geoms in
//! MuJoCo's order and ids, with what dynamics and (next) simulation read.

use nalgebra::{Matrix3, UnitQuaternion, Vector3};

/// A joint kind of MJCF.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MjJointType {
    /// 6 DoF, `<freejoint>` or `type="free"`.
    Free,
    /// 3 rotational DoF.
    Ball,
    /// Translation along `axis`.
    Slide,
    /// Rotation about `axis` through `pos`.
    Hinge,
}

/// A compiled joint (MuJoCo's `jnt_*` and `dof_*` of one joint).
#[derive(Clone, Debug, PartialEq)]
pub struct MjJoint {
    /// Its name (`joint_K` when unnamed, K its MuJoCo id).
    pub name: String,
    /// Its kind.
    pub kind: MjJointType,
    /// Its MuJoCo body.
    pub body: usize,
    /// Anchor in the body frame.
    pub pos: Vector3<f64>,
    /// Unit axis in the body frame.
    pub axis: Vector3<f64>,
    /// Position limits (rad or m) when limited.
    pub range: Option<(f64, f64)>,
    /// `ref` (rad or m): qpos0 of a hinge or slide.
    pub reference: f64,
    /// Rotor inertia added to H's diagonal.
    pub armature: f64,
    /// Viscous damping.
    pub damping: f64,
    /// Dry friction.
    pub frictionloss: f64,
    /// Spring stiffness.
    pub stiffness: f64,
    /// Spring rest position.
    pub springref: f64,
    /// `springdamper` (τ s, ζ) when both are positive: stiffness and damping are
    /// then set from the joint's inertia at qpos0 (src/mjcf/springdamper.rs).
    pub springdamper: Option<(f64, f64)>,
    /// How errors name its element (`<joint name="…">` or `<joint> (line N)`).
    pub(crate) label: String,
}

/// MuJoCo's geom types.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MjGeomType {
    /// Half-space (infinite plane facing +z).
    Plane,
    /// Height field.
    Hfield,
    /// Sphere.
    Sphere,
    /// Capsule along z.
    Capsule,
    /// Ellipsoid.
    Ellipsoid,
    /// Cylinder along z.
    Cylinder,
    /// Box (half sizes).
    Box,
    /// Mesh asset.
    Mesh,
}

/// A compiled geom.
#[derive(Clone, Debug, PartialEq)]
pub struct MjGeom {
    /// Its name (`geom_K` when unnamed).
    pub name: String,
    /// Its MuJoCo body (0: the world).
    pub body: usize,
    /// Its type.
    pub kind: MjGeomType,
    /// MuJoCo's `size` (half lengths), `fromto` applied.
    pub size: [f64; 3],
    /// Position in the body frame.
    pub pos: Vector3<f64>,
    /// Orientation in the body frame.
    pub quat: UnitQuaternion<f64>,
    /// Mass (kg), from `mass` or density × volume (0 outside inertiagrouprange).
    pub mass: f64,
    /// Principal moments about its centre in its own frame.
    pub inertia: [f64; 3],
    /// A mesh geom's centre of mass and inertia about it, both in the body
    /// frame (`inertia` unused), as MuJoCo's compiler takes them from the
    /// mesh (`crate::mesh::mass_properties`).
    pub mesh_mass: Option<(Vector3<f64>, nalgebra::Matrix3<f64>)>,
    /// `contype`, `conaffinity`, `condim`, `priority`, `group`.
    pub contype: i64,
    /// See `contype`.
    pub conaffinity: i64,
    /// Contact dimensionality.
    pub condim: i64,
    /// Contact priority.
    pub priority: i64,
    /// Visual group.
    pub group: i64,
    /// Sliding, torsional, rolling friction.
    pub friction: [f64; 3],
    /// Colour.
    pub rgba: [f64; 4],
    /// The mesh or height field asset it names.
    pub asset: Option<String>,
}

/// A compiled body: its frame in its parent's and its mass properties.
#[derive(Clone, Debug, PartialEq)]
pub struct MjBody {
    /// Its name (`world` for body 0, `body_K` when unnamed).
    pub name: String,
    /// Its parent body (0 for the world's children and the world).
    pub parent: usize,
    /// Position in the parent's frame (MuJoCo's `body_pos`).
    pub pos: Vector3<f64>,
    /// Orientation in the parent's frame (`body_quat`).
    pub quat: UnitQuaternion<f64>,
    /// Its joints, MuJoCo ids (contiguous, in file order).
    pub joints: std::ops::Range<usize>,
    /// Mass (kg).
    pub mass: f64,
    /// Centre of mass in the body frame (`body_ipos`).
    pub com: Vector3<f64>,
    /// Inertia about the centre of mass in the body frame (`body_iquat`·diag(`body_inertia`)).
    pub inertia: Matrix3<f64>,
    /// Sites: name and pose in the body frame.
    pub sites: Vec<(String, Vector3<f64>, UnitQuaternion<f64>)>,
    /// Whether the body has an `<inertial>` element.
    pub(crate) explicit: Option<(f64, Vector3<f64>, Matrix3<f64>)>,
}

/// MuJoCo's compiled world.
#[derive(Clone, Debug)]
pub struct World {
    /// `<mujoco model>`.
    pub name: String,
    /// Bodies, the world (0) first, in MuJoCo's order (depth-first, file order).
    pub bodies: Vec<MjBody>,
    /// Joints in MuJoCo's order.
    pub joints: Vec<MjJoint>,
    /// Geoms in MuJoCo's order (the world's among them).
    pub geoms: Vec<MjGeom>,
    /// `<option gravity>` (zero under `<flag gravity="disable">`).
    pub gravity: Vector3<f64>,
    /// `<option><flag contact="disable">`: no contact at all (no collision
    /// shapes, no ground).
    pub contact_disabled: bool,
    /// `<option timestep>`.
    pub timestep: f64,
    /// `<contact><exclude>`: body pairs (MuJoCo ids) that never touch.
    pub excludes: Vec<(usize, usize)>,
    /// `<keyframe><key>`s in file order.
    pub keys: Vec<super::sections::MjKey>,
    /// `<actuator>`s in MuJoCo's order.
    pub actuators: Vec<super::actuators::MjActuator>,
    /// `<tendon>`s in MuJoCo's order.
    pub tendons: Vec<super::tendons::MjTendon>,
    /// `<equality>` constraints in MuJoCo's order.
    pub equalities: Vec<super::equality::MjEquality>,
    /// `<asset><mesh>`es by name (MuJoCo's: its `name`, else its file's name
    /// without the extension).
    pub meshes: std::collections::HashMap<String, MjMesh>,
    /// What urdyn does not model, one line a kind.
    pub warnings: Vec<String>,
}

/// An `<asset><mesh>`: its file (resolved as MuJoCo does: `meshdir`, else
/// `assetdir`, else the model's directory) and its `scale` (class defaults
/// applied). A mesh given inline (`vertex`/`face`) has no file.
#[derive(Clone, Debug, PartialEq)]
pub struct MjMesh {
    /// The mesh file.
    pub file: Option<std::path::PathBuf>,
    /// Scale along x, y, z.
    pub scale: [f64; 3],
    /// `inertia`: how its volume is taken (MuJoCo's default `legacy`).
    pub inertia: crate::mesh::MeshInertia,
}
