//! The immutable [`Model`] (tree, joints, inertias, frames, collision geometry) and
//! the preallocated [`Data`] workspace — the Model/Data split of Pinocchio and MuJoCo.
//!
//! Bodies are stored flat, parent before child (`parent[i] < i`); body 0 is the
//! world. A body is a movable joint plus every link welded to its child link
//! through fixed joints; each URDF link stays addressable as a [`Frame`].

mod actuators;
mod armature;
pub mod configuration;
mod constraints;
mod data;
pub(crate) mod joint;
pub(crate) mod lie;
mod names;
mod topology;
mod trees;

pub use names::{edit_distance, nearest, BodyId, FrameId, JointId, NameError};

pub use actuators::{Actuator, Keyframe};
pub use constraints::{Attachment, Constraint, ConstraintError, ConstraintKind, Constraints};
pub use data::Data;
pub(crate) use data::KeptLdl6;
pub(crate) use joint::{dispatch_joint, dispatch_keyed, JointModel};
pub use joint::{Axis, Joint, JointKind};
pub use topology::{FdMethod, Topology};
pub use trees::{FreeJoint, Tree};

use crate::spatial::{Inertia, Scalar, Se3};
use nalgebra::{DVector, Vector3};
use std::path::PathBuf;

/// Position, velocity and effort limits of a 1-DoF joint; `None` where the URDF
/// gives none (urdf-rs reads a missing `<limit>` as 0..0: that is "unknown").
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct JointLimits {
    /// Lowest position (rad or m).
    pub lower: Option<f64>,
    /// Highest position (rad or m).
    pub upper: Option<f64>,
    /// Largest applied torque or force (N·m or N); simulation clamps to it.
    pub effort: Option<f64>,
    /// Largest speed (rad/s or m/s), as the URDF gives it (not enforced).
    pub velocity: Option<f64>,
}

/// Per-joint data of every joint that owns coordinates (a movable, non-mimic
/// URDF joint; not a `--floating-base` root), in engine order: one entry a
/// joint, of 1 (revolute, continuous, prismatic), 3 (spherical, planar) or 6
/// (floating) velocity coordinates. Limits, damping and friction are read for
/// 1-DoF joints only.
#[derive(Clone, Debug, PartialEq)]
pub struct DofInfo {
    /// The URDF joint's name.
    pub name: String,
    /// The joint's kind (its axis included).
    pub kind: JointKind,
    /// Its first coordinate in q ([`JointKind::nq`] of them).
    pub iq: usize,
    /// Its first coordinate in v ([`JointKind::nv`] of them).
    pub iv: usize,
    /// From `<limit>` (a continuous joint has no position limits).
    pub limits: JointLimits,
    /// Viscous damping (N·m·s/rad or N·s/m) from `<dynamics damping>`.
    pub damping: f64,
    /// Coulomb friction (N·m or N) from `<dynamics friction>`.
    pub friction: f64,
    /// Whether the joint is continuous (unbounded angle).
    pub continuous: bool,
    /// Rotor inertia on H's diagonal (MJCF `armature`, in H as MuJoCo's `qM`); 0
    /// for a URDF, whose `--armature` is the simulation's option.
    pub armature: f64,
    /// Joint spring stiffness (MJCF `stiffness`; 0 for a URDF).
    pub stiffness: f64,
    /// The spring's rest position (MJCF `springref`).
    pub springref: f64,
}

/// A link's (an MJCF body's) own mass properties as the file gives them
/// (`inspect --json`): mass, centre of mass and inertia about it, in its frame.
#[derive(Clone, Debug, PartialEq)]
pub struct LinkMass {
    /// The link's or body's name.
    pub name: String,
    /// Mass (kg).
    pub mass: f64,
    /// Centre of mass in the link frame (m).
    pub com: Vector3<f64>,
    /// Inertia about the centre of mass in the link frame (kg·m²).
    pub inertia: nalgebra::Matrix3<f64>,
}

/// A URDF link as a frame on its body: `placement` is `body_M_link`.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame<T: Scalar = f64> {
    /// The URDF link's name.
    pub name: String,
    /// The body the link is merged into (0: welded to the world).
    pub body: usize,
    /// `body_M_link`: the link frame in the body frame.
    pub placement: Se3<T>,
}

/// A collision shape as the URDF or a scene gives it (meshes are not read at import).
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// A box centred at its frame.
    Box {
        /// Edge lengths along x, y, z (m).
        size: [f64; 3],
    },
    /// A cylinder along its frame's z, centred.
    Cylinder {
        /// Radius (m).
        radius: f64,
        /// Length along z (m).
        length: f64,
    },
    /// A capsule along its frame's z, centred (urdf-rs's extension).
    Capsule {
        /// Radius (m).
        radius: f64,
        /// Length of the cylindrical part along z (m).
        length: f64,
    },
    /// A sphere centred at its frame.
    Sphere {
        /// Radius (m).
        radius: f64,
    },
    /// A mesh file (STL, OBJ, DAE), read when contact shapes are built.
    Mesh {
        /// The URDF's `filename` (`package://`, `file://` or a path relative to the URDF).
        filename: String,
        /// Per-axis scale.
        scale: [f64; 3],
    },
    /// A height field (a scene's terrain): a grid of heights over a rectangle
    /// centred on its frame, the surface z = h(x, y) above the frame.
    HeightField {
        /// Rows along y from −y to +y, each row along x from −x to +x: `heights[i][j]`
        /// is the height (m) at y = −size[1]/2 + i·size[1]/(rows − 1),
        /// x = −size[0]/2 + j·size[0]/(columns − 1). At least 2 × 2, not ragged.
        heights: Vec<Vec<f64>>,
        /// Extents along x and y (m), centred on the frame.
        size: [f64; 2],
    },
}

impl Shape {
    /// The shape's URDF element name (`box`, `cylinder`, `capsule`, `sphere`, `mesh`;
    /// a scene's `heightfield`).
    pub fn kind(&self) -> &'static str {
        match self {
            Shape::Box { .. } => "box",
            Shape::Cylinder { .. } => "cylinder",
            Shape::Capsule { .. } => "capsule",
            Shape::Sphere { .. } => "sphere",
            Shape::Mesh { .. } => "mesh",
            Shape::HeightField { .. } => "heightfield",
        }
    }
}

/// [`CollisionGeom::model`] of a static obstacle: a shape welded to the world
/// that belongs to no model (it touches every moving body, scene.md "Who
/// touches whom").
pub const OBSTACLE: usize = usize::MAX;

/// A `<collision>` element (or a scene obstacle): its shape, the link it belongs
/// to, and its placement in the body frame (`body_M_geom`).
#[derive(Clone, Debug, PartialEq)]
pub struct CollisionGeom {
    /// The URDF link the element belongs to (an obstacle: the obstacle's name).
    pub link: String,
    /// The body that link is merged into (0: welded to the world — an obstacle,
    /// or a fixed model's root and the links welded to it).
    pub body: usize,
    /// `body_M_geom`: the shape's frame in the body frame (for body 0: the world).
    pub placement: Se3<f64>,
    /// The geometry.
    pub shape: Shape,
    /// A [`Shape::Mesh`] collides as its triangle mesh (may be non-convex: a
    /// scene obstacle's mesh) instead of its convex hull (a URDF link's mesh).
    /// Ignored for other shapes.
    pub trimesh: bool,
    /// This side's Coulomb friction coefficient; a pair uses the larger of its
    /// two sides' (as MuJoCo). The ground's side is `ContactParams::friction`.
    /// A URDF import gives 0 (the URDF names none: the other side's
    /// coefficient, e.g. the ground's `--friction`, is the pair's); a scene
    /// gives its model's or obstacle's `friction` (default 1.0).
    pub friction: f64,
    /// Index of the scene model the shape belongs to (0 for a single URDF), or
    /// [`OBSTACLE`] for a static obstacle.
    pub model: usize,
}

/// Which pairs of collision shapes never touch, besides the fixed rules of
/// scene.md "Who touches whom" (same body, both welded to the world, a body and
/// its parent within one model), which need no data.
#[derive(Clone, Debug, PartialEq)]
pub struct CollisionFilter {
    /// Link-name pairs never in contact (SRDF `<disable_collisions>`, a scene's
    /// `exclude`): the shapes of the one link ([`CollisionGeom::link`]; an
    /// obstacle's name) never touch the shapes of the other, whatever body they
    /// were merged into. Order within a pair does not matter.
    pub excluded: Vec<(String, String)>,
    /// Per scene model ([`CollisionGeom::model`]): contact between two links of
    /// that model. A model without an entry has self-collision on.
    pub self_collision: Vec<bool>,
}

impl Default for CollisionFilter {
    /// One model, self-collision on (scene.md's default), nothing excluded.
    fn default() -> Self {
        Self {
            excluded: Vec::new(),
            self_collision: vec![true],
        }
    }
}

impl CollisionFilter {
    /// Whether model `m` collides with itself (true for a model without an entry).
    pub fn self_collides(&self, m: usize) -> bool {
        self.self_collision.get(m).copied().unwrap_or(true)
    }
    /// Whether the link pair (`a`, `b`) is excluded (either order).
    pub fn is_excluded(&self, a: &str, b: &str) -> bool {
        self.excluded
            .iter()
            .any(|(x, y)| (x == a && y == b) || (x == b && y == a))
    }
}

/// What the importer merged, ignored or found suspicious (printed by `inspect`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ImportReport {
    /// (link, body's link) pairs: links welded through fixed joints.
    pub merged: Vec<(String, String)>,
    /// The kinematic tree, one line a link, indented by depth.
    pub tree: Vec<String>,
    /// What the import skipped on purpose because no dynamics reads it
    /// (`<gazebo>`, `<transmission>`, `<sensor>`, xacro leftovers, `<calibration>`, ...).
    pub ignored: Vec<String>,
    /// Suspicious but usable input, one line each, naming the element: inertias
    /// that are not positive semi-definite (loaded as written) or not physical,
    /// massless subtrees, unknown limits, attributes and elements outside the URDF
    /// specification, malformed visuals and materials. `urdyn inspect --strict`
    /// makes the first one an error.
    pub warnings: Vec<String>,
    /// Each link's own mass properties, in file order (`inspect --json`).
    pub bodies: Vec<LinkMass>,
}

/// The immutable multibody model. Arrays indexed by body have `nbodies` entries,
/// entry 0 being the world.
#[derive(Clone, Debug)]
pub struct Model<T: Scalar = f64> {
    /// The `<robot name>`.
    pub name: String,
    /// Dimension of the configuration vector q (7 for a free base, then each
    /// joint's [`JointKind::nq`]).
    pub nq: usize,
    /// Dimension of the velocity vector v (6 for a free base, then each joint's
    /// [`JointKind::nv`]).
    pub nv: usize,
    /// Bodies, the world (0) included: links merged through fixed joints count once.
    pub nbodies: usize,
    /// `parent[i] < i`; `parent[0] = 0` (the world).
    pub parent: Vec<usize>,
    /// `joints[i]` connects body i to its parent (entry 0 unused).
    pub joints: Vec<Joint<T>>,
    /// `placements[i]` = `parent_M_joint`, the joint frame on the parent at q = 0 (`X_tree`).
    pub placements: Vec<Se3<T>>,
    /// Whether `placements[i].rot` is exactly the identity (decided at load; the
    /// hot loops then apply a revolute joint's rotation with 4 products a vector,
    /// see [`Joint::axis_rotation`]).
    pub placement_identity: Vec<bool>,
    /// Whether `placements[i].trans` is exactly zero (either sign; decided at
    /// load, [`zero_translation`]): a revolute joint's `λ(i)Mi` keeps its
    /// placement's translation at every q, so it then has none, and the CRBA
    /// and the bias RNEA (f64) move forces, motions and inertias across it by
    /// its rotation alone. Each term the translation enters (`t × f`, `m t`,
    /// the parallel-axis shift) is a product with a zero added to a value, so
    /// leaving them out gives the same numbers (at most a zero's sign differs:
    /// −0 + 0 is +0).
    pub placement_zero_trans: Vec<bool>,
    /// Spatial inertia of each body in its own frame (links merged).
    pub inertias: Vec<Inertia<T>>,
    /// The same inertias in origin form (mass, first moment, rotational inertia
    /// about the frame origin; [`crate::spatial::CompositeInertia::from_inertia`]),
    /// computed at load: the CRBA's starting composite inertias.
    pub inertias_origin: Vec<crate::spatial::CompositeInertia<T>>,
    /// URDF joint name of each body (entry 0: "universe").
    pub body_joint_names: Vec<String>,
    /// URDF link name of each body (its movable joint's child link).
    pub body_link_names: Vec<String>,
    /// Gravity vector in the world frame (docs/theory.md §"Gravity": the world accelerates by −g).
    pub gravity: Vector3<T>,
    /// Body 1 is a free joint at `q[0..7]`, `v[0..6]` (a floating robot, or a
    /// scene whose first model floats). Every free joint of a scene is in
    /// [`Model::free_joints`].
    pub floating_base: bool,
    /// Every free (6-DoF) joint, in body order (a floating robot: body 1 at
    /// q[0..7], v[0..6]; a scene: one per floating model).
    pub free_joints: Vec<FreeJoint>,
    /// The URDF models this one is made of, in q order: one tree for a lone URDF,
    /// one per model of a scene (names `MODEL/NAME`).
    pub trees: Vec<Tree>,
    /// The joints that own coordinates (excluding a free base), in engine order.
    pub dofs: Vec<DofInfo>,
    /// Every URDF link, in the URDF's order.
    pub frames: Vec<Frame<T>>,
    /// Every `<collision>` element, in the URDF's order (a scene: its models'
    /// in file order, then its obstacles', on body 0 with model [`OBSTACLE`]).
    pub collisions: Vec<CollisionGeom>,
    /// Which shape pairs never touch (SRDF, a scene's `exclude`, per-model
    /// self-collision).
    pub collision_filter: CollisionFilter,
    /// For the velocity coordinate k, the previous coordinate on its path to the root
    /// (`λ(k)` of the tree-sparse factorisation), or `usize::MAX` at a root.
    pub dof_parent: Vec<usize>,
    /// Whether any joint is a mimic joint (H is then Gᵀ H_full G, with extra fill).
    pub has_mimic: bool,
    /// Movable joints whose subtree has neither mass nor inertia (H singular).
    pub massless_joints: Vec<String>,
    /// Tree-shape facts and the forward-dynamics method chosen from them.
    pub topology: Topology,
    /// The URDF file this model came from (mesh paths are resolved against it).
    pub source: Option<PathBuf>,
    /// What the import merged, ignored or warned about.
    pub report: ImportReport,
    /// The configuration the file defines (MJCF's `qpos0`: each hinge or slide at
    /// its `ref`, each free joint at its body's defined pose), returned by
    /// [`Model::neutral`]; `None` (a URDF, a scene): zeros and identity rotations.
    pub qpos0: Option<Vec<f64>>,
    /// The file's actuators (MJCF `<actuator>`; none for a URDF), in its order.
    pub actuators: Vec<Actuator>,
    /// The file's named starting states (MJCF `<keyframe>`; none for a URDF).
    pub keyframes: Vec<Keyframe>,
    /// The file's own loop constraints (MJCF `<equality>` as mechanisms.md's
    /// `point`, `frame`, `joint`; none for a URDF): `eval` applies the active
    /// ones, a [`crate::sim::Simulation`] starts with them (inactive ones off).
    pub equalities: Constraints,
    /// Whether each of [`Model::equalities`] is on at the start (`active`).
    pub equality_active: Vec<bool>,
}

impl<T: Scalar> Model<T> {
    /// Index of the first joint DoF in v (6 with a free base, else 0): a lone
    /// URDF's joints are `v[joint_v_offset()..]`. A scene's models each have
    /// their own ([`Tree::joint_v`], [`Model::dof_v`]).
    pub fn joint_v_offset(&self) -> usize {
        if self.floating_base {
            6
        } else {
            0
        }
    }
    /// Index of the first joint coordinate in q (7 with a free base, else 0): a
    /// lone URDF's joints are `q[joint_q_offset()..]`. A scene's models each have
    /// their own ([`Tree::joint_q`], [`Model::dof_q`]).
    pub fn joint_q_offset(&self) -> usize {
        if self.floating_base {
            7
        } else {
            0
        }
    }
    /// DoF names (joints only) in engine order.
    pub fn dof_names(&self) -> Vec<&str> {
        self.dofs.iter().map(|d| d.name.as_str()).collect()
    }
    /// Position of a DoF by joint name in [`Model::dofs`]: neither a q nor a v
    /// index (those are offset by a floating base).
    #[deprecated(
        note = "an index into `dofs`, neither q nor v: use `q_index`, `v_index` or `joint_id` + `joint_v_range`"
    )]
    pub fn dof_index(&self, name: &str) -> Option<usize> {
        self.dofs.iter().position(|d| d.name == name)
    }
    /// Index of a URDF link in [`Model::frames`] (see [`Model::frame_id`] for an
    /// error naming the nearest link).
    pub fn frame_index(&self, name: &str) -> Option<usize> {
        self.frames.iter().position(|f| f.name == name)
    }
    /// The neutral configuration: [`Model::qpos0`] when the file defines one, else
    /// zeros, identity orientation of every free and spherical joint.
    pub fn neutral(&self) -> DVector<T> {
        if let Some(q0) = self.qpos0.as_ref().filter(|q0| q0.len() == self.nq) {
            return DVector::from_iterator(self.nq, q0.iter().map(|&x| nalgebra::convert(x)));
        }
        let mut q = DVector::zeros(self.nq);
        for f in &self.free_joints {
            q[f.iq + 6] = T::one();
        }
        for d in &self.dofs {
            match d.kind {
                JointKind::Free => q[d.iq + 6] = T::one(),
                JointKind::Spherical => q[d.iq + 3] = T::one(),
                _ => {}
            }
        }
        q
    }
    /// Whether every joint that owns coordinates is a 1-DoF one (the free base aside).
    pub fn all_dofs_scalar(&self) -> bool {
        self.dofs.iter().all(|d| d.kind.nv() == 1)
    }
    /// Total mass of the bodies that move (the world excluded).
    pub fn total_mass(&self) -> T {
        self.inertias
            .iter()
            .skip(1)
            .fold(T::zero(), |s, i| s + i.mass)
    }
    /// Whether body `j` is `i` or one of its ancestors.
    pub fn is_ancestor(&self, j: usize, mut i: usize) -> bool {
        loop {
            if i == j {
                return true;
            }
            if i == 0 {
                return false;
            }
            i = self.parent[i];
        }
    }
}

/// A vector or matrix of the wrong size for the model: names the argument.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("{arg} has {got} entries, the model needs {expected}")]
pub struct DimensionError {
    /// The argument's name (`"q"`, `"v"`, `"fext"`, …).
    pub arg: &'static str,
    /// The size the model needs (nq, nv, nbodies, …).
    pub expected: usize,
    /// The size given.
    pub got: usize,
}

impl DimensionError {
    /// `Ok` iff `got == expected`, else the error naming `arg` (O(1)).
    #[inline]
    pub fn check(arg: &'static str, expected: usize, got: usize) -> Result<(), Self> {
        if got == expected {
            Ok(())
        } else {
            Err(Self { arg, expected, got })
        }
    }
}

impl Model<f64> {
    /// Converts the model to another scalar type (e.g. a higher-precision one).
    pub fn cast<U: Scalar>(&self) -> Model<U> {
        type T = f64;
        let c = |x: T| -> U { nalgebra::convert(x) };
        let cv = |v: &Vector3<T>| v.map(c);
        let cs = |m: &Se3<T>| Se3::new(m.rot.map(c), m.trans.map(c));
        let cj = |j: &Joint<T>| Joint {
            kind: match j.kind {
                JointKind::Free => JointKind::Free,
                JointKind::Spherical => JointKind::Spherical,
                JointKind::Planar => JointKind::Planar,
                JointKind::Revolute(a) => JointKind::Revolute(cast_axis(a, &cv)),
                JointKind::Prismatic(a) => JointKind::Prismatic(cast_axis(a, &cv)),
            },
            iq: j.iq,
            iv: j.iv,
            mult: c(j.mult),
            offset: c(j.offset),
        };
        Model {
            name: self.name.clone(),
            nq: self.nq,
            nv: self.nv,
            nbodies: self.nbodies,
            parent: self.parent.clone(),
            joints: self.joints.iter().map(cj).collect(),
            placements: self.placements.iter().map(cs).collect(),
            placement_identity: self.placement_identity.clone(),
            placement_zero_trans: self.placement_zero_trans.clone(),
            inertias: self
                .inertias
                .iter()
                .map(|i| Inertia::new(c(i.mass), cv(&i.com), i.inertia_c.map(c)))
                .collect(),
            inertias_origin: self
                .inertias_origin
                .iter()
                .map(|i| crate::spatial::CompositeInertia {
                    m: c(i.m),
                    h: cv(&i.h),
                    io: i.io.map(c),
                })
                .collect(),
            body_joint_names: self.body_joint_names.clone(),
            body_link_names: self.body_link_names.clone(),
            gravity: cv(&self.gravity),
            floating_base: self.floating_base,
            free_joints: self.free_joints.clone(),
            trees: self.trees.clone(),
            dofs: self.dofs.clone(),
            frames: self
                .frames
                .iter()
                .map(|f| Frame {
                    name: f.name.clone(),
                    body: f.body,
                    placement: cs(&f.placement),
                })
                .collect(),
            collisions: self.collisions.clone(),
            collision_filter: self.collision_filter.clone(),
            dof_parent: self.dof_parent.clone(),
            has_mimic: self.has_mimic,
            massless_joints: self.massless_joints.clone(),
            topology: self.topology.clone(),
            source: self.source.clone(),
            report: self.report.clone(),
            qpos0: self.qpos0.clone(),
            actuators: self.actuators.clone(),
            keyframes: self.keyframes.clone(),
            equalities: self.equalities.clone(),
            equality_active: self.equality_active.clone(),
        }
    }
}

/// Whether a placement's translation is exactly zero (either sign):
/// [`Model::placement_zero_trans`], set by every constructor of a [`Model`].
pub fn zero_translation<T: Scalar>(placement: &Se3<T>) -> bool {
    placement.trans.iter().all(|x| *x == T::zero())
}

/// [`zero_translation`] of each placement.
pub fn zero_translations<T: Scalar>(placements: &[Se3<T>]) -> Vec<bool> {
    placements.iter().map(zero_translation).collect()
}

/// Whether a placement's rotation is exactly the identity:
/// [`Model::placement_identity`], set by every constructor of a [`Model`].
pub fn identity_rotation<T: Scalar>(placement: &Se3<T>) -> bool {
    placement.rot == nalgebra::Matrix3::identity()
}

/// [`identity_rotation`] of each placement.
pub fn identity_rotations<T: Scalar>(placements: &[Se3<T>]) -> Vec<bool> {
    placements.iter().map(identity_rotation).collect()
}

fn cast_axis<T: Scalar, U: Scalar>(a: Axis<T>, cv: &impl Fn(&Vector3<T>) -> Vector3<U>) -> Axis<U> {
    match a {
        Axis::X => Axis::X,
        Axis::Y => Axis::Y,
        Axis::Z => Axis::Z,
        Axis::Unit(u) => Axis::Unit(cv(&u)),
    }
}
