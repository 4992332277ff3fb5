//! Mesh files, read in a room of their own below the importers (URDF, MJCF,
//! scenes) and contact: their paths resolved without ROS ([`resolve_mesh_path`]),
//! their vertices (a contact shape is their convex hull), their triangles (a
//! mesh obstacle, mass properties) and, for drawing, their colours. This room
//! names no other module of the crate (tests/layering.rs).
//!
//! - STL (ASCII or binary) through `stl_io`;
//! - Wavefront OBJ through `tobj` (every object's `v` positions);
//! - COLLADA (`.dae`) through a minimal reader. The vertices are the
//!   `<float_array>` of the `<source>` that a geometry's
//!   `<vertices><input semantic="POSITION">` names, those of them that the
//!   geometry's `<triangles>`, `<polylist>` and `<polygons>` index (the whole
//!   array for a geometry without such primitives or whose primitives index
//!   nothing; assimp, which coal and Pinocchio use, also drops positions that
//!   nothing indexes: see docs/meshes.md), placed by the scene graph: the visual
//!   scene `<scene><instance_visual_scene url>` names (else the first one) is
//!   walked, each `<node>`'s transform elements (`<matrix>`, row-major;
//!   `<translate>`; `<rotate>`, axis and angle in degrees; `<scale>`) are
//!   multiplied in document order onto its parent's transform, and every
//!   `<instance_geometry>` (and `<instance_node>` of a node in the file) emits
//!   its geometry's positions in that transform — a geometry placed twice
//!   appears twice. The result is scaled by the document's `<asset><unit meter>`.
//!   `<up_axis>` is ignored, as ROS tools do (so does coal's loader, which
//!   Pinocchio uses). A `<skew>` or
//!   `<lookat>` above a placed geometry is an error; `<instance_controller>`
//!   (skinned meshes) places nothing. A document whose scene places no geometry
//!   (or that has no scene) gives every POSITION array, untransformed.
//!
//!   For drawing, [`load_mesh_colored`] also gives each DAE triangle the diffuse
//!   `<color>` of its material: the primitive's `material` symbol, bound by the
//!   placing `<instance_geometry>`'s `<instance_material symbol target>` (else
//!   taken as a material id), the material's `<instance_effect>`, the effect's
//!   `<diffuse><color>` (none for a `<texture>`).

use nalgebra::Vector3;
use std::path::Path;

/// Why a mesh could not be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}: {message}")]
pub struct MeshError {
    /// The mesh file.
    pub file: String,
    /// What is wrong with it.
    pub message: String,
}

fn err(path: &Path, message: impl Into<String>) -> MeshError {
    MeshError {
        file: path.display().to_string(),
        message: message.into(),
    }
}

/// A triangle mesh as a mesh file gives it: vertex positions (in the file's
/// units times the scale asked for) and triangles as indices into them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions.
    pub vertices: Vec<Vector3<f64>>,
    /// Triangles, three indices into `vertices` each (polygons fan-triangulated).
    pub triangles: Vec<[u32; 3]>,
}

/// The vertex positions of a mesh file, in the file's units times `scale`.
/// Non-finite coordinates are an error; an empty mesh is an error.
pub fn load_vertices(path: &Path, scale: [f64; 3]) -> Result<Vec<Vector3<f64>>, MeshError> {
    let (raw, _, _) = read_raw(path, false)?;
    scaled(path, raw, scale)
}

/// The vertices and triangles of a mesh file (STL, OBJ, DAE as [`load_vertices`]
/// reads them: the same vertices, DAE nodes placed alike), in the file's units
/// times `scale`. DAE triangles come from `<triangles>`, `<polylist>` and
/// `<polygons>` (fan-triangulated), OBJ faces are triangulated; an index outside
/// the vertices is an error, and so is a mesh without vertices.
pub fn load_mesh(path: &Path, scale: [f64; 3]) -> Result<TriMesh, MeshError> {
    load_mesh_colored(path, scale).map(|(m, _)| m)
}

/// A triangle's colour as its mesh file gives it: red, green, blue, alpha in 0..1.
pub type Rgba = [f64; 4];

/// [`load_mesh`] and each triangle's colour where the file gives one (a DAE
/// material's diffuse colour, see the module doc; `None` for STL and OBJ, and for
/// DAE triangles without a material colour). The colours are as many as the
/// triangles.
pub fn load_mesh_colored(
    path: &Path,
    scale: [f64; 3],
) -> Result<(TriMesh, Vec<Option<Rgba>>), MeshError> {
    let (raw, triangles, mut colors) = read_raw(path, true)?;
    colors.resize(triangles.len(), None);
    let n = raw.len();
    if let Some(t) = triangles
        .iter()
        .find(|t| t.iter().any(|&i| i as usize >= n))
    {
        return Err(err(
            path,
            format!("a triangle {t:?} indexes past the {n} vertices"),
        ));
    }
    Ok((
        TriMesh {
            vertices: scaled(path, raw, scale)?,
            triangles,
        },
        colors,
    ))
}

/// Scales raw positions, refusing an empty mesh and non-finite vertices.
fn scaled(
    path: &Path,
    raw: Vec<[f64; 3]>,
    scale: [f64; 3],
) -> Result<Vec<Vector3<f64>>, MeshError> {
    if raw.is_empty() {
        return Err(err(path, "the mesh has no vertices"));
    }
    let mut out = Vec::with_capacity(raw.len());
    for p in raw {
        let v = Vector3::new(p[0] * scale[0], p[1] * scale[1], p[2] * scale[2]);
        if !v.iter().all(|x| x.is_finite()) {
            return Err(err(path, "the mesh has a non-finite vertex"));
        }
        out.push(v);
    }
    Ok(out)
}

/// Raw positions, triangles and triangle colours.
type RawMesh = (Vec<[f64; 3]>, Vec<[u32; 3]>, Vec<Option<Rgba>>);

/// Raw positions of a mesh file and, when `with_triangles`, its triangles and
/// their colours (DAE only; empty otherwise).
fn read_raw(path: &Path, with_triangles: bool) -> Result<RawMesh, MeshError> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let mut triangles = Vec::new();
    let mut colors = Vec::new();
    let raw: Vec<[f64; 3]> = match ext.as_str() {
        "stl" => {
            let mut f =
                std::fs::File::open(path).map_err(|e| err(path, format!("cannot read: {e}")))?;
            let mesh = stl_io::read_stl(&mut f)
                .map_err(|e| err(path, format!("not a valid STL file: {e}")))?;
            if with_triangles {
                for face in &mesh.faces {
                    let [a, b, c] = face.vertices;
                    let idx =
                        |i: usize| u32::try_from(i).map_err(|_| err(path, "too many vertices"));
                    triangles.push([idx(a)?, idx(b)?, idx(c)?]);
                }
            }
            mesh.vertices
                .iter()
                .map(|v| [v.0[0] as f64, v.0[1] as f64, v.0[2] as f64])
                .collect()
        }
        "obj" => {
            let opts = tobj::LoadOptions {
                triangulate: with_triangles,
                ..tobj::LoadOptions::default()
            };
            let (models, _) = tobj::load_obj(path, &opts)
                .map_err(|e| err(path, format!("not a valid OBJ file: {e}")))?;
            let mut out = Vec::new();
            for m in &models {
                let base = u32::try_from(out.len()).map_err(|_| err(path, "too many vertices"))?;
                if with_triangles {
                    for t in m.mesh.indices.chunks_exact(3) {
                        if let &[a, b, c] = t {
                            triangles.push([base + a, base + b, base + c]);
                        }
                    }
                }
                for c in m.mesh.positions.chunks_exact(3) {
                    out.push([c[0] as f64, c[1] as f64, c[2] as f64]);
                }
            }
            out
        }
        "dae" => {
            let bytes = std::fs::read(path).map_err(|e| err(path, format!("cannot read: {e}")))?;
            let text = String::from_utf8_lossy(&bytes);
            let dae = read_dae_colored(&text).map_err(|m| err(path, m))?;
            if with_triangles {
                triangles = dae.triangles;
                colors = dae.colors;
            }
            dae.positions
        }
        other => {
            return Err(err(
                path,
                format!("unsupported mesh format \"{other}\" (STL, OBJ and DAE are read)"),
            ))
        }
    };
    Ok((raw, triangles, colors))
}

pub(crate) mod cache;
mod inertia;
pub use inertia::{mass_properties, MeshInertia, MeshMass};
pub(crate) mod dae;
mod paths;
pub use paths::resolve_mesh_path;
mod dae_parts;
use dae::read_dae_colored;
