//! Building the ground path's shapes from the model's collision geometry.

use super::super::hull::compressed_graph;
use super::super::shapes::rot_x90;
use super::super::{ContactError, ContactParams, ContactPoint, NO_GEOM};
use super::reduce::reduce_directions;
use super::{GroundContact, GroundShape, Manifold, ParryShape};
use crate::contact::resolve_mesh_path;
use crate::mesh;
use crate::model::{Model, Shape};
use crate::spatial::Se3;
use nalgebra::Vector3;
use parry3d_f64::math::Vector as PVec;
use parry3d_f64::shape::{Ball, Capsule, ConvexPolyhedron, Cuboid, Cylinder};
use std::path::{Path, PathBuf};

/// Hulls with more vertices than this are searched on their vertex graph
/// instead of scanned whole.
const GRAPH_SEARCH_MIN: usize = 24;

const CYL_SAMPLES: usize = 6;

/// The compressed adjacency of a hull's vertex graph from its edges.
fn hull_adjacency(h: &ConvexPolyhedron) -> (Vec<u32>, Vec<u32>) {
    compressed_graph(
        h.points().len(),
        h.edges().iter().map(|e| (e.vertices[0], e.vertices[1])),
    )
}

/// What the ground path makes of a mesh file: the convex hull of its
/// vertices (a flat mesh: the vertices themselves) and, for a large hull,
/// its vertex graph.
struct GroundMesh {
    shape: ParryShape,
    verts: Vec<Vector3<f64>>,
    graph: (Vec<u32>, Vec<u32>),
}

/// Reads the mesh at `path` scaled by `scale` and makes its [`GroundMesh`].
fn ground_mesh(path: &Path, scale: [f64; 3]) -> Result<GroundMesh, mesh::MeshError> {
    let pts = mesh::load_vertices(path, scale)?;
    let pv: Vec<PVec> = pts.iter().map(|p| PVec::new(p.x, p.y, p.z)).collect();
    Ok(match ConvexPolyhedron::from_convex_hull(&pv) {
        Some(h) => {
            let verts: Vec<_> = h
                .points()
                .iter()
                .map(|p| Vector3::new(p.x, p.y, p.z))
                .collect();
            let graph = if verts.len() > GRAPH_SEARCH_MIN {
                hull_adjacency(&h)
            } else {
                (Vec::new(), Vec::new())
            };
            GroundMesh {
                shape: ParryShape::Hull(h),
                verts,
                graph,
            }
        }
        None => {
            let mut verts = pts;
            verts.dedup();
            GroundMesh {
                shape: ParryShape::Points,
                verts,
                graph: (Vec::new(), Vec::new()),
            }
        }
    })
}

impl GroundContact {
    /// Builds the contact shapes of `model` (meshes are read here). Returns `None`
    /// when no moving link has collision geometry: such a scene does no contact work.
    pub fn build(
        model: &Model,
        ground: f64,
        params: ContactParams,
        package_paths: &[PathBuf],
    ) -> Result<Option<Self>, ContactError> {
        let mut shapes = Vec::new();
        for (gi, g) in model.collisions.iter().enumerate() {
            if g.body == 0 {
                continue; // welded to the world
            }
            let link = g.link.clone();
            let bad = |kind| ContactError::BadSize {
                link: link.clone(),
                kind,
            };
            let pos = |x: f64| x.is_finite() && x >= 0.0;
            let mut graph = (Vec::new(), Vec::new());
            let (shape, manifold, verts, parry_offset) = match &g.shape {
                Shape::Box { size } => {
                    if !size.iter().all(|&s| pos(s)) {
                        return Err(bad("box"));
                    }
                    let h = Vector3::new(size[0] / 2.0, size[1] / 2.0, size[2] / 2.0);
                    let mut v = Vec::with_capacity(8);
                    for k in 0..8 {
                        let sx = if k & 1 == 0 { -1.0 } else { 1.0 };
                        let sy = if k & 2 == 0 { -1.0 } else { 1.0 };
                        let sz = if k & 4 == 0 { -1.0 } else { 1.0 };
                        v.push(Vector3::new(sx * h.x, sy * h.y, sz * h.z));
                    }
                    (
                        ParryShape::Cuboid(Cuboid::new(PVec::new(h.x, h.y, h.z))),
                        Manifold::Vertices,
                        v,
                        Se3::identity(),
                    )
                }
                Shape::Sphere { radius } => {
                    if !pos(*radius) {
                        return Err(bad("sphere"));
                    }
                    (
                        ParryShape::Ball(Ball::new(*radius)),
                        Manifold::Sphere(*radius),
                        Vec::new(),
                        Se3::identity(),
                    )
                }
                Shape::Capsule { radius, length } => {
                    if !pos(*radius) || !pos(*length) {
                        return Err(bad("capsule"));
                    }
                    (
                        ParryShape::Capsule(Capsule::new_z(length / 2.0, *radius)),
                        Manifold::Capsule {
                            half: length / 2.0,
                            radius: *radius,
                        },
                        Vec::new(),
                        Se3::identity(),
                    )
                }
                Shape::Cylinder { radius, length } => {
                    if !pos(*radius) || !pos(*length) {
                        return Err(bad("cylinder"));
                    }
                    let half = length / 2.0;
                    let mut v = Vec::with_capacity(2 * CYL_SAMPLES);
                    for s in [-1.0, 1.0] {
                        for k in 0..CYL_SAMPLES {
                            let a = std::f64::consts::TAU * (k as f64) / (CYL_SAMPLES as f64);
                            v.push(Vector3::new(radius * a.cos(), radius * a.sin(), s * half));
                        }
                    }
                    (
                        ParryShape::Cylinder(Cylinder::new(half, *radius)),
                        Manifold::Cylinder {
                            half,
                            radius: *radius,
                        },
                        v,
                        Se3::from_rotation(rot_x90()),
                    )
                }
                Shape::Mesh { filename, scale } => {
                    let path = resolve_mesh_path(filename, model.source.as_deref(), package_paths)
                        .ok_or_else(|| ContactError::MissingMesh {
                            link: link.clone(),
                            file: filename.clone(),
                        })?;
                    // the hull of the file's vertices, made once a file (`mesh::cache`)
                    let made = mesh::cache::cached("ground-hull", &path, *scale, || {
                        ground_mesh(&path, *scale)
                    })
                    .map_err(|source| ContactError::Mesh {
                        link: link.clone(),
                        source,
                    })?;
                    graph = made.graph.clone();
                    (
                        made.shape.clone(),
                        Manifold::Vertices,
                        made.verts.clone(),
                        Se3::identity(),
                    )
                }
                // (a scene's terrain is welded to the world: never a moving link's)
                Shape::HeightField { .. } => continue,
            };
            let nslots = match manifold {
                Manifold::Vertices => verts.len(),
                Manifold::Sphere(_) => 1,
                Manifold::Capsule { .. } => 2,
                Manifold::Cylinder { .. } => 2 + verts.len(),
            };
            let bound = match manifold {
                Manifold::Vertices => verts.iter().map(|v| v.norm()).fold(0.0, f64::max),
                Manifold::Sphere(r) => r,
                Manifold::Capsule { half, radius } => half + radius,
                Manifold::Cylinder { half, radius } => half.hypot(radius),
            };
            // a vertex shape's box in the body frame
            let low_box = (manifold == Manifold::Vertices && !verts.is_empty()).then(|| {
                let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
                for v in &verts {
                    let p = g.placement.act_point(v);
                    for a in 0..3 {
                        lo[a] = lo[a].min(p[a]);
                        hi[a] = hi[a].max(p[a]);
                    }
                }
                let c = [0, 1, 2].map(|a| (lo[a] + hi[a]) / 2.0);
                let e = [0, 1, 2].map(|a| (hi[a] - lo[a]) / 2.0);
                (c, e)
            });
            shapes.push(GroundShape {
                body: g.body,
                geom: gi,
                template: ContactPoint {
                    shape: 0,
                    slot: 0,
                    body: g.body,
                    point: Vector3::zeros(),
                    gap: 0.0,
                    geom: gi,
                    other: 0,
                    other_geom: NO_GEOM,
                    normal: Vector3::z(),
                    friction: g.friction.max(params.friction),
                    fresh: false,
                    key: 0,
                },
                link,
                placement: g.placement,
                at_body: g.placement.rot == nalgebra::Matrix3::identity()
                    && g.placement.trans == Vector3::zeros(),
                parry_offset,
                shape,
                manifold,
                verts,
                adj_start: graph.0,
                adj: graph.1,
                nslots,
                bound,
                low_box,
            });
        }
        if shapes.is_empty() {
            return Ok(None);
        }
        let mut slot_offset = Vec::with_capacity(shapes.len());
        let mut n = 0;
        for s in &shapes {
            slot_offset.push(n);
            n += s.nslots;
        }
        let cap = shapes.iter().map(|s| s.nslots).max().unwrap_or(0);
        let nshapes = shapes.len();
        let hulls = shapes
            .iter()
            .any(|s| s.manifold == super::Manifold::Vertices && !s.adj.is_empty());
        Ok(Some(Self {
            cull: shapes.iter().map(super::Cull::of).collect(),
            shapes: shapes.into(),
            ground,
            params,
            queries: 0,
            slot_offset,
            nslots: n,
            scratch: Vec::with_capacity(cap),
            prev_flag: vec![false; n],
            prev_list: Vec::with_capacity(n),
            prev_range: vec![(0, 0, 0); nshapes],
            picks: vec![usize::MAX; nshapes],
            reduce_dirs: reduce_directions(params.max_points_per_shape),
            last_low: vec![0; nshapes],
            visited: vec![0; n],
            generation: 0,
            in_band: vec![0; n],
            band_place: vec![0; n],
            band_pts: super::patch::Soa::zeros(cap),
            band_xyz: super::patch::Soa::zeros(n),
            rim_xyz: super::patch::Soa::zeros(n),
            band_order: vec![0; n],
            band_len: vec![0; nshapes],
            rim_len: vec![0; nshapes],
            band_gen: vec![0; nshapes],
            stack: Vec::with_capacity(n),
            anchor: vec![[f64::NAN; 4]; nshapes],
            travel: super::Travel::new(&params, vec![false; nshapes]),
            hulls,
            parts: Vec::new(),
            reached: Vec::with_capacity(nshapes),
        }))
    }
}
