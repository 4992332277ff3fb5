//! The replay page of an MJCF world (mjcf.md §"What the file becomes": "the
//! replay page draws every geom with its `rgba` or material"): every geom of
//! the file, on the urdyn body that carries its MuJoCo body, in MuJoCo's colour
//! (its `rgba`, else its material's when the geom's is MuJoCo's default grey, as
//! MuJoCo's renderer picks; defaults and classes already folded in by the
//! importer). Spheres, capsules, cylinders, boxes and ellipsoids are drawn as
//! they are; a plane other than the ground (which the page draws) as a thin
//! box of its size (20 m a side where the size is 0: infinite); mesh geoms as
//! their `<asset><mesh>` file (STL, OBJ, read by [`crate::mesh`], scaled by the
//! asset's `scale`, placed by the geom's pose as the file writes it: MuJoCo's
//! compiler moves a mesh geom's frame to the mesh's centre of mass and moves the
//! vertices back, which draws the same), in the geom's colour, simplified to the
//! page's budget as a URDF's meshes are; a mesh whose file cannot be read (or an
//! inline mesh) and height fields as the placeholder box, one warning line each.

use super::{
    Geometry, Visual, VisualShape, MAX_MESH_TRIANGLES, MAX_PAGE_TRIANGLES, PLACEHOLDER_BOX,
    PLACEHOLDER_RGBA,
};
use crate::mesh::load_mesh_colored;
use crate::mjcf::{MjGeomType, World};
use crate::spatial::Se3;
use crate::Model;
use std::collections::HashMap;
use std::path::PathBuf;

/// Half-side (m) drawn for an infinite plane.
const INFINITE_PLANE: f64 = 10.0;

/// Every geom of `world` as the page draws it (`model` the world lowered).
pub fn geometry(model: &Model, world: &World, file: &str) -> Geometry {
    let mut g = Geometry::default();
    let ground = crate::mjcf::ground_of(world);
    let mut placeholders = 0usize;
    let mut mesh_index: HashMap<(PathBuf, [u64; 3]), Option<usize>> = HashMap::new();
    for geom in &world.geoms {
        let body = &world.bodies[geom.body];
        let (ub, at) = if geom.body == 0 {
            (0, Se3::identity())
        } else {
            match model.frames.iter().find(|f| f.name == body.name) {
                Some(f) => (f.body, f.placement),
                None => continue,
            }
        };
        let own = Se3::new(geom.quat.to_rotation_matrix().into_inner(), geom.pos);
        let mut placement = at.compose(&own);
        let s = geom.size;
        let mut rgba = geom.rgba;
        let shape = match geom.kind {
            MjGeomType::Sphere => VisualShape::Sphere { radius: s[0] },
            MjGeomType::Capsule => VisualShape::Capsule {
                radius: s[0],
                length: 2.0 * s[1],
            },
            MjGeomType::Cylinder => VisualShape::Cylinder {
                radius: s[0],
                length: 2.0 * s[1],
            },
            MjGeomType::Box => VisualShape::Box([2.0 * s[0], 2.0 * s[1], 2.0 * s[2]]),
            MjGeomType::Ellipsoid => VisualShape::Ellipsoid { radii: s },
            MjGeomType::Plane => {
                let is_ground = geom.body == 0
                    && ground.as_ref().is_some_and(|gr| {
                        (placement.trans.z - gr.height).abs() < 1e-12
                            && placement.rot[(2, 2)] > 1.0 - 1e-9
                    });
                if is_ground {
                    continue;
                }
                let half = |x: f64| if x > 0.0 { x } else { INFINITE_PLANE };
                // a thin slab below the plane's surface
                let t = 1e-3;
                placement = placement.compose(&Se3::from_translation(nalgebra::Vector3::new(
                    0.0,
                    0.0,
                    -t / 2.0,
                )));
                VisualShape::Box([2.0 * half(s[0]), 2.0 * half(s[1]), t])
            }
            MjGeomType::Mesh => {
                let asset = geom.asset.as_deref().and_then(|a| world.meshes.get(a));
                let k = match asset.and_then(|m| m.file.clone().map(|f| (f, m.scale))) {
                    Some((path, scale)) => {
                        let key = (path.clone(), scale.map(f64::to_bits));
                        *mesh_index.entry(key).or_insert_with(|| {
                            match load_mesh_colored(&path, scale) {
                                Ok((m, _)) => {
                                    // the geom's rgba colours the whole mesh, as MuJoCo draws it
                                    g.meshes.push(m);
                                    g.mesh_colors.push(Vec::new());
                                    Some(g.meshes.len() - 1)
                                }
                                Err(e) => {
                                    g.warnings.push(format!(
                                        "{file}: geom \"{}\": {e}: a placeholder box is drawn",
                                        geom.name
                                    ));
                                    None
                                }
                            }
                        })
                    }
                    None => None,
                };
                match k {
                    Some(k) => VisualShape::Mesh(k),
                    None => {
                        placeholders += 1;
                        rgba = PLACEHOLDER_RGBA;
                        VisualShape::Box([PLACEHOLDER_BOX; 3])
                    }
                }
            }
            MjGeomType::Hfield => {
                placeholders += 1;
                rgba = PLACEHOLDER_RGBA;
                VisualShape::Box([PLACEHOLDER_BOX; 3])
            }
        };
        if rgba[3] <= 0.0 {
            continue;
        }
        g.visuals.push(Visual {
            link: if geom.body == 0 {
                "world".to_string()
            } else {
                body.name.clone()
            },
            body: ub,
            placement,
            shape,
            rgba,
        });
    }
    if placeholders > 0 {
        g.warnings.push(format!(
            "{file}: {placeholders} height-field or unread mesh geom(s) drawn as placeholder boxes"
        ));
    }
    g.simplify_to(MAX_MESH_TRIANGLES, MAX_PAGE_TRIANGLES);
    g
}
