//! The drawn geometry of a URDF's links: visuals (collision geometry where a
//! link has none), meshes read and simplified for the page.

use super::{visuals, LoopMark, ViewError, MAX_MESH_TRIANGLES, MAX_PAGE_TRIANGLES};
use crate::mesh::{load_mesh_colored, Rgba, TriMesh};
use crate::model::Shape;
use crate::spatial::Se3;
use crate::Model;
use nalgebra::{Matrix3, Vector3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// The shape of a visual, as the page draws it.
#[derive(Clone, Debug, PartialEq)]
pub enum VisualShape {
    /// Index into [`Geometry::meshes`].
    Mesh(usize),
    /// Full extents along x, y, z.
    Box([f64; 3]),
    /// Along z, centred.
    Cylinder {
        /// Radius (m).
        radius: f64,
        /// Length (m).
        length: f64,
    },
    /// A cylinder with hemispherical caps, along z, centred.
    Capsule {
        /// Radius (m).
        radius: f64,
        /// Length of the cylindrical part (m).
        length: f64,
    },
    /// Centred sphere.
    Sphere {
        /// Radius (m).
        radius: f64,
    },
    /// Centred ellipsoid (an MJCF geom).
    Ellipsoid {
        /// Semi-axes along x, y, z (m).
        radii: [f64; 3],
    },
}

/// One drawn piece of a link: its shape, its placement on its body and its colour.
#[derive(Clone, Debug, PartialEq)]
pub struct Visual {
    /// The URDF link it belongs to.
    pub link: String,
    /// The body that carries it (index into the model's bodies; 0 is the world).
    pub body: usize,
    /// `body_M_visual`.
    pub placement: Se3,
    /// What is drawn.
    pub shape: VisualShape,
    /// Red, green, blue, alpha in 0..1.
    pub rgba: [f64; 4],
}

/// The robot's drawn geometry: distinct meshes (simplified) and the visuals that
/// place them and the primitive shapes.
#[derive(Clone, Debug, Default)]
pub struct Geometry {
    /// Distinct (file, scale) meshes, simplified where they were too large.
    pub meshes: Vec<TriMesh>,
    /// Per mesh, the colour of each triangle where its file gives one (DAE
    /// materials; empty or `None` where it does not: the visual's colour).
    pub mesh_colors: Vec<Vec<Option<Rgba>>>,
    /// How many of `meshes` were simplified.
    pub simplified: usize,
    /// Every drawn piece.
    pub visuals: Vec<Visual>,
    /// Visual elements left out (malformed), one line each, naming the URDF and link.
    pub warnings: Vec<String>,
    /// The loop constraints drawn (mechanisms.md): a line between each
    /// `point`/`frame` constraint's two anchor points.
    pub loops: Vec<LoopMark>,
}

/// The colour of a visual without a material, and of collision geometry.
pub(crate) const DEFAULT_RGBA: [f64; 4] = [0.72, 0.74, 0.78, 1.0];
/// The side (m) of the box drawn for a link whose visual mesh is missing and
/// that has no collision geometry.
pub const PLACEHOLDER_BOX: f64 = 0.05;
/// The colour of that box (a translucent red: "something is missing here").
pub(crate) const PLACEHOLDER_RGBA: [f64; 4] = [0.9, 0.25, 0.2, 0.6];

impl Geometry {
    /// Reads the URDF's visual geometry (its collision geometry for a link
    /// without visuals) and every mesh it names. A visual mesh file that is not
    /// found is a warning (naming the URDF, the link and the file), and the link
    /// is drawn as its collision geometry, or as a [`PLACEHOLDER_BOX`] without any;
    /// a collision mesh drawn that is not found, or a mesh that cannot be read, is
    /// an error naming the URDF, the link and the mesh file.
    pub fn load(model: &Model, urdf: &Path, package_paths: &[PathBuf]) -> Result<Self, ViewError> {
        Self::load_prefixed(model, urdf, "", package_paths)
    }

    /// As [`Geometry::load`] for the URDF of one model of a scene, whose links
    /// are `PREFIX` + the URDF's link name in `model`.
    pub fn load_prefixed(
        model: &Model,
        urdf: &Path,
        prefix: &str,
        package_paths: &[PathBuf],
    ) -> Result<Self, ViewError> {
        let name = urdf.display().to_string();
        let text = std::fs::read_to_string(urdf)
            .map_err(|e| ViewError::Geometry(format!("{name}: cannot read: {e}")))?;
        let drawables =
            visuals::read(&text).map_err(|e| ViewError::Geometry(format!("{name}: {e}")))?;
        let mut geometry = Geometry {
            warnings: drawables
                .warnings
                .iter()
                .map(|w| format!("{name}: {w}"))
                .collect(),
            ..Geometry::default()
        };
        let mut mesh_index: HashMap<(PathBuf, [u64; 3]), usize> = HashMap::new();
        let resolve =
            |filename: &str| crate::contact::resolve_mesh_path(filename, Some(urdf), package_paths);
        for link in &drawables.links {
            let Some(frame) = model
                .frame_index(&format!("{prefix}{}", link.name))
                .and_then(|k| model.frames.get(k))
            else {
                continue;
            };
            // The pieces drawn: the visuals whose files exist; for any that is
            // missing, the collision geometry (once) or a placeholder box.
            let mut drawn: Vec<(&str, &visuals::Piece)> = Vec::new();
            let mut missing = Vec::new();
            if link.visuals.is_empty() {
                drawn.extend(link.collisions.iter().map(|p| ("collision", p)));
            } else {
                for piece in &link.visuals {
                    match &piece.shape {
                        Shape::Mesh { filename, .. } if resolve(filename).is_none() => {
                            missing.push(filename.as_str());
                        }
                        _ => drawn.push(("visual", piece)),
                    }
                }
            }
            if !missing.is_empty() {
                let instead = if link.collisions.is_empty() {
                    "a placeholder box is drawn"
                } else {
                    "its collision geometry is drawn"
                };
                for filename in &missing {
                    geometry.warnings.push(format!(
                        "{name}: link \"{}\": <visual> mesh file \"{filename}\" not found \
                         (a package:// path needs --package-path DIR): {instead}",
                        link.name
                    ));
                }
                drawn.extend(link.collisions.iter().map(|p| ("collision", p)));
            }
            let placeholder =
                (!missing.is_empty() && link.collisions.is_empty()).then(|| visuals::Piece {
                    rot: Matrix3::identity(),
                    xyz: Vector3::zeros(),
                    shape: Shape::Box {
                        size: [PLACEHOLDER_BOX; 3],
                    },
                    material: None,
                    color: Some(PLACEHOLDER_RGBA),
                });
            drawn.extend(placeholder.iter().map(|p| ("visual", p)));
            for (element, piece) in drawn {
                let at = || format!("{name}: link \"{}\": <{element}>", link.name);
                let placement = frame.placement.compose(&Se3::new(piece.rot, piece.xyz));
                let shape = match &piece.shape {
                    Shape::Box { size } => VisualShape::Box(*size),
                    &Shape::Cylinder { radius, length } => VisualShape::Cylinder { radius, length },
                    &Shape::Capsule { radius, length } => VisualShape::Capsule { radius, length },
                    &Shape::Sphere { radius } => VisualShape::Sphere { radius },
                    Shape::Mesh { filename, scale } => {
                        let path = resolve(filename).ok_or_else(|| {
                            ViewError::Geometry(format!(
                                "{}: mesh file \"{filename}\" not found (a package:// path needs --package-path DIR)",
                                at()
                            ))
                        })?;
                        let key = (path.clone(), scale.map(f64::to_bits));
                        let k = match mesh_index.get(&key) {
                            Some(&k) => k,
                            None => {
                                let (m, colors) = load_mesh_colored(&path, *scale)
                                    .map_err(|e| ViewError::Geometry(format!("{}: {e}", at())))?;
                                geometry.meshes.push(m);
                                geometry.mesh_colors.push(colors);
                                mesh_index.insert(key, geometry.meshes.len() - 1);
                                geometry.meshes.len() - 1
                            }
                        };
                        VisualShape::Mesh(k)
                    }
                    // a URDF has none (a scene's terrain is drawn by the scene's page)
                    Shape::HeightField { .. } => continue,
                };
                let rgba = piece
                    .color
                    .or_else(|| {
                        piece
                            .material
                            .as_ref()
                            .and_then(|m| drawables.materials.get(m).copied())
                    })
                    .map(|c| c.map(|x| x.clamp(0.0, 1.0)))
                    .unwrap_or(DEFAULT_RGBA);
                geometry.visuals.push(Visual {
                    link: format!("{prefix}{}", link.name),
                    body: frame.body,
                    placement,
                    shape,
                    rgba,
                });
            }
        }
        geometry.simplify_to(MAX_MESH_TRIANGLES, MAX_PAGE_TRIANGLES);
        Ok(geometry)
    }

    /// Simplifies the meshes so that none has more than `per_mesh` triangles and
    /// all of them together at most `total`: every mesh is kept whole up to a
    /// common limit L (the largest with Σ min(nᵢ, L) ≤ total, at most
    /// `per_mesh`), larger ones are simplified to L.
    pub fn simplify_to(&mut self, per_mesh: usize, total: usize) {
        let limit = triangle_limit(
            &self
                .meshes
                .iter()
                .map(|m| m.triangles.len())
                .collect::<Vec<_>>(),
            per_mesh,
            total,
        );
        self.mesh_colors.resize(self.meshes.len(), Vec::new());
        for (m, colors) in self.meshes.iter_mut().zip(self.mesh_colors.iter_mut()) {
            if m.triangles.len() > limit {
                let (s, kept) = simplify_keeping(m, limit);
                if !colors.is_empty() {
                    *colors = kept
                        .iter()
                        .map(|&k| colors.get(k).copied().flatten())
                        .collect();
                }
                *m = s;
                self.simplified += 1;
            }
        }
    }
}

/// The largest L ≤ `per_mesh` with Σ min(nᵢ, L) ≤ `total` for triangle counts
/// `counts` (water filling; at least 12, a box's worth, for a tiny `total`).
pub(crate) fn triangle_limit(counts: &[usize], per_mesh: usize, total: usize) -> usize {
    let mut sorted: Vec<usize> = counts.iter().map(|&n| n.min(per_mesh)).collect();
    sorted.sort_unstable();
    if sorted.iter().sum::<usize>() <= total {
        return per_mesh;
    }
    // meshes below the level keep their count; the level is shared by the rest
    let mut left = total;
    for (k, &n) in sorted.iter().enumerate() {
        let rest = sorted.len() - k;
        if n * rest > left {
            return (left / rest).max(12);
        }
        left -= n;
    }
    per_mesh
}

/// The mesh's bounding box (lower corner, upper corner).
pub(crate) fn bounds(m: &TriMesh) -> (Vector3<f64>, Vector3<f64>) {
    let mut lo = Vector3::repeat(f64::INFINITY);
    let mut hi = Vector3::repeat(f64::NEG_INFINITY);
    for v in &m.vertices {
        lo = lo.inf(v);
        hi = hi.sup(v);
    }
    if m.vertices.is_empty() {
        (Vector3::zeros(), Vector3::zeros())
    } else {
        (lo, hi)
    }
}

/// Vertex clustering: the mesh on ever coarser grids until it has at most
/// `max_triangles` triangles (each cell's vertices merged into their mean,
/// collapsed and repeated triangles dropped).
pub fn simplify(m: &TriMesh, max_triangles: usize) -> TriMesh {
    simplify_keeping(m, max_triangles).0
}

/// [`simplify`], and for each triangle of the result the index of the input
/// triangle it comes from.
pub fn simplify_keeping(m: &TriMesh, max_triangles: usize) -> (TriMesh, Vec<usize>) {
    let (lo, hi) = bounds(m);
    let size = (hi - lo).max();
    if m.triangles.len() <= max_triangles || size <= 0.0 {
        return (m.clone(), (0..m.triangles.len()).collect());
    }
    let mut cells = (max_triangles as f64).sqrt() * 1.5;
    loop {
        let out = cluster(m, lo, size / cells);
        if out.0.triangles.len() <= max_triangles || cells < 2.0 {
            return out;
        }
        cells *= 0.8;
    }
}

/// One vertex-clustering pass with cubic cells of side `h` from `lo`: the mesh
/// and the input triangle each output triangle comes from.
fn cluster(m: &TriMesh, lo: Vector3<f64>, h: f64) -> (TriMesh, Vec<usize>) {
    let mut cell_of: HashMap<[i64; 3], u32> = HashMap::new();
    let mut sums: Vec<(Vector3<f64>, f64)> = Vec::new();
    let remap: Vec<u32> = m
        .vertices
        .iter()
        .map(|v| {
            let c = ((v - lo) / h).map(|x| x.floor() as i64);
            let next = sums.len() as u32;
            let k = *cell_of.entry([c.x, c.y, c.z]).or_insert(next);
            if k == next {
                sums.push((Vector3::zeros(), 0.0));
            }
            if let Some(s) = sums.get_mut(k as usize) {
                s.0 += v;
                s.1 += 1.0;
            }
            k
        })
        .collect();
    let mut seen = std::collections::HashSet::new();
    let mut triangles = Vec::new();
    let mut kept = Vec::new();
    for (k, t) in m.triangles.iter().enumerate() {
        let [a, b, c] = t.map(|i| remap.get(i as usize).copied().unwrap_or(0));
        if a == b || b == c || a == c {
            continue;
        }
        let mut key = [a, b, c];
        key.sort_unstable();
        if seen.insert(key) {
            triangles.push([a, b, c]);
            kept.push(k);
        }
    }
    let mesh = TriMesh {
        vertices: sums.into_iter().map(|(s, n)| s / n).collect(),
        triangles,
    };
    (mesh, kept)
}
