//! The parsed URDF: links and joints as urdf-rs 0.10 models them (its field names,
//! defaults and URDF 1.0–1.2 semantics), built by `build.rs` with quick-xml. Only the
//! types are kept: urdf-rs's own reader (xml-rs, serde-xml-rs, RustyXML, regex) was
//! never called and cost a fifth of the first build (Cargo.toml §"urdf-rs").
//! Visuals and materials, which no dynamics reads, are checked by the scan and not
//! built. Fields are the URDF attributes and elements of the same names.
//!
//! Adapted from urdf-rs 0.10's `deserialize.rs` (https://github.com/openrr/urdf-rs,
//! Apache-2.0, © the urdf-rs authors): the type and field names and their defaults.
#![allow(missing_docs)]

/// Three numbers (`xyz`, `rpy`, `size`, `scale`).
#[derive(Debug, Default, Clone, Copy, PartialEq)]
pub struct Vec3(pub [f64; 3]);

impl std::ops::Deref for Vec3 {
    type Target = [f64; 3];
    fn deref(&self) -> &[f64; 3] {
        &self.0
    }
}

/// `<mass value>`.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Mass {
    pub value: f64,
}

/// `<inertia>`: the tensor about the centre of mass, in the inertial frame.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Inertia {
    pub ixx: f64,
    pub ixy: f64,
    pub ixz: f64,
    pub iyy: f64,
    pub iyz: f64,
    pub izz: f64,
}

/// `<inertial>`: a link without one has zero mass.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Inertial {
    pub origin: Pose,
    pub mass: Mass,
    pub inertia: Inertia,
}

/// `<geometry>`'s shape.
#[derive(Debug, Clone, PartialEq)]
pub enum Geometry {
    Box {
        size: Vec3,
    },
    Cylinder {
        radius: f64,
        length: f64,
    },
    Capsule {
        radius: f64,
        length: f64,
    },
    Sphere {
        radius: f64,
    },
    Mesh {
        filename: String,
        scale: Option<Vec3>,
    },
}

impl Default for Geometry {
    fn default() -> Self {
        Geometry::Box {
            size: Vec3::default(),
        }
    }
}

/// `<collision>`.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Collision {
    pub name: Option<String>,
    pub origin: Pose,
    pub geometry: Geometry,
}

/// `<link>` (its visuals are not built: always empty).
#[derive(Debug, Clone, PartialEq)]
pub struct Link {
    pub name: String,
    pub inertial: Inertial,
    pub collision: Vec<Collision>,
}

/// `<axis xyz>`: x when omitted.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    pub xyz: Vec3,
}

impl Default for Axis {
    fn default() -> Axis {
        Axis {
            xyz: Vec3([1.0, 0.0, 0.0]),
        }
    }
}

/// `<origin xyz rpy>` (a `quat_xyzw` is converted to rpy).
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Pose {
    pub xyz: Vec3,
    pub rpy: Vec3,
}

/// `<parent link>`, `<child link>`.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct LinkName {
    pub link: String,
}

/// A joint's `type`.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub enum JointType {
    Revolute,
    Continuous,
    Prismatic,
    #[default]
    Fixed,
    Floating,
    Planar,
    Spherical,
}

/// `<limit>`: from URDF 1.2 an omitted limit is infinite (`lower` negative);
/// `acceleration`, `deceleration` and `jerk` (1.2) are infinite before.
#[derive(Debug, Clone, PartialEq)]
pub struct JointLimit {
    pub lower: f64,
    pub upper: f64,
    pub effort: f64,
    pub velocity: f64,
    pub acceleration: f64,
    /// `acceleration` when omitted.
    pub deceleration: f64,
    pub jerk: f64,
}

impl Default for JointLimit {
    fn default() -> Self {
        Self {
            lower: 0.0,
            upper: 0.0,
            effort: 0.0,
            velocity: 0.0,
            acceleration: f64::INFINITY,
            deceleration: f64::INFINITY,
            jerk: f64::INFINITY,
        }
    }
}

/// `<mimic>`.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Mimic {
    pub joint: String,
    pub multiplier: Option<f64>,
    pub offset: Option<f64>,
}

/// `<safety_controller>` (read, not used by dynamics).
#[derive(Debug, Default, Clone, PartialEq)]
pub struct SafetyController {
    pub soft_lower_limit: f64,
    pub soft_upper_limit: f64,
    pub k_position: f64,
    pub k_velocity: f64,
}

/// `<joint>`.
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    pub name: String,
    pub joint_type: JointType,
    pub origin: Pose,
    pub parent: LinkName,
    pub child: LinkName,
    pub axis: Axis,
    pub limit: JointLimit,
    pub calibration: Option<Calibration>,
    pub dynamics: Option<Dynamics>,
    pub mimic: Option<Mimic>,
    pub safety_controller: Option<SafetyController>,
}

/// `<calibration>` (read, not used by dynamics).
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Calibration {
    pub rising: Option<f64>,
    pub falling: Option<f64>,
}

/// `<dynamics damping friction>`.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Dynamics {
    pub damping: f64,
    pub friction: f64,
}

/// `<robot>`: its links and joints in file order.
#[derive(Debug, Clone, PartialEq)]
pub struct Robot {
    pub name: String,
    /// The URDF version, such as `"1.1"`; `None` is 1.0.
    pub version: Option<String>,
    pub links: Vec<Link>,
    pub joints: Vec<Joint>,
}
