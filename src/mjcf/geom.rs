//! MuJoCo's compiler for one `<geom>`: its type, size (and `fromto`), pose in the
//! body's frame, contact settings, colour and, inside the `<compiler>`'s group
//! range, its mass properties (primitives here, meshes in inertia.rs).

use super::compile::{compose, Ctx};
use super::orient;
use super::world::{MjGeom, MjGeomType};
use super::xml::El;
use super::MjcfError;
use nalgebra::{UnitQuaternion, Vector3};

const GEOM_ATTRS: &[&str] = &[
    "name",
    "type",
    "contype",
    "conaffinity",
    "condim",
    "group",
    "priority",
    "size",
    "material",
    "friction",
    "mass",
    "density",
    "shellinertia",
    "solmix",
    "solref",
    "solimp",
    "margin",
    "gap",
    "fromto",
    "pos",
    "quat",
    "axisangle",
    "xyaxes",
    "zaxis",
    "euler",
    "hfield",
    "mesh",
    "fitscale",
    "rgba",
    "fluidshape",
    "fluidcoef",
    "user",
];

pub(super) fn geom(
    cx: &mut Ctx,
    el: &El,
    b: usize,
    childclass: &str,
    frame: &(Vector3<f64>, UnitQuaternion<f64>),
) -> Result<(), MjcfError> {
    let a = cx.defaults.resolve(el, childclass)?;
    a.check_known(GEOM_ATTRS)?;
    let id = cx.world.geoms.len();
    let name = cx.name(2, el, format!("geom_{id}"))?;
    let kind = match a.get("type").unwrap_or("sphere") {
        "plane" => MjGeomType::Plane,
        "hfield" => MjGeomType::Hfield,
        "sphere" => MjGeomType::Sphere,
        "capsule" => MjGeomType::Capsule,
        "ellipsoid" => MjGeomType::Ellipsoid,
        "cylinder" => MjGeomType::Cylinder,
        "box" => MjGeomType::Box,
        "mesh" => MjGeomType::Mesh,
        t => return Err(a.err("type", format!("unknown geom type \"{t}\""))),
    };
    let mut size = a.partial::<3>("size", [0.0; 3])?;
    if size.iter().any(|s| *s < 0.0) {
        return Err(a.err("size", "must not be negative"));
    }
    let (mut pos, mut quat) = cx.pose(&a)?;
    if let Some(ft) = a.arr::<6>("fromto")? {
        let (p0, p1) = (
            Vector3::new(ft[0], ft[1], ft[2]),
            Vector3::new(ft[3], ft[4], ft[5]),
        );
        let d = p1 - p0;
        match kind {
            MjGeomType::Capsule | MjGeomType::Cylinder => size[1] = d.norm() / 2.0,
            MjGeomType::Box | MjGeomType::Ellipsoid => {
                size[1] = size[0];
                size[2] = d.norm() / 2.0;
            }
            _ => {
                return Err(a.err(
                    "fromto",
                    "applies to capsules, cylinders, boxes and ellipsoids",
                ))
            }
        }
        pos = (p0 + p1) / 2.0;
        quat = orient::z_axis(d).ok_or_else(|| a.err("fromto", "has equal ends"))?;
    }
    let (pos, quat) = compose(frame, pos, quat);
    let group = a.int("group")?.unwrap_or(0);
    let friction = a.partial::<3>("friction", [1.0, 0.005, 0.0001])?;
    let condim = a.int("condim")?.unwrap_or(3);
    if condim == 4 || condim == 6 {
        cx.note("condim 4/6 (torsional and rolling friction)".into());
    }
    if a.flag("shellinertia")? == Some(true) {
        return Err(a.err(
            "shellinertia",
            "shell inertia is not supported by urdyn yet",
        ));
    }
    let asset = match kind {
        MjGeomType::Mesh => Some(
            a.get("mesh")
                .ok_or_else(|| el.err("a mesh geom needs mesh"))?,
        ),
        MjGeomType::Hfield => Some(
            a.get("hfield")
                .ok_or_else(|| el.err("an hfield geom needs hfield"))?,
        ),
        _ => None,
    }
    .map(str::to_string);
    let in_group = group >= cx.set.group_range.0 && group <= cx.set.group_range.1;
    // a body with an <inertial> takes no mass from its geoms (unless
    // inertiafromgeom="true"): a mesh there needs no mass properties
    let from_geoms =
        cx.world.bodies[b].explicit.is_none() || cx.set.inertia_from_geom == Some(true);
    let mut mesh_mass = None;
    let (mass, inertia) = if kind == MjGeomType::Mesh && !from_geoms {
        (0.0, [0.0; 3])
    } else if b != 0 && in_group {
        let density = a.nonneg("density", 1000.0)?;
        let mass = a.num("mass")?;
        if mass.is_some_and(|m| m < 0.0) {
            return Err(a.err("mass", "must not be negative"));
        }
        match (kind, asset.as_deref()) {
            (MjGeomType::Mesh, Some(mesh)) => {
                let (m, c, i) =
                    super::inertia::mesh_geom_mass(&cx.world.meshes, mesh, mass, density)
                        .map_err(|m| el.err(m))?;
                let r = quat.to_rotation_matrix().into_inner();
                mesh_mass = Some((pos + r * c, r * i * r.transpose()));
                (m, [0.0; 3])
            }
            _ => super::inertia::geom_mass(kind, &size, mass, density).map_err(|m| el.err(m))?,
        }
    } else {
        (0.0, [0.0; 3])
    };
    cx.world.geoms.push(MjGeom {
        name,
        body: b,
        kind,
        size,
        pos,
        quat,
        mass,
        inertia,
        mesh_mass,
        contype: a.int("contype")?.unwrap_or(1),
        conaffinity: a.int("conaffinity")?.unwrap_or(1),
        condim,
        priority: a.int("priority")?.unwrap_or(0),
        group,
        friction,
        rgba: {
            // MuJoCo's renderer: the material's colour when the geom's is the default
            const GREY: [f64; 4] = [0.5, 0.5, 0.5, 1.0];
            let own = a.partial::<4>("rgba", GREY)?;
            match a.get("material").and_then(|m| cx.materials.get(m)) {
                Some(m) if own == GREY => *m,
                _ => own,
            }
        },
        asset,
    });
    Ok(())
}
