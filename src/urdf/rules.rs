//! The URDF element rules the parser's checking scan (parse.rs) applies: which
//! attributes and children each element may have, which are required, how many
//! numbers an attribute holds, the joint types and shapes, the nesting limit.

/// The URDF version of `<robot version="M.N">` (urdf-rs semantics: missing or
/// malformed means 1.0).
pub(super) fn robot_version(v: Option<&str>) -> (u32, u32) {
    v.and_then(|v| {
        let (a, b) = v.trim().split_once('.')?;
        Some((a.parse().ok()?, b.parse().ok()?))
    })
    .unwrap_or((1, 0))
}

/// How many numbers an attribute of an element holds (`None`: not a number).
pub(super) fn numeric_arity(tag: &str, attr: &str) -> Option<usize> {
    Some(match (tag, attr) {
        ("origin", "xyz" | "rpy") => 3,
        ("origin", "quat_xyzw") => 4,
        ("axis", "xyz") | ("box", "size") | ("mesh", "scale") => 3,
        ("color", "rgba") => 4,
        ("mass", "value") => 1,
        ("inertia", "ixx" | "ixy" | "ixz" | "iyy" | "iyz" | "izz") => 1,
        (
            "limit",
            "lower" | "upper" | "effort" | "velocity" | "acceleration" | "deceleration" | "jerk",
        ) => 1,
        ("mimic", "multiplier" | "offset") => 1,
        ("dynamics", "damping" | "friction") => 1,
        ("calibration", "rising" | "falling") => 1,
        (
            "safety_controller",
            "soft_lower_limit" | "soft_upper_limit" | "k_position" | "k_velocity",
        ) => 1,
        ("cylinder" | "capsule", "radius" | "length") | ("sphere", "radius") => 1,
        _ => return None,
    })
}

/// The attributes the URDF specification (urdfdom, urdf-rs, URDF 1.0–1.2) gives an
/// element; `None` for an element outside it. `xmlns` declarations are known everywhere.
pub(super) fn known_attrs(tag: &str) -> Option<&'static [&'static str]> {
    Some(match tag {
        "robot" => &["name", "version"],
        "link" | "visual" | "collision" | "material" => &["name"],
        "joint" => &["name", "type"],
        "inertial" | "geometry" => &[],
        "origin" => &["xyz", "rpy", "quat_xyzw"],
        "mass" => &["value"],
        "inertia" => &["ixx", "ixy", "ixz", "iyy", "iyz", "izz"],
        "box" => &["size"],
        "cylinder" | "capsule" => &["radius", "length"],
        "sphere" => &["radius"],
        "mesh" => &["filename", "scale"],
        "color" => &["rgba"],
        "texture" => &["filename"],
        "parent" | "child" => &["link"],
        "axis" => &["xyz"],
        // urdfdom's JointCalibration also holds a reference position.
        "calibration" => &["rising", "falling", "reference_position"],
        "dynamics" => &["damping", "friction"],
        "limit" => &[
            "lower",
            "upper",
            "effort",
            "velocity",
            "acceleration",
            "deceleration",
            "jerk",
        ],
        "mimic" => &["joint", "multiplier", "offset"],
        "safety_controller" => &[
            "soft_lower_limit",
            "soft_upper_limit",
            "k_position",
            "k_velocity",
        ],
        _ => return None,
    })
}

/// The child elements the URDF specification allows below a (read) element.
pub(super) fn known_children(tag: &str) -> &'static [&'static str] {
    match tag {
        "link" => &["inertial", "visual", "collision"],
        "inertial" => &["origin", "mass", "inertia"],
        "visual" => &["origin", "geometry", "material"],
        "collision" => &["origin", "geometry"],
        "geometry" => &SHAPES,
        "material" => &["color", "texture"],
        "joint" => &[
            "origin",
            "parent",
            "child",
            "axis",
            "calibration",
            "dynamics",
            "limit",
            "mimic",
            "safety_controller",
        ],
        _ => &[],
    }
}

/// Top-level elements that no dynamics reads, skipped with their whole subtree:
/// simulator and controller extensions and the URDF sensor element.
pub(super) const SKIPPED_TOP_LEVEL: [&str; 4] =
    ["gazebo", "transmission", "sensor", "ros2_control"];

/// Link children outside the URDF specification that a widely used reader
/// defines (PyBullet's `<contact>` friction parameters), skipped whole.
pub(super) const SKIPPED_IN_LINK: [&str; 1] = ["contact"];

/// Attributes without which urdf-rs cannot read an element.
pub(super) fn required_attrs(
    tag: &str,
    parent: &str,
    version: (u32, u32),
) -> &'static [&'static str] {
    match (tag, parent) {
        ("link", "robot") | ("material", "robot" | "visual") => &["name"],
        ("joint", "robot") => &["name", "type"],
        ("parent" | "child", "joint") => &["link"],
        ("axis", "joint") => &["xyz"],
        ("limit", "joint") if version < (1, 2) => &["velocity"],
        ("mimic", "joint") => &["joint"],
        ("safety_controller", "joint") => &["k_velocity"],
        ("mass", "inertial") => &["value"],
        ("inertia", "inertial") => &["ixx", "ixy", "ixz", "iyy", "iyz", "izz"],
        ("box", "geometry") => &["size"],
        ("cylinder" | "capsule", "geometry") => &["radius", "length"],
        ("sphere", "geometry") => &["radius"],
        ("mesh", "geometry") => &["filename"],
        // A `<texture>` without `filename` is no texture (urdfdom's reading).
        ("color", "material") => &["rgba"],
        _ => &[],
    }
}

/// Children that urdf-rs requires (`required`) or allows at most once.
pub(super) fn child_rules(
    tag: &str,
    parent: &str,
) -> (&'static [&'static str], &'static [&'static str]) {
    match (tag, parent) {
        ("joint", "robot") => (
            &["parent", "child"],
            &[
                "parent",
                "child",
                "origin",
                "axis",
                "limit",
                "mimic",
                "dynamics",
                "calibration",
                "safety_controller",
            ],
        ),
        ("link", "robot") => (&[], &["inertial"]),
        ("inertial", "link") => (&["mass", "inertia"], &["mass", "inertia", "origin"]),
        ("visual" | "collision", "link") => (&["geometry"], &["geometry", "origin", "material"]),
        ("geometry", _) => (&[], &[]),
        _ => (&[], &[]),
    }
}

pub(super) const JOINT_TYPES: [&str; 7] = [
    "revolute",
    "continuous",
    "prismatic",
    "fixed",
    "floating",
    "planar",
    "spherical",
];
pub(super) const SHAPES: [&str; 5] = ["box", "cylinder", "capsule", "sphere", "mesh"];

/// The deepest element nesting accepted.
pub(super) const MAX_DEPTH: usize = 64;
