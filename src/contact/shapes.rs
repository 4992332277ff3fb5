//! The parry3d-f64 shape of a collision geometry for pair contact, and the
//! conversions at the boundary between the engine's nalgebra types and parry's
//! glam types (nothing else in the crate sees glam).
//!
//! box → `Cuboid`, sphere → `Ball`, capsule → `Capsule` (z axis), cylinder →
//! `Cylinder` (parry's axis is y: a fixed +90° x-rotation is folded into the
//! shape's offset), a URDF link's mesh → the `ConvexPolyhedron` hull of its
//! vertices (a large one as a [`ClimbHull`]), an obstacle's mesh (`trimesh`) → the `TriMesh` it is, a height
//! field → `HeightField` (parry's grid lies in its x–z plane with heights along
//! y: the same +90° x-rotation maps parry's (x, y, z) to the frame's (x, z, −y),
//! so parry's row i, along +z, is the frame's row from +y: the rows are
//! reversed).

use super::hull::ClimbHull;
use super::ContactError;
use crate::mesh;
use crate::mesh::resolve_mesh_path;
use crate::model::{CollisionGeom, Model, Shape};
use crate::spatial::Se3;
use nalgebra::{Matrix3, Vector3};
use parry3d_f64::math::{Pose, Vector as PVec};
use parry3d_f64::shape::SharedShape;
use std::path::PathBuf;

/// A collision geometry as parry sees it.
#[derive(Clone)]
pub struct PairShape {
    /// The parry shape, in its own frame.
    pub shape: SharedShape,
    /// `geom_M_parry`: parry's frame in the geometry frame.
    pub offset: Se3<f64>,
    /// The centre of the shape's box in parry's frame of it (the broad
    /// phase's world box is this box at the shape's pose, boxed again).
    pub mid: Vector3<f64>,
    /// The half extents of that box.
    pub half: Vector3<f64>,
    /// Whether parry treats it as convex (a support map).
    pub convex: bool,
    /// A sphere's or capsule's axis ends in parry's frame of it (equal for a
    /// sphere) and radius: the closed-form pairs' (`narrow::prim`).
    pub round: Option<(Vector3<f64>, Vector3<f64>, f64)>,
    /// A box's half extents in parry's frame of it (the closed-form
    /// box–box pairs', `narrow::boxes`).
    pub cuboid: Option<Vector3<f64>>,
    /// A cylinder's half height and radius (parry's: axis y; the
    /// closed-form cylinder–box pairs', `narrow::cylinder`).
    pub cylinder: Option<(f64, f64)>,
}

impl PairShape {
    /// A parry shape at `offset` in its geometry frame, with its box in
    /// parry's frame.
    pub(crate) fn new(shape: SharedShape, offset: Se3<f64>, convex: bool) -> Self {
        let b = shape.compute_local_aabb();
        let round = if let Some(s) = shape.as_ball() {
            Some((Vector3::zeros(), Vector3::zeros(), s.radius))
        } else {
            shape
                .as_capsule()
                .map(|c| (from_pvec(c.segment.a), from_pvec(c.segment.b), c.radius))
        };
        let cuboid = shape.as_cuboid().map(|c| from_pvec(c.half_extents));
        let cylinder = shape.as_cylinder().map(|c| (c.half_height, c.radius));
        Self {
            cylinder,
            round,
            cuboid,
            mid: from_pvec(b.center()),
            half: from_pvec(b.half_extents()),
            shape,
            offset,
            convex,
        }
    }
}

impl std::fmt::Debug for PairShape {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PairShape")
            .field("shape", &self.shape.shape_type())
            .field("half", &self.half)
            .finish()
    }
}

/// The rotation of +90° about x (y → z, z → −y).
pub(crate) fn rot_x90() -> Matrix3<f64> {
    Matrix3::new(1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0)
}

/// An engine placement as a parry pose.
pub(crate) fn to_pose(m: &Se3<f64>) -> Pose {
    let r = &m.rot;
    let mat = parry3d_f64::math::Mat3::from_cols_array(&[
        r[(0, 0)],
        r[(1, 0)],
        r[(2, 0)],
        r[(0, 1)],
        r[(1, 1)],
        r[(2, 1)],
        r[(0, 2)],
        r[(1, 2)],
        r[(2, 2)],
    ]);
    let q = parry3d_f64::math::Rot3::from_mat3(&mat).normalize();
    Pose::from_parts(PVec::new(m.trans.x, m.trans.y, m.trans.z), q)
}

/// An engine vector as a parry vector.
#[inline]
pub(crate) fn to_pvec(v: &Vector3<f64>) -> PVec {
    PVec::new(v.x, v.y, v.z)
}

/// A parry vector as an engine vector.
#[inline]
pub(crate) fn from_pvec(v: PVec) -> Vector3<f64> {
    Vector3::new(v.x, v.y, v.z)
}

/// The vertices of a link's collision mesh (resolved, read, scaled).
pub(crate) fn mesh_vertices(
    g: &CollisionGeom,
    filename: &str,
    scale: [f64; 3],
    model: &Model,
    package_paths: &[PathBuf],
) -> Result<mesh::TriMesh, ContactError> {
    let path =
        resolve_mesh_path(filename, model.source.as_deref(), package_paths).ok_or_else(|| {
            ContactError::MissingMesh {
                link: g.link.clone(),
                file: filename.to_string(),
            }
        })?;
    let wrap = |source| ContactError::Mesh {
        link: g.link.clone(),
        source,
    };
    if g.trimesh {
        mesh::load_mesh(&path, scale).map_err(wrap)
    } else {
        Ok(mesh::TriMesh {
            vertices: mesh::load_vertices(&path, scale).map_err(wrap)?,
            triangles: Vec::new(),
        })
    }
}

/// The parry shape of `g`'s mesh file and whether it is convex: its
/// triangles (an obstacle's `trimesh`) or the convex hull of its vertices;
/// `None` for a flat or empty hull.
fn mesh_shape(
    g: &CollisionGeom,
    filename: &str,
    scale: [f64; 3],
    model: &Model,
    package_paths: &[PathBuf],
) -> Result<Option<(SharedShape, bool)>, ContactError> {
    let m = mesh_vertices(g, filename, scale, model, package_paths)?;
    let pv: Vec<PVec> = m
        .vertices
        .iter()
        .map(|p| PVec::new(p.x, p.y, p.z))
        .collect();
    if g.trimesh && !m.triangles.is_empty() {
        match SharedShape::trimesh(pv, m.triangles) {
            Ok(s) => Ok(Some((s, false))),
            Err(e) => Err(ContactError::Mesh {
                link: g.link.clone(),
                source: mesh::MeshError {
                    file: filename.to_string(),
                    message: format!("not a usable triangle mesh: {e}"),
                },
            }),
        }
    } else {
        // a large hull climbs its vertex graph for its support points
        Ok(match ClimbHull::of_points(&pv) {
            Some(Ok(h)) => Some((SharedShape::new(h), true)),
            Some(Err(h)) => Some((SharedShape::new(h), true)),
            None => None,
        })
    }
}

/// The parry shape of `g`; `None` for a shape that cannot collide (a flat or
/// empty mesh: the ground path still handles its points).
pub(crate) fn pair_shape(
    g: &CollisionGeom,
    model: &Model,
    package_paths: &[PathBuf],
) -> Result<Option<PairShape>, ContactError> {
    let bad = |kind| ContactError::BadSize {
        link: g.link.clone(),
        kind,
    };
    let pos = |x: f64| x.is_finite() && x >= 0.0;
    let id = Se3::identity();
    let (shape, offset, convex) = match &g.shape {
        Shape::Box { size } => {
            if !size.iter().all(|&s| pos(s)) {
                return Err(bad("box"));
            }
            (
                SharedShape::cuboid(size[0] / 2.0, size[1] / 2.0, size[2] / 2.0),
                id,
                true,
            )
        }
        Shape::Sphere { radius } => {
            if !pos(*radius) {
                return Err(bad("sphere"));
            }
            (SharedShape::ball(*radius), id, true)
        }
        Shape::Capsule { radius, length } => {
            if !pos(*radius) || !pos(*length) {
                return Err(bad("capsule"));
            }
            (SharedShape::capsule_z(length / 2.0, *radius), id, true)
        }
        Shape::Cylinder { radius, length } => {
            if !pos(*radius) || !pos(*length) {
                return Err(bad("cylinder"));
            }
            (
                SharedShape::cylinder(length / 2.0, *radius),
                Se3::from_rotation(rot_x90()),
                true,
            )
        }
        Shape::Mesh { filename, scale } => {
            // made once a file (`mesh::cache`): a second simulation of the
            // same model reads and hulls nothing
            let path = resolve_mesh_path(filename, model.source.as_deref(), package_paths)
                .ok_or_else(|| ContactError::MissingMesh {
                    link: g.link.clone(),
                    file: filename.to_string(),
                })?;
            let kind = if g.trimesh {
                "pair-trimesh"
            } else {
                "pair-hull"
            };
            let made = mesh::cache::cached(kind, &path, *scale, || {
                mesh_shape(g, filename, *scale, model, package_paths)
            })?;
            match &*made {
                Some((s, convex)) => (s.clone(), id, *convex),
                None => return Ok(None),
            }
        }
        Shape::HeightField { heights, size } => {
            let rows = heights.len();
            let cols = heights.first().map_or(0, Vec::len);
            let finite = heights.iter().flatten().all(|h| h.is_finite());
            if rows < 2
                || cols < 2
                || heights.iter().any(|r| r.len() != cols)
                || !finite
                || !size.iter().all(|&s| s.is_finite() && s > 0.0)
            {
                return Err(bad("heightfield"));
            }
            // parry: column-major (rows along its z = the frame's −y), so its
            // row i is the frame's row rows − 1 − i
            let mut data = Vec::with_capacity(rows * cols);
            for j in 0..cols {
                for i in 0..rows {
                    data.push(heights[rows - 1 - i][j]);
                }
            }
            let a = parry3d_f64::utils::Array2::new(rows, cols, data);
            (
                SharedShape::heightfield(a, PVec::new(size[0], 1.0, size[1])),
                Se3::from_rotation(rot_x90()),
                false,
            )
        }
    };
    Ok(Some(PairShape::new(shape, offset, convex)))
}
