//! MuJoCo's compiler where it decides numbers: `<compiler>` settings, defaults and
//! `childclass`, `<frame>`, every orientation form, `fromto`, joints in their
//! body's frame, and (in inertia.rs) each body's mass properties. The result, a
//! [`World`], holds MuJoCo's compiled bodies, joints and geoms in MuJoCo's order
//! (ids as MuJoCo numbers them), with what the simulation phase will need.

use super::attrs::{Attrs, Defaults};
use super::orient;
use super::xml::El;
use super::MjcfError;
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use std::collections::HashSet;

pub use super::world::{MjBody, MjGeom, MjGeomType, MjJoint, MjJointType, MjMesh, World};

/// The `<compiler>` settings that decide numbers.
#[derive(Clone, Debug)]
pub(crate) struct Settings {
    pub degree: bool,
    pub eulerseq: [u8; 3],
    pub autolimits: bool,
    /// `inertiafromgeom`: Some(true) always, Some(false) never, None auto.
    pub inertia_from_geom: Option<bool>,
    pub group_range: (i64, i64),
    pub settotalmass: f64,
    pub balanceinertia: bool,
    pub boundmass: f64,
    pub boundinertia: f64,
}

const POSE: [&str; 6] = ["pos", "quat", "axisangle", "xyaxes", "zaxis", "euler"];

pub(crate) struct Ctx<'a> {
    pub set: Settings,
    pub defaults: &'a Defaults,
    pub world: World,
    pub names: [HashSet<String>; 4],
    pub not_modelled: Vec<String>,
    /// `<asset><material>` colours by name.
    pub materials: std::collections::HashMap<String, [f64; 4]>,
}

impl Ctx<'_> {
    /// An angle attribute in radians.
    pub fn angle(&self, x: f64) -> f64 {
        if self.set.degree {
            x.to_radians()
        } else {
            x
        }
    }
    /// The element's orientation (one form at most) and position.
    pub fn pose(&self, a: &Attrs) -> Result<(Vector3<f64>, UnitQuaternion<f64>), MjcfError> {
        let pos = Vector3::from(a.arr::<3>("pos")?.unwrap_or([0.0; 3]));
        let given: Vec<&str> = POSE[1..]
            .iter()
            .copied()
            .filter(|k| a.el.attr(k).is_some())
            .collect();
        if given.len() > 1 {
            return Err(a.el.err(format!(
                "{} and {}: give one orientation",
                given[0], given[1]
            )));
        }
        // the element's own form wins over its class's
        let form = given
            .first()
            .copied()
            .or_else(|| POSE[1..].iter().copied().find(|k| a.get(k).is_some()));
        let q = match form {
            None => UnitQuaternion::identity(),
            Some("quat") => {
                let q = a.arr::<4>("quat")?.unwrap_or([1.0, 0.0, 0.0, 0.0]);
                orient::quat_wxyz(q).ok_or_else(|| a.err("quat", "is a zero quaternion"))?
            }
            Some("axisangle") => {
                let v = a.arr::<4>("axisangle")?.unwrap_or_default();
                orient::axis_angle(Vector3::new(v[0], v[1], v[2]), self.angle(v[3]))
                    .ok_or_else(|| a.err("axisangle", "has a zero axis"))?
            }
            Some("euler") => {
                let e = a.arr::<3>("euler")?.unwrap_or_default();
                orient::euler(e.map(|x| self.angle(x)), &self.set.eulerseq)
            }
            Some("xyaxes") => {
                let v = a.arr::<6>("xyaxes")?.unwrap_or_default();
                orient::xy_axes(
                    Vector3::new(v[0], v[1], v[2]),
                    Vector3::new(v[3], v[4], v[5]),
                )
                .ok_or_else(|| a.err("xyaxes", "is degenerate"))?
            }
            _ => {
                let v = a.arr::<3>("zaxis")?.unwrap_or_default();
                orient::z_axis(Vector3::from(v))
                    .ok_or_else(|| a.err("zaxis", "is a zero vector"))?
            }
        };
        Ok((pos, q))
    }

    /// Registers a name of kind `k` (0 body, 1 joint, 2 geom, 3 site), refusing duplicates.
    pub(super) fn name(
        &mut self,
        k: usize,
        el: &El,
        fallback: String,
    ) -> Result<String, MjcfError> {
        let Some(n) = el.attr("name") else {
            return Ok(fallback);
        };
        if !self.names[k].insert(n.to_string()) {
            let kind = ["body", "joint", "geom", "site"][k];
            return Err(el.err(format!("name=\"{n}\": duplicate {kind} name")));
        }
        Ok(n.to_string())
    }

    pub(super) fn note(&mut self, what: String) {
        if !self.not_modelled.contains(&what) {
            self.not_modelled.push(what);
        }
    }
}

/// A frame composed onto a child pose: `(p, q) ∘ (pos, quat)`.
pub(super) fn compose(
    f: &(Vector3<f64>, UnitQuaternion<f64>),
    pos: Vector3<f64>,
    quat: UnitQuaternion<f64>,
) -> (Vector3<f64>, UnitQuaternion<f64>) {
    (f.0 + f.1 * pos, f.1 * quat)
}

const BODY_ATTRS: &[&str] = &[
    "name",
    "childclass",
    "pos",
    "quat",
    "axisangle",
    "xyaxes",
    "zaxis",
    "euler",
    "mocap",
    "gravcomp",
    "user",
    "sleep",
];
const JOINT_ATTRS: &[&str] = &[
    "name",
    "type",
    "group",
    "pos",
    "axis",
    "springdamper",
    "limited",
    "actuatorfrclimited",
    "solreflimit",
    "solimplimit",
    "solreffriction",
    "solimpfriction",
    "stiffness",
    "range",
    "actuatorfrcrange",
    "actuatorgravcomp",
    "margin",
    "ref",
    "springref",
    "armature",
    "damping",
    "frictionloss",
    "user",
];
const SITE_ATTRS: &[&str] = &[
    "name",
    "type",
    "group",
    "material",
    "rgba",
    "size",
    "fromto",
    "pos",
    "quat",
    "axisangle",
    "xyaxes",
    "zaxis",
    "euler",
    "user",
];
const INERTIAL_ATTRS: &[&str] = &[
    "pos",
    "quat",
    "axisangle",
    "xyaxes",
    "zaxis",
    "euler",
    "mass",
    "diaginertia",
    "fullinertia",
];
const FRAME_ATTRS: &[&str] = &[
    "name",
    "childclass",
    "pos",
    "quat",
    "axisangle",
    "xyaxes",
    "zaxis",
    "euler",
];

/// Walks the children of body `b` (an element `<worldbody>`, `<body>` or
/// `<frame>`), `frame` the pose of that element's frame in body `b`'s.
pub(crate) fn walk_children(
    cx: &mut Ctx,
    el: &El,
    b: usize,
    childclass: &str,
    frame: (Vector3<f64>, UnitQuaternion<f64>),
) -> Result<(), MjcfError> {
    // joints and inertial first (MuJoCo numbers a body's joints before its children's)
    for c in &el.children {
        match c.tag.as_str() {
            "joint" | "freejoint" => joint(cx, c, b, childclass, &frame)?,
            "inertial" => {
                if b == 0 {
                    return Err(c.err("the world body has no <inertial>"));
                }
                let a = cx.defaults.resolve(c, childclass)?;
                a.check_known(INERTIAL_ATTRS)?;
                let (pos, q) = cx.pose(&a)?;
                let (pos, q) = compose(&frame, pos, q);
                let mass = a.nonneg("mass", f64::NAN)?;
                if mass.is_nan() {
                    return Err(c.err("missing attribute mass"));
                }
                let r = q.to_rotation_matrix().into_inner();
                let i = match (a.arr::<3>("diaginertia")?, a.arr::<6>("fullinertia")?) {
                    (Some(d), None) => {
                        if d.iter().any(|x| *x < 0.0) {
                            return Err(a.err("diaginertia", "must not be negative"));
                        }
                        r * Matrix3::from_diagonal(&Vector3::from(d)) * r.transpose()
                    }
                    (None, Some(f)) => {
                        let m = Matrix3::new(f[0], f[3], f[4], f[3], f[1], f[5], f[4], f[5], f[2]);
                        r * m * r.transpose()
                    }
                    _ => return Err(c.err("give one of diaginertia and fullinertia")),
                };
                cx.world.bodies[b].explicit = Some((mass, pos, i));
            }
            _ => {}
        }
    }
    for c in &el.children {
        match c.tag.as_str() {
            "joint" | "freejoint" | "inertial" => {}
            "geom" => super::geom::geom(cx, c, b, childclass, &frame)?,
            "site" => {
                let a = cx.defaults.resolve(c, childclass)?;
                a.check_known(SITE_ATTRS)?;
                let (p, q) = cx.pose(&a)?;
                let (p, q) = compose(&frame, p, q);
                let n = cx.world.bodies.iter().map(|b| b.sites.len()).sum::<usize>();
                let name = cx.name(3, c, format!("site_{n}"))?;
                cx.world.bodies[b].sites.push((name, p, q));
            }
            "body" => body(cx, c, b, childclass, &frame)?,
            "frame" => {
                let a = cx.defaults.resolve(c, childclass)?;
                a.check_known(FRAME_ATTRS)?;
                let (p, q) = cx.pose(&a)?;
                let f = compose(&frame, p, q);
                let cc = c.attr("childclass").unwrap_or(childclass);
                walk_children(cx, c, b, cc, f)?;
            }
            "camera" | "light" => {}
            "plugin" => cx.note("plugins".into()),
            "composite" | "flexcomp" | "replicate" | "attach" => {
                return Err(c.err("not supported by urdyn's MJCF import"))
            }
            _ => return Err(c.err(format!("unknown element <{}> in <{}>", c.tag, el.tag))),
        }
    }
    Ok(())
}

fn body(
    cx: &mut Ctx,
    el: &El,
    parent: usize,
    childclass: &str,
    frame: &(Vector3<f64>, UnitQuaternion<f64>),
) -> Result<(), MjcfError> {
    let a = cx.defaults.resolve_body(el)?;
    a.check_known(BODY_ATTRS)?;
    let (p, q) = cx.pose(&a)?;
    let (pos, quat) = compose(frame, p, q);
    let id = cx.world.bodies.len();
    let name = cx.name(0, el, format!("body_{id}"))?;
    if a.get("gravcomp").is_some() {
        cx.note("gravity compensation (gravcomp)".into());
    }
    let nj = cx.world.joints.len();
    cx.world.bodies.push(MjBody {
        name,
        parent,
        pos,
        quat,
        joints: nj..nj,
        mass: 0.0,
        com: Vector3::zeros(),
        inertia: Matrix3::zeros(),
        sites: Vec::new(),
        explicit: None,
    });
    let cc = el.attr("childclass").unwrap_or(childclass);
    if !cx.defaults.classes.contains_key(cc) {
        return Err(el.err(format!("childclass=\"{cc}\": unknown default class")));
    }
    walk_children(
        cx,
        el,
        id,
        cc,
        (Vector3::zeros(), UnitQuaternion::identity()),
    )
}

impl Defaults {
    /// A body reads no defaults (its `childclass` is for its descendants).
    fn resolve_body<'a>(&'a self, el: &'a El) -> Result<Attrs<'a>, MjcfError> {
        self.resolve(el, "main")
    }
}

fn joint(
    cx: &mut Ctx,
    el: &El,
    b: usize,
    childclass: &str,
    frame: &(Vector3<f64>, UnitQuaternion<f64>),
) -> Result<(), MjcfError> {
    if b == 0 {
        return Err(el.err("the world body cannot have joints"));
    }
    let a = cx.defaults.resolve(el, childclass)?;
    let id = cx.world.joints.len();
    let name = cx.name(1, el, format!("joint_{id}"))?;
    let kind = if el.tag == "freejoint" {
        a.check_known(&["name", "group", "align"])?;
        MjJointType::Free
    } else {
        a.check_known(JOINT_ATTRS)?;
        match a.get("type").unwrap_or("hinge") {
            "hinge" => MjJointType::Hinge,
            "slide" => MjJointType::Slide,
            "ball" => MjJointType::Ball,
            "free" => MjJointType::Free,
            t => return Err(a.err("type", format!("unknown joint type \"{t}\""))),
        }
    };
    let body = &cx.world.bodies[b];
    if kind == MjJointType::Free {
        if body.parent != 0 {
            return Err(
                el.err("a free joint is allowed only in a top-level body (a child of <worldbody>)")
            );
        }
        if !body.joints.is_empty() {
            return Err(el.err("a body with a free joint has no other joint"));
        }
    } else if let Some(j) = body.joints.clone().next()
        && cx.world.joints[j].kind == MjJointType::Free
    {
        return Err(el.err("a body with a free joint has no other joint"));
    }
    let (pos, axis) = if kind == MjJointType::Free {
        (Vector3::zeros(), Vector3::z())
    } else {
        let p = Vector3::from(a.arr::<3>("pos")?.unwrap_or([0.0; 3]));
        let ax = Vector3::from(a.arr::<3>("axis")?.unwrap_or([0.0, 0.0, 1.0]));
        let n = ax.norm();
        if n.is_nan() || n < 1e-10 {
            return Err(a.err("axis", "is a zero axis"));
        }
        (frame.0 + frame.1 * p, frame.1 * (ax / n))
    };
    if a.get("actuatorfrcrange").is_some() || a.get("actuatorgravcomp") == Some("true") {
        cx.note("joints' actuatorfrcrange and actuatorgravcomp".into());
    }
    let angular = matches!(kind, MjJointType::Hinge | MjJointType::Ball);
    let conv = |x: f64| if angular { cx.angle(x) } else { x };
    let range = a.arr::<2>("range")?;
    let limited = match a.get("limited").unwrap_or("auto") {
        "true" => true,
        "false" => false,
        "auto" if cx.set.autolimits => range.is_some(),
        "auto" => false,
        _ => return Err(a.err("limited", "must be true, false or auto")),
    };
    let range = match (limited, range) {
        (true, Some([lo, _])) if kind == MjJointType::Ball && lo != 0.0 => {
            return Err(a.err("range", "a ball joint's range starts at 0 (a cone angle)"));
        }
        (true, Some([lo, hi])) => {
            if lo > hi {
                return Err(a.err("range", "lower bound above upper bound"));
            }
            Some((conv(lo), conv(hi)))
        }
        (true, None) => return Err(a.err("limited", "limited joint without a range")),
        _ => None,
    };
    let j = MjJoint {
        name,
        kind,
        body: b,
        pos,
        axis,
        range: if kind == MjJointType::Free {
            None
        } else {
            range
        },
        reference: conv(a.num("ref")?.unwrap_or(0.0)),
        armature: a.nonneg("armature", 0.0)?,
        damping: a.nonneg("damping", 0.0)?,
        frictionloss: a.nonneg("frictionloss", 0.0)?,
        stiffness: a.nonneg("stiffness", 0.0)?,
        springref: conv(a.num("springref")?.unwrap_or(0.0)),
        springdamper: a
            .arr::<2>("springdamper")?
            .and_then(|[t, z]| (t > 0.0 && z > 0.0).then_some((t, z))),
        label: el.label(),
    };
    cx.world.joints.push(j);
    cx.world.bodies[b].joints.end = id + 1;
    Ok(())
}
