//! Builds the [`Robot`](super::super::types::Robot) from URDF text with quick-xml,
//! following urdf-rs 0.10's reading of URDF 1.0–1.2 (defaults, `quat_xyzw` from 1.1,
//! limit defaults and checks from 1.2). The text has passed the checking scan, so
//! required attributes exist and numbers parse; every access is still fallible.

use super::super::types::{
    Axis, Calibration, Collision, Dynamics, Geometry, Inertia, Inertial, Joint, JointLimit,
    JointType, Link, LinkName, Mass, Mimic, Pose, Robot, SafetyController, Vec3,
};
use super::super::UrdfError;
use quick_xml::events::{BytesStart, Event};

/// A small element tree: one top-level `<link>` or `<joint>`.
struct El {
    tag: String,
    attrs: Vec<(String, String)>,
    children: Vec<El>,
}

impl El {
    fn attr(&self, k: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(a, _)| a == k)
            .map(|(_, v)| v.as_str())
    }
    fn child(&self, tag: &str) -> Option<&El> {
        self.children.iter().find(|c| c.tag == tag)
    }
    fn all<'a>(&'a self, tag: &'a str) -> impl Iterator<Item = &'a El> + 'a {
        self.children.iter().filter(move |c| c.tag == tag)
    }
}

struct Ctx<'a> {
    file: &'a str,
    version: (u32, u32),
}

impl Ctx<'_> {
    fn err(&self, label: &str, msg: impl Into<String>) -> UrdfError {
        UrdfError::new(self.file, Some(label.to_string()), msg)
    }
    fn numbers(&self, el: &El, k: &str, label: &str) -> Result<Option<Vec<f64>>, UrdfError> {
        let Some(v) = el.attr(k) else { return Ok(None) };
        v.split_whitespace()
            .map(|p| p.parse::<f64>())
            .collect::<Result<Vec<f64>, _>>()
            .map(Some)
            .map_err(|_| self.err(label, format!("{k}=\"{v}\" is not numeric")))
    }
    fn num(&self, el: &El, k: &str, label: &str) -> Result<Option<f64>, UrdfError> {
        match self.numbers(el, k, label)? {
            None => Ok(None),
            Some(v) if v.len() == 1 => Ok(Some(v[0])),
            Some(_) => Err(self.err(label, format!("{k} must be one number"))),
        }
    }
    fn req(&self, el: &El, k: &str, label: &str) -> Result<f64, UrdfError> {
        self.num(el, k, label)?
            .ok_or_else(|| self.err(label, format!("missing attribute {k}")))
    }
    fn vec3(&self, el: &El, k: &str, label: &str) -> Result<Option<[f64; 3]>, UrdfError> {
        match self.numbers(el, k, label)? {
            None => Ok(None),
            Some(v) => <[f64; 3]>::try_from(v)
                .map(Some)
                .map_err(|_| self.err(label, format!("{k} must be 3 numbers"))),
        }
    }
    fn string(&self, el: &El, k: &str, label: &str) -> Result<String, UrdfError> {
        el.attr(k)
            .map(str::to_string)
            .ok_or_else(|| self.err(label, format!("missing attribute {k}")))
    }

    fn pose(&self, el: Option<&El>, owner: &str) -> Result<Pose, UrdfError> {
        let Some(el) = el else {
            return Ok(Pose::default());
        };
        let label = format!("{owner} <origin>");
        let xyz = self.vec3(el, "xyz", &label)?.unwrap_or([0.0; 3]);
        let mut rpy = self.vec3(el, "rpy", &label)?.unwrap_or([0.0; 3]);
        if self.version >= (1, 1) {
            if let Some(q) = self.numbers(el, "quat_xyzw", &label)? {
                if el.attr("rpy").is_some() {
                    return Err(self.err(&label, "both rpy and quat_xyzw are given"));
                }
                let q = <[f64; 4]>::try_from(q)
                    .map_err(|_| self.err(&label, "quat_xyzw must be 4 numbers"))?;
                rpy = quaternion_to_rpy(q);
            }
        }
        Ok(Pose {
            xyz: Vec3(xyz),
            rpy: Vec3(rpy),
        })
    }

    fn geometry(&self, el: Option<&El>, owner: &str) -> Result<Geometry, UrdfError> {
        let label = format!("{owner} <geometry>");
        let el = el.ok_or_else(|| self.err(owner, "missing <geometry>"))?;
        let shape = el
            .children
            .iter()
            .find(|c| {
                matches!(
                    c.tag.as_str(),
                    "box" | "cylinder" | "capsule" | "sphere" | "mesh"
                )
            })
            .ok_or_else(|| self.err(&label, "no shape"))?;
        let l = format!("{label} <{}>", shape.tag);
        let g = match shape.tag.as_str() {
            "box" => Geometry::Box {
                size: Vec3(
                    self.vec3(shape, "size", &l)?
                        .ok_or_else(|| self.err(&l, "missing attribute size"))?,
                ),
            },
            "cylinder" => Geometry::Cylinder {
                radius: self.req(shape, "radius", &l)?,
                length: self.req(shape, "length", &l)?,
            },
            "capsule" => Geometry::Capsule {
                radius: self.req(shape, "radius", &l)?,
                length: self.req(shape, "length", &l)?,
            },
            "sphere" => Geometry::Sphere {
                radius: self.req(shape, "radius", &l)?,
            },
            _ => Geometry::Mesh {
                filename: self.string(shape, "filename", &l)?,
                scale: self.vec3(shape, "scale", &l)?.map(Vec3),
            },
        };
        if self.version >= (1, 2) {
            let dims: Vec<f64> = match &g {
                Geometry::Box { size } => size.0.to_vec(),
                Geometry::Cylinder { radius, length } | Geometry::Capsule { radius, length } => {
                    vec![*radius, *length]
                }
                Geometry::Sphere { radius } => vec![*radius],
                Geometry::Mesh { .. } => vec![],
            };
            if dims.iter().any(|d| !(d.is_finite() && *d > 0.0)) {
                return Err(self.err(&l, "sizes must be positive and finite (URDF 1.2)"));
            }
        }
        Ok(g)
    }

    fn link(&self, el: &El) -> Result<Link, UrdfError> {
        let name = self.string(el, "name", "<link>")?;
        let label = format!("link \"{name}\"");
        let inertial = match el.child("inertial") {
            None => Inertial::default(),
            Some(i) => {
                let l = format!("{label} <inertial>");
                let mass = i
                    .child("mass")
                    .ok_or_else(|| self.err(&l, "missing <mass>"))?;
                let it = i
                    .child("inertia")
                    .ok_or_else(|| self.err(&l, "missing <inertia>"))?;
                let li = format!("{l} <inertia>");
                Inertial {
                    origin: self.pose(i.child("origin"), &l)?,
                    mass: Mass {
                        value: self.req(mass, "value", &format!("{l} <mass>"))?,
                    },
                    inertia: Inertia {
                        ixx: self.req(it, "ixx", &li)?,
                        ixy: self.req(it, "ixy", &li)?,
                        ixz: self.req(it, "ixz", &li)?,
                        iyy: self.req(it, "iyy", &li)?,
                        iyz: self.req(it, "iyz", &li)?,
                        izz: self.req(it, "izz", &li)?,
                    },
                }
            }
        };
        let mut collision = Vec::new();
        for (k, c) in el.all("collision").enumerate() {
            let l = format!("{label} <collision> #{}", k + 1);
            collision.push(Collision {
                name: c.attr("name").map(str::to_string),
                origin: self.pose(c.child("origin"), &l)?,
                geometry: self.geometry(c.child("geometry"), &l)?,
            });
        }
        Ok(Link {
            name,
            inertial,
            // Visuals are not used by dynamics: the scan checks them (warnings only).
            collision,
        })
    }

    fn joint(&self, el: &El) -> Result<Joint, UrdfError> {
        let name = self.string(el, "name", "<joint>")?;
        let label = format!("joint \"{name}\"");
        let t = self.string(el, "type", &label)?;
        let joint_type = match t.as_str() {
            "revolute" => JointType::Revolute,
            "continuous" => JointType::Continuous,
            "prismatic" => JointType::Prismatic,
            "fixed" => JointType::Fixed,
            "floating" => JointType::Floating,
            "planar" => JointType::Planar,
            "spherical" => JointType::Spherical,
            _ => return Err(self.err(&label, format!("unknown joint type \"{t}\""))),
        };
        let link_of = |tag: &str| -> Result<LinkName, UrdfError> {
            let c = el
                .child(tag)
                .ok_or_else(|| self.err(&label, format!("missing <{tag}>")))?;
            Ok(LinkName {
                link: self.string(c, "link", &format!("{label} <{tag}>"))?,
            })
        };
        let axis = match el.child("axis") {
            Some(a) => Axis {
                xyz: Vec3(
                    self.vec3(a, "xyz", &format!("{label} <axis>"))?
                        .ok_or_else(|| self.err(&label, "<axis> without xyz"))?,
                ),
            },
            // a planar joint's default plane is xy (mechanisms.md), URDF's axis x
            None if joint_type == JointType::Planar => Axis {
                xyz: Vec3([0.0, 0.0, 1.0]),
            },
            None => Axis::default(),
        };
        let limit = match el.child("limit") {
            None => JointLimit::default(),
            Some(l) => self.limit(l, &format!("{label} <limit>"))?,
        };
        let calibration = match el.child("calibration") {
            Some(c) => {
                let l = format!("{label} <calibration>");
                Some(Calibration {
                    rising: self.num(c, "rising", &l)?,
                    falling: self.num(c, "falling", &l)?,
                })
            }
            None => None,
        };
        let dynamics = match el.child("dynamics") {
            Some(d) => {
                let l = format!("{label} <dynamics>");
                Some(Dynamics {
                    damping: self.num(d, "damping", &l)?.unwrap_or(0.0),
                    friction: self.num(d, "friction", &l)?.unwrap_or(0.0),
                })
            }
            None => None,
        };
        let mimic = match el.child("mimic") {
            Some(m) => {
                let l = format!("{label} <mimic>");
                Some(Mimic {
                    joint: self.string(m, "joint", &l)?,
                    multiplier: self.num(m, "multiplier", &l)?,
                    offset: self.num(m, "offset", &l)?,
                })
            }
            None => None,
        };
        let safety_controller = match el.child("safety_controller") {
            Some(c) => {
                let l = format!("{label} <safety_controller>");
                Some(SafetyController {
                    soft_lower_limit: self.num(c, "soft_lower_limit", &l)?.unwrap_or(0.0),
                    soft_upper_limit: self.num(c, "soft_upper_limit", &l)?.unwrap_or(0.0),
                    k_position: self.num(c, "k_position", &l)?.unwrap_or(0.0),
                    k_velocity: self.req(c, "k_velocity", &l)?,
                })
            }
            None => None,
        };
        Ok(Joint {
            origin: self.pose(el.child("origin"), &label)?,
            parent: link_of("parent")?,
            child: link_of("child")?,
            name,
            joint_type,
            axis,
            limit,
            calibration,
            dynamics,
            mimic,
            safety_controller,
        })
    }

    /// `<limit>` as urdf-rs reads it: before 1.2, lower/upper/effort default to 0 and
    /// velocity is required; from 1.2, omitted limits are infinite, negative
    /// effort/velocity and upper < lower are errors.
    fn limit(&self, l: &El, label: &str) -> Result<JointLimit, UrdfError> {
        let inf = f64::INFINITY;
        if self.version < (1, 2) {
            return Ok(JointLimit {
                lower: self.num(l, "lower", label)?.unwrap_or(0.0),
                upper: self.num(l, "upper", label)?.unwrap_or(0.0),
                effort: self.num(l, "effort", label)?.unwrap_or(0.0),
                velocity: self.req(l, "velocity", label)?,
                acceleration: inf,
                deceleration: inf,
                jerk: inf,
            });
        }
        let lower = self.num(l, "lower", label)?.unwrap_or(-inf);
        let upper = self.num(l, "upper", label)?.unwrap_or(inf);
        if upper < lower {
            return Err(self.err(label, format!("upper {upper} < lower {lower}")));
        }
        let mut rest = [inf; 5];
        for (k, n) in ["effort", "velocity", "acceleration", "deceleration", "jerk"]
            .iter()
            .enumerate()
        {
            if let Some(v) = self.num(l, n, label)? {
                if v < 0.0 {
                    return Err(self.err(label, format!("{n} {v} is negative")));
                }
                rest[k] = v;
            }
        }
        if l.attr("deceleration").is_none() {
            rest[3] = rest[2];
        }
        Ok(JointLimit {
            lower,
            upper,
            effort: rest[0],
            velocity: rest[1],
            acceleration: rest[2],
            deceleration: rest[3],
            jerk: rest[4],
        })
    }
}

/// urdfdom's `getRPY` of a quaternion (x, y, z, w), as urdf-rs converts `quat_xyzw`.
fn quaternion_to_rpy([x, y, z, w]: [f64; 4]) -> [f64; 3] {
    let norm = (x * x + y * y + z * z + w * w).sqrt();
    let [x, y, z, w] = if norm > 0.0 {
        [x / norm, y / norm, z / norm, w / norm]
    } else {
        [0.0, 0.0, 0.0, 1.0]
    };
    let sin_pitch = -2.0 * (x * z - w * y);
    if sin_pitch <= -0.99999 {
        [0.0, -std::f64::consts::FRAC_PI_2, 2.0 * x.atan2(-y)]
    } else if sin_pitch >= 0.99999 {
        [0.0, std::f64::consts::FRAC_PI_2, 2.0 * (-x).atan2(y)]
    } else {
        let (sqx, sqy, sqz, sqw) = (x * x, y * y, z * z, w * w);
        [
            (2.0 * (y * z + w * x)).atan2(sqw - sqx - sqy + sqz),
            sin_pitch.asin(),
            (2.0 * (x * y + w * z)).atan2(sqw + sqx - sqy - sqz),
        ]
    }
}

fn element(e: &BytesStart, file: &str) -> Result<El, UrdfError> {
    let tag = String::from_utf8_lossy(e.name().as_ref()).into_owned();
    let mut attrs = Vec::new();
    for a in e.attributes() {
        let a = a.map_err(|err| {
            UrdfError::new(
                file,
                Some(format!("<{tag}>")),
                format!("malformed attribute: {err}"),
            )
        })?;
        let v = a.unescape_value().map_err(|err| {
            UrdfError::new(file, Some(format!("<{tag}>")), format!("attribute: {err}"))
        })?;
        attrs.push((
            String::from_utf8_lossy(a.key.as_ref()).into_owned(),
            v.into_owned(),
        ));
    }
    Ok(El {
        tag,
        attrs,
        children: Vec::new(),
    })
}

/// Reads the robot: the `<robot>` attributes and each top-level `<link>` and
/// `<joint>`, in file order (`<material>`s and `<visual>`s, which no dynamics
/// reads, are left out: the scan has checked them).
pub(super) fn build(text: &str, file: &str) -> Result<Robot, UrdfError> {
    let mut reader = quick_xml::Reader::from_str(text);
    let mut depth = 0usize;
    let mut ctx = Ctx {
        file,
        version: (1, 0),
    };
    let mut robot = Robot {
        name: String::new(),
        version: None,
        links: Vec::new(),
        joints: Vec::new(),
    };
    // The open top-level element (depth 1) and its open descendants.
    let mut stack: Vec<El> = Vec::new();
    // A finished top-level element becomes a `Link`/`Joint` at once (its tree is dropped).
    let finish = |ctx: &Ctx, robot: &mut Robot, t: El| -> Result<(), UrdfError> {
        match t.tag.as_str() {
            "link" => robot.links.push(ctx.link(&t)?),
            _ => robot.joints.push(ctx.joint(&t)?),
        }
        Ok(())
    };
    let xml_err =
        |e: quick_xml::Error| UrdfError::new(file, None, format!("not well-formed XML: {e}"));
    loop {
        let (e, empty) = match reader.read_event().map_err(xml_err)? {
            Event::Start(e) => (e, false),
            Event::Empty(e) => (e, true),
            Event::End(_) => {
                depth = depth.saturating_sub(1);
                if let Some(done) = stack.pop() {
                    match stack.last_mut() {
                        Some(p) => p.children.push(done),
                        None => finish(&ctx, &mut robot, done)?,
                    }
                }
                continue;
            }
            Event::Eof => break,
            _ => continue,
        };
        let keep = match depth {
            0 => {
                let attrs = element(&e, file)?.attrs;
                let get = |k: &str| attrs.iter().find(|(a, _)| a == k).map(|(_, v)| v.clone());
                robot.name = get("name").unwrap_or_default();
                robot.version = get("version");
                ctx.version = super::rules::robot_version(robot.version.as_deref());
                false
            }
            1 => matches!(e.name().as_ref(), b"link" | b"joint"),
            _ => !stack.is_empty(),
        };
        if keep {
            let el = element(&e, file)?;
            if empty {
                match stack.last_mut() {
                    Some(p) => p.children.push(el),
                    None => finish(&ctx, &mut robot, el)?,
                }
            } else {
                stack.push(el);
            }
        }
        if !empty {
            depth += 1;
            if !keep && depth > 1 {
                // An element we do not read: skip its whole subtree.
                reader.read_to_end(e.name()).map_err(xml_err)?;
                depth -= 1;
            }
        }
    }
    Ok(robot)
}
