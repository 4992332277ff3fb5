//! Mass properties as MuJoCo's compiler makes them (docs/theory.md §"MJCF
//! import"): each geom's volume, mass and principal moments (solid primitives),
//! then each body's: its `<inertial>`, or the sum of its geoms' about their
//! common centre of mass (`inertiafromgeom`, `inertiagrouprange`), then
//! `boundmass`/`boundinertia`, `balanceinertia` and `settotalmass`.

use super::compile::{MjGeomType, Settings, World};
use super::world::MjMesh;
use nalgebra::{Matrix3, Vector3};
use std::collections::HashMap;
use std::f64::consts::PI;

/// A geom's mass and principal moments about its centre (its own frame):
/// `mass` when given, else `density` × volume.
pub(crate) fn geom_mass(
    kind: MjGeomType,
    size: &[f64; 3],
    mass: Option<f64>,
    density: f64,
) -> Result<(f64, [f64; 3]), String> {
    let [a, b, c] = *size;
    let volume = match kind {
        MjGeomType::Sphere => 4.0 / 3.0 * PI * a * a * a,
        MjGeomType::Capsule => PI * a * a * (2.0 * b) + 4.0 / 3.0 * PI * a * a * a,
        MjGeomType::Cylinder => PI * a * a * (2.0 * b),
        MjGeomType::Ellipsoid => 4.0 / 3.0 * PI * a * b * c,
        MjGeomType::Box => 8.0 * a * b * c,
        MjGeomType::Plane | MjGeomType::Hfield => return Ok((0.0, [0.0; 3])),
        MjGeomType::Mesh => return Err("a mesh geom's mass properties come from its mesh".into()),
    };
    let m = mass.unwrap_or(density * volume);
    let i = match kind {
        MjGeomType::Sphere => {
            let s = 2.0 * m * a * a / 5.0;
            [s, s, s]
        }
        MjGeomType::Capsule => {
            let (r, h) = (a, 2.0 * b);
            let sphere_mass = m * 4.0 * r / (4.0 * r + 3.0 * h);
            let cyl_mass = m - sphere_mass;
            let mut xx = cyl_mass * (3.0 * r * r + h * h) / 12.0;
            let mut zz = cyl_mass * r * r / 2.0;
            let sphere_i = 2.0 * sphere_mass * r * r / 5.0;
            xx += sphere_i + sphere_mass * h * (3.0 * r + 2.0 * h) / 8.0;
            zz += sphere_i;
            [xx, xx, zz]
        }
        MjGeomType::Cylinder => {
            let (r, h) = (a, 2.0 * b);
            let xx = m * (3.0 * r * r + h * h) / 12.0;
            [xx, xx, m * r * r / 2.0]
        }
        MjGeomType::Ellipsoid => [
            m * (b * b + c * c) / 5.0,
            m * (a * a + c * c) / 5.0,
            m * (a * a + b * b) / 5.0,
        ],
        _ => [
            m * (b * b + c * c) / 3.0,
            m * (a * a + c * c) / 3.0,
            m * (a * a + b * b) / 3.0,
        ],
    };
    Ok((m, i))
}

/// A mesh geom's mass, centre of mass and inertia about it (the geom's
/// frame): its mesh's by MuJoCo's rule (`crate::mesh::mass_properties`),
/// at `density`, or scaled to `mass` when given (MuJoCo: density = mass /
/// volume).
pub(crate) fn mesh_geom_mass(
    meshes: &HashMap<String, MjMesh>,
    name: &str,
    mass: Option<f64>,
    density: f64,
) -> Result<(f64, Vector3<f64>, Matrix3<f64>), String> {
    let mesh = meshes
        .get(name)
        .ok_or_else(|| format!("mesh=\"{name}\": no such <mesh> asset"))?;
    let Some(file) = &mesh.file else {
        return Err(format!(
            "mesh \"{name}\": the mass properties of an inline mesh (vertex/face) are not supported by urdyn yet (give the body an <inertial>)"
        ));
    };
    let tri = crate::mesh::load_mesh(file, mesh.scale).map_err(|e| e.to_string())?;
    let props = crate::mesh::mass_properties(&tri, mesh.inertia)
        .map_err(|e| format!("mesh \"{name}\" ({}): {e}", file.display()))?;
    let density = match mass {
        Some(0.0) => 0.0,
        Some(m) if props.volume > 1e-14 => m / props.volume,
        Some(_) => 0.0,
        None => density,
    };
    Ok((density * props.volume, props.com, props.inertia * density))
}

/// Every body's mass, centre of mass and inertia (about the centre of mass, body
/// frame), as MuJoCo's compiler.
pub(crate) fn bodies(world: &mut World, set: &Settings) {
    for b in 1..world.bodies.len() {
        let explicit = world.bodies[b].explicit;
        let (m, c, i) = match (explicit, set.inertia_from_geom) {
            (Some(e), None | Some(false)) => e,
            (None, Some(false)) => (0.0, Vector3::zeros(), Matrix3::zeros()),
            _ => from_geoms(world, b),
        };
        let (m, i) = bounds(m, i, set);
        let body = &mut world.bodies[b];
        body.mass = m;
        body.com = c;
        body.inertia = i;
    }
    if set.settotalmass > 0.0 {
        let total: f64 = world.bodies[1..].iter().map(|b| b.mass).sum();
        if total > 0.0 {
            let scale = set.settotalmass / total;
            for body in &mut world.bodies[1..] {
                body.mass *= scale;
                body.inertia *= scale;
            }
        }
    }
}

/// The body's geoms (those of its mass group) combined about their centre of mass.
fn from_geoms(world: &World, b: usize) -> (f64, Vector3<f64>, Matrix3<f64>) {
    let geoms = world.geoms.iter().filter(|g| g.body == b && g.mass > 0.0);
    let mut m = 0.0;
    let mut c = Vector3::zeros();
    for g in geoms.clone() {
        m += g.mass;
        c += g.mass * g.mesh_mass.map_or(g.pos, |(at, _)| at);
    }
    if m <= 0.0 {
        return (0.0, Vector3::zeros(), Matrix3::zeros());
    }
    c /= m;
    let mut i = Matrix3::zeros();
    for g in geoms {
        let at = match g.mesh_mass {
            Some((at, own)) => {
                i += own;
                at
            }
            None => {
                let r = g.quat.to_rotation_matrix().into_inner();
                i += r * Matrix3::from_diagonal(&Vector3::from(g.inertia)) * r.transpose();
                g.pos
            }
        };
        let d = at - c;
        i += g.mass * (Matrix3::identity() * d.dot(&d) - d * d.transpose());
    }
    (m, c, i)
}

/// `boundmass`, `boundinertia` (on the principal moments) and `balanceinertia`
/// (principal moments raised to satisfy the triangle inequality).
fn bounds(m: f64, i: Matrix3<f64>, set: &Settings) -> (f64, Matrix3<f64>) {
    let m = m.max(set.boundmass);
    if set.boundinertia <= 0.0 && !set.balanceinertia {
        return (m, i);
    }
    let eig = nalgebra::SymmetricEigen::new(i);
    let mut d = eig.eigenvalues.map(|x| x.max(set.boundinertia));
    if set.balanceinertia && (0..3).any(|k| d[k] > d[(k + 1) % 3] + d[(k + 2) % 3]) {
        d = Vector3::from_element(d.sum() / 3.0);
    }
    let v = eig.eigenvectors;
    (m, v * Matrix3::from_diagonal(&d) * v.transpose())
}
